//! Scenes built in code: the file format's own definitions (`scene::format`), filled by an
//! application instead of parsed from JSON, then validated by the loader itself, so a built scene
//! and a loaded one are the same `Scene`, with the same errors naming object and field.

use super::check::Ctx;
use super::error::{SceneError, quoted};
use super::format::*;
use super::load;
use super::types::{Scene, Texture};
use std::path::PathBuf;

/// Builds a [`Scene`] from definitions given in code. Names play the role they play in a file:
/// materials are referred to by name, and errors name the object (`materials.gold.diffuse`).
///
/// ```
/// use illum::scene::{SceneBuilder, format::*};
/// let mut b = SceneBuilder::new(CameraDef::look_at([0.0, 1.0, 4.0], [0.0; 3], 40.0, [64, 48]));
/// b.material("red", MaterialDef { diffuse: [0.8, 0.1, 0.1], ..Default::default() })
///     .shape("ball", ShapeDef::sphere([0.0; 3], 1.0, "red"))
///     .light("sky", LightDef::dome([0.3, 0.4, 0.5]));
/// let scene = b.build().unwrap();
/// assert_eq!(scene.shapes.len(), 1);
/// ```
pub struct SceneBuilder {
    file: SceneFile,
    /// Names errors ("<scene builder>" unless set).
    origin: String,
    /// Base of relative texture and glTF paths.
    base_dir: PathBuf,
    /// The first repeated name, reported by `build`.
    duplicate: Option<SceneError>,
}

impl SceneBuilder {
    pub fn new(camera: CameraDef) -> SceneBuilder {
        SceneBuilder {
            file: SceneFile {
                _schema: None,
                description: None,
                camera,
                textures: NamedMap::default(),
                materials: NamedMap::default(),
                shapes: NamedMap::default(),
                lights: NamedMap::default(),
                integrator: None,
            },
            origin: "<scene builder>".into(),
            base_dir: PathBuf::from("."),
            duplicate: None,
        }
    }

    /// The name errors give instead of a file name.
    pub fn origin(&mut self, origin: &str) -> &mut Self {
        self.origin = origin.to_owned();
        self
    }

    /// The directory relative file paths (textures, glTF) are resolved against.
    pub fn base_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Self {
        self.base_dir = dir.into();
        self
    }

    pub fn camera(&mut self, camera: CameraDef) -> &mut Self {
        self.file.camera = camera;
        self
    }

    pub fn description(&mut self, text: &str) -> &mut Self {
        self.file.description = Some(text.to_owned());
        self
    }

    fn insert<T>(
        map: &mut NamedMap<T>,
        dup: &mut Option<SceneError>,
        origin: &str,
        section: &str,
        name: &str,
        def: T,
    ) {
        if map.0.contains_key(name) {
            dup.get_or_insert_with(|| {
                SceneError::invalid(
                    origin,
                    format!("{section}.{name}"),
                    quoted(name),
                    "duplicate name",
                )
            });
        } else {
            map.0.insert(name.to_owned(), def);
        }
    }

    /// A texture read from a file, as in a scene file.
    pub fn texture(&mut self, name: &str, def: TextureDef) -> &mut Self {
        let o = &self.origin;
        Self::insert(
            &mut self.file.textures,
            &mut self.duplicate,
            o,
            "textures",
            name,
            def,
        );
        self
    }

    /// A texture from host memory: width × height RGBA texels (row-major, top row first),
    /// linear, or sRGB-encoded in RGB when `srgb` (decoded as image files are).
    pub fn texture_pixels(
        &mut self,
        name: &str,
        width: u32,
        height: u32,
        rgba: &[f32],
        srgb: bool,
    ) -> &mut Self {
        let def = TextureDef {
            file: String::new(),
            srgb: Some(srgb),
            filter: FilterDef::default(),
            wrap: WrapDef::default(),
            pixels: Some(HostPixels {
                width,
                height,
                rgba: rgba.to_vec(),
            }),
            bytes: None,
            mirror_u: false,
        };
        self.texture(name, def)
    }

    pub fn material(&mut self, name: &str, def: MaterialDef) -> &mut Self {
        let o = &self.origin;
        Self::insert(
            &mut self.file.materials,
            &mut self.duplicate,
            o,
            "materials",
            name,
            def,
        );
        self
    }

    pub fn shape(&mut self, name: &str, def: ShapeDef) -> &mut Self {
        let o = &self.origin;
        Self::insert(
            &mut self.file.shapes,
            &mut self.duplicate,
            o,
            "shapes",
            name,
            def,
        );
        self
    }

    /// A triangle mesh from host slices (object space), placed by `transform`.
    pub fn mesh(
        &mut self,
        name: &str,
        material: &str,
        positions: &[[f32; 3]],
        indices: &[u32],
        transform: Option<TransformDef>,
    ) -> &mut Self {
        let mesh = MeshDef {
            positions: positions.iter().map(|p| p.map(f64::from)).collect(),
            indices: Some(indices.to_vec()),
            ..Default::default()
        };
        self.shape(
            name,
            ShapeDef {
                mesh: Some(mesh),
                material: Some(material.to_owned()),
                transform,
                ..Default::default()
            },
        )
    }

    pub fn light(&mut self, name: &str, def: LightDef) -> &mut Self {
        let o = &self.origin;
        Self::insert(
            &mut self.file.lights,
            &mut self.duplicate,
            o,
            "lights",
            name,
            def,
        );
        self
    }

    /// Validates the definitions as the loader validates a file's.
    pub fn build(&self) -> Result<Scene, SceneError> {
        if let Some(e) = &self.duplicate {
            return Err(e.clone());
        }
        load::build(&self.file, &self.origin, &self.base_dir)
    }
}

/// A texture handed over in host memory, checked as a decoded image file is.
pub(crate) fn host_texture(
    ctx: Ctx,
    name: &str,
    srgb: Option<bool>,
    p: &HostPixels,
) -> Result<Texture, SceneError> {
    let field = format!("textures.{name}.pixels");
    let want = u64::from(p.width) * u64::from(p.height) * 4;
    if p.width == 0 || p.height == 0 || want != p.rgba.len() as u64 {
        return Err(ctx.err(
            field,
            format!("{} values for {}x{}", p.rgba.len(), p.width, p.height),
            "must hold width x height RGBA values (width, height > 0)",
        ));
    }
    if let Some(i) = p.rgba.iter().position(|v| !v.is_finite()) {
        let px = i / 4;
        return Err(ctx.err(
            field,
            p.rgba[i],
            &format!(
                "pixel ({}, {}) must be finite",
                px % p.width as usize,
                px / p.width as usize
            ),
        ));
    }
    let texels = p
        .rgba
        .chunks_exact(4)
        .map(|t| {
            let c = |v: f32| {
                if srgb == Some(true) {
                    super::texture::srgb_to_linear(v)
                } else {
                    v
                }
            };
            glam::Vec4::new(c(t[0]), c(t[1]), c(t[2]), t[3])
        })
        .collect();
    Ok(Texture::new(name, p.width, p.height, texels))
}

impl CameraDef {
    /// The look-at camera of a scene file.
    pub fn look_at(position: V3, look_at: V3, fov_y: f64, resolution: [u32; 2]) -> CameraDef {
        CameraDef {
            position: Some(position),
            look_at: Some(look_at),
            up: None,
            fov_y: Some(fov_y),
            gltf: None,
            index: None,
            resolution,
        }
    }
}

impl Default for MaterialDef {
    fn default() -> Self {
        MaterialDef {
            diffuse: default_diffuse(),
            diffuse_texture: None,
            specular: Vec::new(),
            emission: [0.0; 3],
            emission_texture: None,
            two_sided: false,
            tangent: None,
            metallic_roughness: None,
        }
    }
}

impl ShapeDef {
    pub fn sphere(center: V3, radius: f64, material: &str) -> ShapeDef {
        ShapeDef {
            sphere: Some(SphereDef { center, radius }),
            material: Some(material.to_owned()),
            ..Default::default()
        }
    }

    pub fn rect(center: V3, normal: V3, size: V2, material: &str) -> ShapeDef {
        ShapeDef {
            rect: Some(RectDef {
                center,
                normal,
                size,
                up: None,
            }),
            material: Some(material.to_owned()),
            ..Default::default()
        }
    }
}

impl Default for LightDef {
    fn default() -> Self {
        LightDef {
            rect: None,
            disk: None,
            sphere: None,
            dome: None,
            sun: None,
            color: default_color(),
            intensity: default_intensity(),
            exposure: 0.0,
            two_sided: false,
            texture: None,
            visible: default_visible(),
            shadows: None,
        }
    }
}

impl LightDef {
    /// A constant dome of radiance `color`.
    pub fn dome(color: V3) -> LightDef {
        LightDef {
            dome: Some(DomeDef::default()),
            color,
            ..Default::default()
        }
    }

    /// A rectangular area light.
    pub fn rect(center: V3, normal: V3, size: V2, intensity: f64) -> LightDef {
        LightDef {
            rect: Some(RectDef {
                center,
                normal,
                size,
                up: None,
            }),
            intensity,
            ..Default::default()
        }
    }
}
