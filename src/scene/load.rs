//! Scene file → validated `Scene`: parsing with field-path tracking, then one pass over the
//! file's sections in dependency order (textures, materials, shapes, lights, camera).

use super::check::Ctx;
use super::error::{
    MAX_ASSET_FILE_BYTES, MAX_SCENE_FILE_BYTES, SceneError, fmt_num, fmt_vec, io_message, quoted,
    read_capped,
};
use super::format::{
    DomeConventionDef, FilterDef, FresnelDef, LightDef, LobeDef, MaterialDef, MeshDef, ModelDef,
    NumOrArray, SceneFile, ShapeDef, TextureDef, WrapDef,
};
use super::gltf::{self as gltf_load, GltfCamera};
use super::texture::{self, ImageKind};
use super::transform;
use super::types::*;

mod light;
mod material;
mod shape;
use glam::{DMat4, Vec2, Vec3};
use indexmap::IndexMap;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

type Result<T> = std::result::Result<T, SceneError>;

/// Everything of a `Scene` but its camera, filled section by section.
#[derive(Default)]
pub(crate) struct Parts {
    pub textures: Vec<Texture>,
    pub materials: Vec<Material>,
    pub meshes: Vec<Mesh>,
    pub instances: Vec<MeshInstance>,
    pub shapes: Vec<AnalyticShape>,
    pub lights: Vec<Light>,
}

pub(crate) fn parse(text: &str, origin: &str) -> Result<SceneFile> {
    // Editors on Windows may start UTF-8 files with a byte-order mark; JSON does not allow one.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    check_shape(text, origin)?;
    let mut de = serde_json::Deserializer::from_str(text);
    let file: SceneFile = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| SceneError::from_json(origin, e.path().to_string(), e.inner()))?;
    de.end()
        .map_err(|e| SceneError::from_json(origin, String::new(), &e))?;
    Ok(file)
}

/// What serde's derived structs let through although the format forbids it: a top-level array
/// (derived structs also accept their fields in order) and `null` for an optional field.
fn check_shape(text: &str, origin: &str) -> Result<()> {
    // Malformed JSON is left to the typed parse, which reports line, column and field.
    let Ok(value) = serde_json::from_str::<serde_json::Value>(text) else {
        return Ok(());
    };
    if !value.is_object() {
        return Err(SceneError::unsupported(
            origin,
            "top level",
            format!(
                "a scene file is one JSON object ({{\"camera\": ..., \"shapes\": ...}}), got {}",
                json_kind(&value)
            ),
        ));
    }
    fn find_null(v: &serde_json::Value, path: &mut String) -> bool {
        let len = path.len();
        let found = match v {
            serde_json::Value::Null => return true,
            serde_json::Value::Object(m) => m.iter().any(|(k, v)| {
                path.truncate(len);
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
                find_null(v, path)
            }),
            serde_json::Value::Array(a) => a.iter().enumerate().any(|(i, v)| {
                path.truncate(len);
                path.push_str(&format!("[{i}]"));
                find_null(v, path)
            }),
            _ => false,
        };
        if !found {
            path.truncate(len);
        }
        found
    }
    let mut path = String::new();
    if find_null(&value, &mut path) {
        return Err(SceneError::invalid(
            origin,
            path,
            "null",
            "not part of the scene format (leave the field out to get its default)",
        ));
    }
    Ok(())
}

fn json_kind(v: &serde_json::Value) -> &'static str {
    match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

pub(crate) fn build(file: &SceneFile, origin: &str, base_dir: &Path) -> Result<Scene> {
    let ctx = Ctx { file: origin };
    if file.shapes.0.is_empty() && file.lights.0.is_empty() {
        return Err(ctx.err(
            "shapes",
            "none",
            "a scene needs at least one shape or light",
        ));
    }
    let mut b = Builder {
        ctx,
        base_dir,
        parts: Parts::default(),
        texture_ids: IndexMap::new(),
        material_ids: IndexMap::new(),
        gltf_cameras: HashMap::new(),
        mesh_ids: HashMap::new(),
    };
    for (name, def) in &file.textures.0 {
        let tex = b.texture(name, def)?;
        b.texture_ids
            .insert(name.clone(), b.parts.textures.len() as TextureId);
        b.parts.textures.push(tex);
    }
    for (name, def) in &file.materials.0 {
        let mat = b.material(name, def)?;
        b.material_ids
            .insert(name.clone(), b.parts.materials.len() as MaterialId);
        b.parts.materials.push(mat);
    }
    for (name, def) in &file.shapes.0 {
        b.shape(name, def)?;
    }
    let (mut dome, mut sun) = (None, None);
    for (name, def) in &file.lights.0 {
        let light = b.light(name, def)?;
        let slot = match light.kind {
            LightKind::Dome { .. } => Some((&mut dome, "dome")),
            LightKind::Sun { .. } => Some((&mut sun, "sun")),
            _ => None,
        };
        if let Some((slot, kind)) = slot {
            if let Some(first) = slot.replace(name.clone()) {
                return Err(SceneError::unsupported(
                    origin,
                    format!("lights.{name}.{kind}"),
                    format!("a scene has at most one {kind} light, and \"{first}\" is one already"),
                ));
            }
        }
        b.parts.lights.push(light);
    }
    let camera = b.camera(&file.camera, file)?;
    let p = b.parts;
    Ok(Scene {
        camera,
        materials: p.materials,
        textures: p.textures,
        meshes: p.meshes,
        instances: p.instances,
        shapes: p.shapes,
        lights: p.lights,
        description: file.description.clone(),
        source: None,
        integrator: match &file.integrator {
            Some(d) => integrator_choice(origin, d)?,
            None => IntegratorChoice::default(),
        },
        warnings: Vec::new(),
        inputs: Vec::new(),
    })
}

/// The files a scene file names (besides itself): its glTF files and images, packaged images
/// left out, each once.
fn inputs(file: &SceneFile, base_dir: &Path, scene_file: &Path) -> Vec<PathBuf> {
    let mut v = vec![scene_file.to_path_buf()];
    let named = file
        .shapes
        .0
        .values()
        .filter_map(|s| s.gltf.as_ref().map(|g| g.file.as_str()))
        .chain(file.camera.gltf.as_deref())
        .chain(
            file.textures
                .0
                .values()
                .filter(|t| t.bytes.is_none() && t.pixels.is_none())
                .map(|t| t.file.as_str()),
        );
    for f in named {
        let p = base_dir.join(f);
        if !v.contains(&p) {
            v.push(p);
        }
    }
    v
}

/// The integrator section as text; the integrator it names reads (and checks) the values.
fn integrator_choice(origin: &str, d: &super::format::IntegratorDef) -> Result<IntegratorChoice> {
    let mut params = Vec::new();
    for (name, v) in &d.params {
        let text = match v {
            serde_json::Value::Bool(b) => b.to_string(),
            serde_json::Value::Number(n) => n.to_string(),
            serde_json::Value::String(s) => s.clone(),
            _ => {
                return Err(SceneError::invalid(
                    origin,
                    format!("integrator.{name}"),
                    v,
                    "an integrator parameter is a number, a boolean or a string",
                ));
            }
        };
        params.push((name.clone(), text));
    }
    Ok(IntegratorChoice {
        name: d.kind.clone(),
        params,
    })
}

pub(crate) struct Builder<'a> {
    pub ctx: Ctx<'a>,
    pub base_dir: &'a Path,
    pub parts: Parts,
    pub texture_ids: IndexMap<String, TextureId>,
    pub material_ids: IndexMap<String, MaterialId>,
    /// Cameras of each glTF shape, by shape name.
    pub gltf_cameras: HashMap<String, Vec<GltfCamera>>,
    /// The mesh of each mesh shape, by shape name (what `instance` shapes place again).
    pub mesh_ids: HashMap<String, u32>,
}

/// "exactly one of" check for shapes and lights; returns the key given.
fn one_of(ctx: Ctx, field: &str, keys: &[(&'static str, bool)]) -> Result<&'static str> {
    let given: Vec<&str> = keys.iter().filter(|k| k.1).map(|k| k.0).collect();
    if given.len() == 1 {
        return Ok(given[0]);
    }
    let all: Vec<String> = keys.iter().map(|k| quoted(k.0)).collect();
    let got = if given.is_empty() {
        "none".to_owned()
    } else {
        given
            .iter()
            .map(|k| quoted(k))
            .collect::<Vec<_>>()
            .join(", ")
    };
    Err(ctx.err(
        field,
        got,
        &format!("must have exactly one of {}", all.join(", ")),
    ))
}

pub(crate) fn known(names: impl Iterator<Item = impl AsRef<str>>) -> String {
    let list: Vec<String> = names.map(|n| quoted(n.as_ref())).collect();
    if list.is_empty() {
        "none are defined".to_owned()
    } else {
        format!("known: {}", list.join(", "))
    }
}

impl Builder<'_> {
    fn texture_ref(&self, field: &str, name: &str) -> Result<TextureId> {
        self.texture_ids.get(name).copied().ok_or_else(|| {
            self.ctx.err(
                field,
                quoted(name),
                &format!("no such texture ({})", known(self.texture_ids.keys())),
            )
        })
    }

    fn material_ref(&self, field: &str, name: &str) -> Result<MaterialId> {
        self.material_ids.get(name).copied().ok_or_else(|| {
            self.ctx.err(
                field,
                quoted(name),
                &format!("no such material ({})", known(self.material_ids.keys())),
            )
        })
    }

    fn texture(&self, name: &str, def: &TextureDef) -> Result<Texture> {
        if let Some(p) = &def.pixels {
            return super::builder::host_texture(self.ctx, name, def.srgb, p)
                .map(|t| self.sampled(t, def));
        }
        let field = format!("textures.{name}.file");
        // A packaged image is named `package.usdz[inner.png]`.
        let kind = ImageKind::from_path(def.file.trim_end_matches(']')).ok_or_else(|| {
            self.ctx.err(
                &field,
                quoted(&def.file),
                "unsupported image format (expected .png, .jpg, .jpeg, .exr or .hdr)",
            )
        })?;
        let path = self.base_dir.join(&def.file);
        // The first bytes first: a huge file that is no image fails before it is read whole.
        let head = match &def.bytes {
            Some(b) => b[..b.len().min(16)].to_vec(),
            None => read_head(&path)
                .map_err(|e| SceneError::file_read(self.ctx.file, &field, &def.file, &e))?,
        };
        match ImageKind::sniff(&head) {
            Some(k) if k == kind => {}
            found => {
                let what = found.map_or("no image file of a known kind".to_string(), |k| {
                    format!("{k:?} data, not what its name says")
                });
                return Err(self.ctx.err(
                    &field,
                    quoted(&def.file),
                    &format!("its first bytes are {what} (PNG, JPEG, OpenEXR or Radiance HDR)"),
                ));
            }
        }
        let bytes = match &def.bytes {
            Some(b) => std::borrow::Cow::Borrowed(b.as_slice()),
            None => std::borrow::Cow::Owned(
                read_capped(&path, MAX_ASSET_FILE_BYTES)
                    .map_err(|e| SceneError::file_read(self.ctx.file, &field, &def.file, &e))?,
            ),
        };
        let srgb = def.srgb.unwrap_or(kind.srgb_by_default());
        let t = texture::decode(name, &bytes, kind, srgb)
            .map_err(|m| SceneError::decode(self.ctx.file, &field, &def.file, m))?;
        Ok(self.sampled(t, def))
    }

    /// The filter and wrap modes of `def` (and its mirroring).
    fn sampled(&self, mut t: Texture, def: &TextureDef) -> Texture {
        if def.mirror_u {
            for row in t.texels.chunks_exact_mut(t.width as usize) {
                row.reverse();
            }
        }
        t.filter = match def.filter {
            FilterDef::Bilinear => TextureFilter::Bilinear,
            FilterDef::Nearest => TextureFilter::Nearest,
        };
        t.wrap = [match def.wrap {
            WrapDef::Repeat => TextureWrap::Repeat,
            WrapDef::Clamp => TextureWrap::Clamp,
            WrapDef::Mirror => TextureWrap::Mirror,
        }; 2];
        t
    }
}

/// Reads a scene file; its directory is the base for relative paths.
pub(crate) fn load_file(path: &Path) -> Result<Scene> {
    let origin = path.display().to_string();
    if super::usd::is_usd(path) {
        let (file, warnings, layers) = super::usd::load(path)?;
        // Asset paths come resolved (absolute); anything relative is the stage's folder's.
        let base = path.parent().unwrap_or(Path::new(""));
        let mut scene = build(&file, &origin, base)?;
        scene.source = Some(path.to_path_buf());
        scene.warnings = warnings;
        scene.inputs = inputs(&file, base, path);
        for layer in layers {
            let same = |p: &PathBuf| p == &layer || same_file(p, &layer);
            if !scene.inputs.iter().any(same) {
                scene.inputs.push(layer);
            }
        }
        return Ok(scene);
    }
    let io = |e: std::io::Error| SceneError::Io {
        file: origin.clone(),
        message: io_message(&e),
    };
    let bytes = read_capped(path, MAX_SCENE_FILE_BYTES).map_err(io)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {}); scene files are UTF-8 JSON",
                e.utf8_error().valid_up_to()
            ),
        ))
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let file = parse(&text, &origin)?;
    let mut scene = build(&file, &origin, base)?;
    scene.source = Some(path.to_path_buf());
    scene.inputs = inputs(&file, base, path);
    Ok(scene)
}

/// Whether two paths name one file (a layer's resolved path and the path the stage was
/// opened by).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// The first 16 bytes of a file (fewer if it is shorter).
fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut head = Vec::with_capacity(16);
    std::fs::File::open(path)?.take(16).read_to_end(&mut head)?;
    Ok(head)
}
