//! The validated, renderer-facing scene: what `scene::load` produces and the GPU side consumes.
//!
//! Conventions (shared with pbrt-v4 and Mitsuba 3, see docs/scene-format.md):
//! right-handed, +Y up, linear RGB, radiance in W·m⁻²·sr⁻¹, lengths in scene units (metres
//! suggested), angles in degrees in the file and radians nowhere here unless named `_rad`.
//! World-space positions and transforms are kept in f64 so that the uploader can make them
//! camera-relative before converting to f32 (scenes far from the origin stay precise).

use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// A whole scene, validated: every index is in range, every number finite.
#[derive(Clone, Debug)]
pub struct Scene {
    pub camera: Camera,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// Triangle meshes in object space; one per glTF primitive or inline mesh.
    pub meshes: Vec<Mesh>,
    /// Placements of meshes in the world.
    pub instances: Vec<MeshInstance>,
    /// Analytic shapes (traced exactly, not tessellated), in world space.
    pub shapes: Vec<AnalyticShape>,
    pub lights: Vec<Light>,
    /// The file's free-text `description`, if any.
    pub description: Option<String>,
    /// The scene file it came from (None for the embedded default scene).
    pub source: Option<PathBuf>,
    /// The file's `integrator` section: defaults that the command line overrides.
    pub integrator: IntegratorChoice,
    /// What the file holds that illum does not render, each naming where it is (a USD stage's
    /// prim and attribute); `illum render` prints them and `--strict` refuses the scene.
    pub warnings: Vec<String>,
    /// The files read to build it: the scene file, glTF files and images (a USD stage's own
    /// layers are the stage file only), for a watcher that reloads it on an edit.
    pub inputs: Vec<PathBuf>,
}

/// A scene's integrator defaults: the integrator's name (None: the renderer's default) and its
/// parameters as text, which the integrator reads (`crate::integrators`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntegratorChoice {
    pub name: Option<String>,
    /// (name, value) in the file's order of names (sorted).
    pub params: Vec<(String, String)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    /// Full vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// Overrides the resolution. Given one of the two, the other follows the camera's aspect
    /// ratio (rounded, at least 1); given both, the image takes both (the vertical field of view
    /// stays, so the horizontal one changes with the aspect).
    pub fn set_resolution(
        &mut self,
        width: Option<u32>,
        height: Option<u32>,
    ) -> Result<(), String> {
        if width == Some(0) || height == Some(0) {
            return Err("--width and --height must be at least 1".into());
        }
        let (w0, h0) = (f64::from(self.width), f64::from(self.height));
        let follow = |size: u32, ratio: f64| ((f64::from(size) * ratio).round() as u32).max(1);
        (self.width, self.height) = match (width, height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, follow(w, h0 / w0)),
            (None, Some(h)) => (follow(h, w0 / h0), h),
            (None, None) => return Ok(()),
        };
        Ok(())
    }
}

/// Index into `Scene::textures`.
pub type TextureId = u32;
/// Index into `Scene::materials`.
pub type MaterialId = u32;

/// An image used by materials or lights, decoded to linear RGBA.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first, linear RGBA (sRGB-encoded sources are decoded on load).
    pub texels: Vec<Vec4>,
    pub filter: TextureFilter,
    /// How texel indices outside the image map back into it, along u and along v.
    pub wrap: [TextureWrap; 2],
}

/// Reconstruction of a texture between texel centres ((i + 1/2) / size in uv).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureFilter {
    /// The four nearest texels, weighted bilinearly (Mitsuba's and pbrt's default).
    #[default]
    Bilinear,
    /// The texel that contains the point: crisp texels.
    Nearest,
}

/// Texel indices outside [0, size): Mitsuba 3's `wrap_mode` semantics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureWrap {
    /// Periodic: index mod size.
    #[default]
    Repeat,
    /// The edge texel continues outward.
    Clamp,
    /// Reflected at each edge, the edge texel repeated (…, 1, 0, 0, 1, …, n−1, n−1, n−2, …).
    Mirror,
}

impl TextureWrap {
    /// The texel index that `i` reads along an axis of `n` texels.
    pub fn index(self, i: i64, n: i64) -> i64 {
        match self {
            TextureWrap::Repeat => i.rem_euclid(n),
            TextureWrap::Clamp => i.clamp(0, n - 1),
            TextureWrap::Mirror => {
                let p = i.rem_euclid(2 * n);
                if p < n { p } else { 2 * n - 1 - p }
            }
        }
    }
}

impl Texture {
    /// A texture with the default sampling (bilinear, repeating).
    pub fn new(name: impl Into<String>, width: u32, height: u32, texels: Vec<Vec4>) -> Texture {
        Texture {
            name: name.into(),
            width,
            height,
            texels,
            filter: TextureFilter::default(),
            wrap: [TextureWrap::default(); 2],
        }
    }

    /// Texel (i, j) after wrapping, as RGBA.
    pub fn texel(&self, i: i64, j: i64) -> Vec4 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (i, j) = (self.wrap[0].index(i, w), self.wrap[1].index(j, h));
        self.texels[(j * w + i) as usize]
    }

    /// The texture at `uv` ((0, 0) the top-left corner of the image), as the renderer reads it
    /// (`texture_lookup` in glsl/scene/scene.glsl), in f64.
    pub fn lookup(&self, uv: glam::DVec2) -> glam::DVec4 {
        let size = glam::DVec2::new(f64::from(self.width), f64::from(self.height));
        match self.filter {
            TextureFilter::Nearest => {
                let p = (uv * size).floor();
                self.texel(p.x as i64, p.y as i64).as_dvec4()
            }
            TextureFilter::Bilinear => {
                let st = uv * size - 0.5;
                let i0 = st.floor();
                let f = st - i0;
                let (i, j) = (i0.x as i64, i0.y as i64);
                let t = |a: i64, b: i64| self.texel(i + a, j + b).as_dvec4();
                (t(0, 0) * (1.0 - f.x) + t(1, 0) * f.x) * (1.0 - f.y)
                    + (t(0, 1) * (1.0 - f.x) + t(1, 1) * f.x) * f.y
            }
        }
    }
}

/// The microfacet distribution and shadowing model of a specular lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    /// The course's D-BRDF: Beckmann D, f = F D (n.h) / (4 (n.l)(v.h)), no Smith term.
    DBrdf,
    /// Cook-Torrance with Beckmann D and separable Smith G (Mitsuba 3 `roughconductor`).
    BeckmannSmith,
    /// Cook-Torrance with GGX D and Smith G (pbrt-v4 `conductor`, glTF).
    GgxSmith,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// F = color, independent of angle.
    Constant(Vec3),
    /// Schlick's approximation with reflectance at normal incidence `f0`.
    Schlick { f0: Vec3 },
    /// Exact conductor Fresnel with complex IOR eta + i k per channel.
    Conductor { eta: Vec3, k: Vec3 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularLobe {
    pub distribution: Distribution,
    /// Roughness alpha along the tangent and the bitangent (equal when isotropic), in [0, 1]: the
    /// renderer raises it to 1e-4 (Mitsuba 3's floor) unless it is 0 along both axes, a perfect
    /// mirror.
    pub alpha: Vec2,
    pub fresnel: Fresnel,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Lambert albedo in [0, 1]^3.
    pub diffuse: Vec3,
    pub diffuse_texture: Option<TextureId>,
    /// At most two specular lobes (the course's look-dev materials use one or two).
    pub specular: Vec<SpecularLobe>,
    /// Metallic-roughness: multiplies metallic (B) and roughness (G) per texel (glTF's packing).
    pub metallic_roughness_texture: Option<TextureId>,
    /// Metallic-roughness factors (glTF, UsdPreviewSurface, the scene format's
    /// `metallic_roughness`). When present the shader re-derives, per texel, the diffuse albedo
    /// base·(1−metallic), the first lobe's Schlick f0 = mix(dielectric_f0, base, metallic) and its
    /// alpha = max(roughness², 1e-4), with base = base_color × the base-colour texture
    /// (`diffuse_texture`); `diffuse` and `specular[0]` hold the values of an untextured texel.
    pub metallic_roughness: Option<MetallicRoughness>,
    /// Emitted radiance (W·m⁻²·sr⁻¹), zero for non-emitters. Emits on the front side only
    /// (the side the geometric normal points to) unless `two_sided`.
    pub emission: Vec3,
    pub emission_texture: Option<TextureId>,
    pub two_sided: bool,
    /// Material direction for the anisotropic tangent when the mesh has no tangents
    /// (projected onto the tangent plane); None: derived from the normal.
    pub tangent_direction: Option<Vec3>,
}

/// The factors of a metallic-roughness material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    pub base_color: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    /// Schlick f0 where metallic is 0: glTF's 0.04, ((ior − 1)/(ior + 1))² for an ior.
    pub dielectric_f0: f32,
}

impl MetallicRoughness {
    /// The Lambert albedo of an untextured texel: base·(1 − metallic).
    pub fn diffuse(&self) -> Vec3 {
        self.base_color * (1.0 - self.metallic)
    }

    /// The GGX-Smith lobe of an untextured texel: alpha max(roughness², 1e-4), Schlick f0
    /// mix(dielectric_f0, base, metallic), as the shader derives it per texel.
    pub fn lobe(&self) -> SpecularLobe {
        SpecularLobe {
            distribution: Distribution::GgxSmith,
            alpha: Vec2::splat((self.roughness * self.roughness).max(1e-4)),
            fresnel: Fresnel::Schlick {
                f0: Vec3::splat(self.dielectric_f0).lerp(self.base_color, self.metallic),
            },
        }
    }
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (same length as positions) or None for flat shading.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex tangents xyz with handedness w = ±1 (glTF convention), or None.
    pub tangents: Option<Vec<Vec4>>,
    pub uvs: Option<Vec<Vec2>>,
    /// Triangle list, 3 indices per triangle, all < positions.len().
    pub indices: Vec<u32>,
    pub material: MaterialId,
}

#[derive(Clone, Debug)]
pub struct MeshInstance {
    /// Index into `Scene::meshes`.
    pub mesh: u32,
    /// Object to world.
    pub transform: DMat4,
    /// Name of the scene shape (or glTF node) it came from, for messages.
    pub name: String,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ShapeGeometry {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Rectangle with centre and full edge vectors `u`, `v` (orthogonal); its normal is
    /// normalize(u × v); uv (0,0) at center - u/2 - v/2.
    Rect {
        center: DVec3,
        u: DVec3,
        v: DVec3,
    },
    Disk {
        center: DVec3,
        normal: DVec3,
        radius: f64,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct AnalyticShape {
    pub name: String,
    pub geometry: ShapeGeometry,
    pub material: MaterialId,
    /// Spheres: unit axis of the tangent frame, tangent = normalize(pole × (p − center)) (Mitsuba 3
    /// and pbrt-v4's dp/du about their local +Z); None: the material's `tangent`, else +Y.
    pub pole: Option<DVec3>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// Area lights are shaped like the analytic shapes; one-sided toward the normal unless `two_sided`.
    Rect {
        center: DVec3,
        u: DVec3,
        v: DVec3,
    },
    Disk {
        center: DVec3,
        normal: DVec3,
        radius: f64,
    },
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Infinite environment; `texture` is a map laid over the sphere as `convention` says.
    /// `rotation_deg` rotates the map about +Y.
    Dome {
        rotation_deg: f64,
        convention: DomeConvention,
    },
    /// Distant light toward which `direction` points (from the scene to the sun); irradiance at
    /// normal incidence `irradiance` (W·m⁻²) is `color * intensity * 2^exposure`.
    Sun {
        direction: DVec3,
        angular_diameter_deg: f64,
    },
}

/// How a dome's map covers the sphere (docs/scene-format.md, glsl/lights/dome_map.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DomeConvention {
    /// Lat-long: u = atan2(x, −z)/2π + ½ (½ at −Z, growing toward +X), v = θ/π from +Y; texel
    /// centres at ((i + ½)/W, (j + ½)/H); the texture's own filter and wrap modes.
    #[default]
    Illum,
    /// Mitsuba 3's `envmap`: u = atan2(x, −z)/2π (0 at −Z), v = θ/π; column i at (i + ½)/W, row j
    /// at θ = πj/(H − 1); bilinear, periodic in u, clamped in v.
    Mitsuba,
    /// pbrt-v4's `imageinfinite`: the equal-area octahedral square of a square map, pbrt's +Z
    /// being +Y here (pbrt (x, y, z) = illum (x, −z, y)); nearest texel.
    Pbrt,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Radiance (or, for the sun, irradiance) = color * intensity * 2^exposure.
    pub color: Vec3,
    pub intensity: f32,
    pub exposure: f32,
    pub two_sided: bool,
    /// Multiplies the radiance over the light's surface (rect/disk uv, sphere lat-long, dome map).
    pub texture: Option<TextureId>,
    /// Whether camera rays see the light's surface (area lights and dome).
    pub visible: bool,
    /// Whether the light's surface blocks shadow rays and BRDF rays (area lights; an opaque
    /// object by default, as in Mitsuba 3 and pbrt-v4).
    pub shadows: bool,
}

impl Material {
    /// A plain Lambert material of albedo `diffuse`: no specular lobe, no emission.
    pub fn lambert(name: impl Into<String>, diffuse: Vec3) -> Material {
        Material {
            name: name.into(),
            diffuse,
            diffuse_texture: None,
            specular: Vec::new(),
            metallic_roughness_texture: None,
            metallic_roughness: None,
            emission: Vec3::ZERO,
            emission_texture: None,
            two_sided: false,
            tangent_direction: None,
        }
    }
}

impl LightKind {
    /// The surface of an area light, shaped like the analytic shape of its name; None for the
    /// dome and the sun.
    pub fn surface(&self) -> Option<ShapeGeometry> {
        match *self {
            LightKind::Rect { center, u, v } => Some(ShapeGeometry::Rect { center, u, v }),
            LightKind::Disk {
                center,
                normal,
                radius,
            } => Some(ShapeGeometry::Disk {
                center,
                normal,
                radius,
            }),
            LightKind::Sphere { center, radius } => Some(ShapeGeometry::Sphere { center, radius }),
            LightKind::Dome { .. } | LightKind::Sun { .. } => None,
        }
    }
}

impl Light {
    /// color * intensity * 2^exposure.
    pub fn radiance(&self) -> Vec3 {
        self.color * self.intensity * self.exposure.exp2()
    }

    /// Whether the light emits nothing: zero radiance, or an area light whose area is zero in
    /// float32 (the renderer leaves such lights out; a zero area would be a 1/0 pdf).
    pub fn emits_nothing(&self) -> bool {
        let zero_area = match &self.kind {
            LightKind::Rect { u, v, .. } => (u.cross(*v).length() as f32) <= 0.0,
            LightKind::Disk { radius, .. } | LightKind::Sphere { radius, .. } => {
                ((radius * radius) as f32) <= 0.0
            }
            LightKind::Dome { .. } | LightKind::Sun { .. } => false,
        };
        zero_area || self.radiance().max_element() <= 0.0
    }
}
