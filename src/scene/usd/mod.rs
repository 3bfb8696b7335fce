//! USD stages (.usda, .usdc, .usdz) as scenes, read through the `openusd` crate, which composes
//! them (sublayers, references, payloads, variants, inherits, instancing). The composed stage is
//! turned into the scene format's own structures (`format::SceneFile`), which are then built and
//! validated exactly as a JSON scene is; docs/scene-format.md ("USD stages") gives the mapping of
//! each schema. What illum cannot render as authored is an error naming the prim and attribute,
//! or, where the rest of the image stays right, a warning in `Scene::warnings`.

mod camera;
mod geom;
mod instancer;
mod lux;
mod quadric;
mod shade;
mod texture;
mod value;
mod xform;

use super::error::{SceneError, io_message};
use super::format::{CameraDef, FilterDef, NamedMap, SceneFile, TextureDef, WrapDef};
use glam::DMat4;
use openusd::sdf::{self, Value};
use openusd::usd;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

type Result<T> = std::result::Result<T, SceneError>;

/// The file extensions read as USD.
pub(crate) const EXTENSIONS: &[&str] = &["usd", "usda", "usdc", "usdz"];

/// Whether `path` names a USD stage (by its extension).
pub(crate) fn is_usd(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| EXTENSIONS.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// The composed stage being converted, and what it has given so far.
pub(crate) struct Reader {
    stage: usd::Stage,
    /// The stage's file as the user named it, for messages.
    file: String,
    warnings: Vec<String>,
    /// Z-up stages are turned into illum's Y-up frame by a rotation of the whole scene (camera
    /// included), which leaves the image as authored.
    to_y_up: DMat4,
    z_up: bool,
    /// World transforms of the prims visited, by path (parents come before children).
    world: HashMap<sdf::Path, DMat4>,
    /// Prims whose subtree is left out (invisible, guide or proxy purpose, materials, ...).
    pruned: HashSet<sdf::Path>,
    out: SceneFile,
    /// illum material names by (bound material or display colour, two-sided emission).
    materials: HashMap<String, String>,
    /// The shape that holds the mesh of each (prototype prim, material), for instances.
    instanced: HashMap<String, String>,
    /// The texture coordinates each material's textures read; `texcoords` are those of the
    /// material being read.
    texcoord_of: HashMap<String, TexCoords>,
    texcoords: Option<TexCoords>,
    cameras: Vec<sdf::Path>,
    render_settings: Vec<sdf::Path>,
}

/// The texture coordinates a material reads: a mesh primvar (its name after `primvars:`), and
/// the `UsdTransform2d` between it and the textures, if any.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct TexCoords {
    pub primvar: String,
    /// st' = R(rotation) (scale · st) + translation, UsdTransform2d's order.
    pub transform: Option<Transform2d>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Transform2d {
    pub rotation_deg: f64,
    pub scale: [f64; 2],
    pub translation: [f64; 2],
}

impl Transform2d {
    pub fn apply(&self, [s, t]: [f64; 2]) -> [f64; 2] {
        let (sin, cos) = self.rotation_deg.to_radians().sin_cos();
        let (x, y) = (s * self.scale[0], t * self.scale[1]);
        [
            cos * x - sin * y + self.translation[0],
            sin * x + cos * y + self.translation[1],
        ]
    }
}

impl TexCoords {
    /// The primvar st meshes give when no material names one.
    pub fn st() -> TexCoords {
        TexCoords {
            primvar: "st".to_string(),
            transform: None,
        }
    }

    /// illum's uv of a USD st (transformed first): USD's t runs up from the image's bottom.
    pub fn uv(&self, st: [f64; 2]) -> [f64; 2] {
        let [u, v] = self.transform.map_or(st, |t| t.apply(st));
        [u, 1.0 - v]
    }
}

/// Reads the stage at `path` into scene-file structures, with the warnings it gives.
/// A stage read as a scene file: the file, its warnings, and the layer files it composed
/// (sublayers, references, payloads; the root layer first), which a watcher follows.
pub(crate) fn load(path: &Path) -> Result<(SceneFile, Vec<String>, Vec<PathBuf>)> {
    let file = path.display().to_string();
    // openusd's own message for a missing file names no cause; say it as every loader does.
    std::fs::metadata(path).map_err(|e| SceneError::Io {
        file: file.clone(),
        message: io_message(&e),
    })?;
    let Some(p) = path.to_str() else {
        return Err(SceneError::unsupported(
            &file,
            "(stage)",
            "the path is not UTF-8 (openusd opens UTF-8 paths only)",
        ));
    };
    let stage = usd::Stage::open(p).map_err(|e| {
        SceneError::unsupported(&file, "(stage)", format!("cannot open the stage: {e:#}"))
    })?;
    let mut r = Reader {
        stage,
        file,
        warnings: Vec::new(),
        to_y_up: DMat4::IDENTITY,
        z_up: false,
        world: HashMap::new(),
        pruned: HashSet::new(),
        out: SceneFile {
            _schema: None,
            description: None,
            camera: CameraDef {
                position: None,
                look_at: None,
                up: None,
                fov_y: None,
                gltf: None,
                index: None,
                resolution: [0, 0],
            },
            textures: NamedMap::default(),
            materials: NamedMap::default(),
            shapes: NamedMap::default(),
            lights: NamedMap::default(),
            integrator: None,
        },
        materials: HashMap::new(),
        instanced: HashMap::new(),
        texcoord_of: HashMap::new(),
        texcoords: None,
        cameras: Vec::new(),
        render_settings: Vec::new(),
    };
    r.stage_metadata()?;
    r.traverse()?;
    // Prims compose as they are visited: their errors are known after the traversal.
    let mut errors = Vec::new();
    for e in r.stage.composition_errors() {
        match &e {
            // A MaterialX document (pxr reads it with a plugin): its materials are not
            // UsdPreviewSurfaces, which the material reader already says where they are used.
            openusd::pcp::Error::MalformedLayer {
                asset_path,
                site_path,
                ..
            } if asset_path.to_ascii_lowercase().ends_with(".mtlx") => r.warn(
                site_path,
                "",
                format!("@{asset_path}@ is a MaterialX document, which illum does not read"),
            ),
            _ => errors.push(e),
        }
    }
    if let Some(e) = errors.first() {
        return Err(SceneError::unsupported(
            &r.file,
            "(composition)",
            format!(
                "{e}{}",
                match errors.len() {
                    1 => String::new(),
                    n => format!(" (and {} more composition errors)", n - 1),
                }
            ),
        ));
    }
    r.out.camera = r.camera()?;
    // Every layer the traversal reached is loaded by now; packaged and anonymous layers are no
    // files of their own.
    let layers = r
        .stage
        .layer_identifiers()
        .into_iter()
        .map(PathBuf::from)
        .filter(|p| p.is_file())
        .collect();
    Ok((r.out, r.warnings, layers))
}

impl Reader {
    /// `prim.attr` as a field name in messages.
    fn field(prim: &sdf::Path, attr: &str) -> String {
        if attr.is_empty() {
            prim.as_str().to_string()
        } else {
            format!("{}.{attr}", prim.as_str())
        }
    }

    fn invalid(
        &self,
        prim: &sdf::Path,
        attr: &str,
        value: impl ToString,
        reason: &str,
    ) -> SceneError {
        SceneError::Invalid {
            file: self.file.clone(),
            field: Self::field(prim, attr),
            value: value.to_string(),
            reason: reason.to_string(),
        }
    }

    fn unsupported(&self, prim: &sdf::Path, attr: &str, message: impl Into<String>) -> SceneError {
        SceneError::unsupported(&self.file, Self::field(prim, attr), message)
    }

    fn warn(&mut self, prim: &sdf::Path, attr: &str, message: impl AsRef<str>) {
        self.warnings
            .push(format!("{}: {}", Self::field(prim, attr), message.as_ref()));
    }

    /// A library failure reading `prim.attr`, as an error naming them.
    fn read_error(&self, prim: &sdf::Path, attr: &str, e: impl std::fmt::Display) -> SceneError {
        self.unsupported(prim, attr, format!("cannot read: {e}"))
    }

    /// The composed value of `prim.attr`: its default, else (an animated attribute) its first
    /// time sample, with a warning that the stage is rendered at that time.
    fn attr(&mut self, prim: &sdf::Path, attr: &str) -> Result<Option<Value>> {
        let path = prim
            .append_property(attr)
            .map_err(|e| self.read_error(prim, attr, e))?;
        let a = self.stage.attribute(path);
        if let Some(v) = a
            .get::<Value>()
            .map_err(|e| self.read_error(prim, attr, e))?
        {
            return Ok(Some(v));
        }
        let times = a
            .time_sample_times()
            .map_err(|e| self.read_error(prim, attr, e))?;
        let Some(&t) = times.first() else {
            return Ok(None);
        };
        let v = a
            .get_at::<Value>(usd::TimeCode::new(t))
            .map_err(|e| self.read_error(prim, attr, e))?;
        self.warn(
            prim,
            attr,
            format!("animated: rendered at its first time sample ({t})"),
        );
        Ok(v)
    }

    /// A number attribute, or `fallback` when it is not authored.
    fn number(&mut self, prim: &sdf::Path, attr: &str, fallback: f64) -> Result<f64> {
        match self.attr(prim, attr)? {
            None => Ok(fallback),
            Some(v) => match value::scalar(&v) {
                Some(x) if x.is_finite() => Ok(x),
                Some(x) => Err(self.invalid(prim, attr, x, "must be finite")),
                None => Err(self.invalid(prim, attr, value::show(&v), "expected a number")),
            },
        }
    }

    fn color(&mut self, prim: &sdf::Path, attr: &str, fallback: [f64; 3]) -> Result<[f64; 3]> {
        match self.attr(prim, attr)? {
            None => Ok(fallback),
            Some(v) => match value::vec3(&v) {
                Some(c) if c.iter().all(|x| x.is_finite()) => Ok(c),
                Some(c) => Err(self.invalid(prim, attr, format!("{c:?}"), "must be finite")),
                None => Err(self.invalid(prim, attr, value::show(&v), "expected 3 numbers")),
            },
        }
    }

    fn boolean(&mut self, prim: &sdf::Path, attr: &str, fallback: bool) -> Result<bool> {
        match self.attr(prim, attr)? {
            None => Ok(fallback),
            Some(v) => value::boolean(&v)
                .ok_or_else(|| self.invalid(prim, attr, value::show(&v), "expected a bool")),
        }
    }

    fn token(&mut self, prim: &sdf::Path, attr: &str, fallback: &str) -> Result<String> {
        match self.attr(prim, attr)? {
            None => Ok(fallback.to_string()),
            Some(v) => value::token(&v)
                .map(str::to_string)
                .ok_or_else(|| self.invalid(prim, attr, value::show(&v), "expected a token")),
        }
    }

    /// The file an asset-valued `prim.attr` names, and its bytes when it lies inside a USDZ
    /// package (`package.usdz[inner.png]`). A relative path is relative to the layer that
    /// authored it: the strongest layer of the attribute's stack where the file exists
    /// (openusd hands over the path as authored).
    fn asset_file(
        &self,
        prim: &sdf::Path,
        attr: &str,
        a: &sdf::AssetPath,
    ) -> (String, Option<Vec<u8>>) {
        let authored = a.resolved_path().unwrap_or(a.as_str());
        if openusd::ar::is_package_relative_path(authored) {
            return (authored.to_string(), packaged(authored));
        }
        if Path::new(authored).is_absolute() {
            return (authored.to_string(), None);
        }
        let stack = prim
            .append_property(attr)
            .ok()
            .and_then(|p| self.stage.attribute(p).property_stack().ok())
            .unwrap_or_default();
        for (layer, _) in &stack {
            // A layer inside a package: the file is beside it in the package.
            if let Some((package, inner)) = openusd::ar::split_package_relative_path_outer(layer) {
                let dir = Path::new(&inner).parent().unwrap_or(Path::new(""));
                let joined = normalize(&dir.join(authored));
                let path = openusd::ar::join_package_relative_path(&package, &joined);
                if let Some(bytes) = packaged(&path) {
                    return (path, Some(bytes));
                }
                continue;
            }
            let Some(dir) = Path::new(layer).parent() else {
                continue;
            };
            let candidate = dir.join(authored);
            if candidate.is_file() {
                return (candidate.display().to_string(), None);
            }
        }
        // Not found: the strongest layer's reading, for the error that names it.
        let file = match stack.first().and_then(|(l, _)| Path::new(l).parent()) {
            Some(dir) => dir.join(authored).display().to_string(),
            None => authored.to_string(),
        };
        (file, None)
    }

    /// A bilinear texture of the scene (the first of its name stays).
    fn add_texture(
        &mut self,
        name: &str,
        file: String,
        bytes: Option<Vec<u8>>,
        srgb: Option<bool>,
        wrap: WrapDef,
    ) {
        self.out
            .textures
            .0
            .entry(name.to_string())
            .or_insert(TextureDef {
                file,
                srgb,
                filter: FilterDef::Bilinear,
                wrap,
                pixels: None,
                bytes,
                mirror_u: false,
            });
    }

    /// The targets of the relationship `prim.rel`.
    fn targets(&self, prim: &sdf::Path, rel: &str) -> Result<Vec<sdf::Path>> {
        let path = prim
            .append_property(rel)
            .map_err(|e| self.read_error(prim, rel, e))?;
        self.stage
            .relationship(path)
            .targets()
            .map_err(|e| self.read_error(prim, rel, e))
    }

    /// That every index of `prim.attr` is in 0..`len` (`what`: the `len` things indexed).
    fn check_indices(
        &self,
        prim: &sdf::Path,
        attr: &str,
        idx: &[i64],
        len: usize,
        what: &str,
    ) -> Result<()> {
        match idx.iter().find(|&&i| i < 0 || i as usize >= len) {
            Some(i) => Err(self.invalid(
                prim,
                attr,
                i,
                &format!("each index must be in 0..{len} (the number of {what})"),
            )),
            None => Ok(()),
        }
    }

    /// Whether `prim.attr` has an opinion (a default or time samples).
    fn authored(&mut self, prim: &sdf::Path, attr: &str) -> Result<bool> {
        Ok(self.attr(prim, attr)?.is_some())
    }

    /// upAxis (Y or Z) and metersPerUnit (read for the record: radiance is per unit area of
    /// whatever unit the stage is in, so it does not change the image).
    fn stage_metadata(&mut self) -> Result<()> {
        let root = sdf::Path::abs_root();
        let up = self
            .stage
            .stage_metadata("upAxis")
            .map_err(|e| self.read_error(&root, "upAxis", e))?;
        match up.as_ref().and_then(value::token) {
            None | Some("Y") => {}
            Some("Z") => {
                self.z_up = true;
                // +Z up becomes +Y up, +Y becomes -Z: a rotation of -90° about X.
                self.to_y_up = DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2);
            }
            Some(other) => {
                return Err(self.invalid(&root, "upAxis", other, "expected \"Y\" or \"Z\""));
            }
        }
        let mpu = self
            .stage
            .stage_metadata("metersPerUnit")
            .map_err(|e| self.read_error(&root, "metersPerUnit", e))?;
        if let Some(m) = mpu.as_ref().and_then(value::scalar)
            && !(m.is_finite() && m > 0.0)
        {
            return Err(self.invalid(&root, "metersPerUnit", m, "must be a positive number"));
        }
        Ok(())
    }

    /// Visits every active, defined, non-abstract prim (instance proxies included), parents
    /// first, and converts what it holds.
    fn traverse(&mut self) -> Result<()> {
        let mut paths = Vec::new();
        let root = sdf::Path::abs_root();
        self.stage
            .traverse(usd::PrimPredicate::DEFAULT_PROXIES, |p| {
                paths.push(p.clone())
            })
            .map_err(|e| self.read_error(&root, "", e))?;
        for path in paths {
            // A prim is left out with any ancestor that was.
            let mut up = path.parent();
            let mut pruned = false;
            while let Some(p) = up {
                if self.pruned.contains(&p) {
                    pruned = true;
                    break;
                }
                up = p.parent();
            }
            if pruned {
                continue;
            }
            self.prim(&path)?;
        }
        Ok(())
    }

    fn prim(&mut self, path: &sdf::Path) -> Result<()> {
        let prim = self.stage.prim(path.clone());
        let kind = prim
            .type_name()
            .map_err(|e| self.read_error(path, "", e))?
            .map(|t| t.as_str().to_string())
            .unwrap_or_default();
        if matches!(
            kind.as_str(),
            "Material" | "Shader" | "NodeGraph" | "GeomSubset"
        ) {
            // Read through the bindings of the geometry that uses them.
            self.pruned.insert(path.clone());
            return Ok(());
        }
        if self.token(path, "visibility", "inherited")? == "invisible" {
            self.pruned.insert(path.clone());
            return Ok(());
        }
        let purpose = self.token(path, "purpose", "default")?;
        if purpose == "guide" || purpose == "proxy" {
            self.pruned.insert(path.clone());
            return Ok(());
        }
        let draw_mode = self.token(path, "model:drawMode", "inherited")?;
        if !matches!(draw_mode.as_str(), "inherited" | "default") {
            self.warn(
                path,
                "model:drawMode",
                format!("{draw_mode:?} is a viewport mode: the full geometry renders"),
            );
        }
        let parent = path
            .parent()
            .and_then(|p| self.world.get(&p).copied())
            .unwrap_or(self.to_y_up);
        let (local, reset) = self.local_transform(path)?;
        let world = if reset { self.to_y_up } else { parent } * local;
        self.world.insert(path.clone(), world);
        let at = geom::Place {
            name: path.as_str().to_string(),
            world,
            share: self.prototype_of(path)?.map(|p| p.as_str().to_string()),
        };
        if self.gprim(path, &kind, &at)? {
            return Ok(());
        }
        match kind.as_str() {
            "RectLight" | "DiskLight" | "SphereLight" | "DistantLight" | "DomeLight"
            | "DomeLight_1" => self.light(path, &kind, world)?,
            "Camera" => self.cameras.push(path.clone()),
            "RenderSettings" => self.render_settings.push(path.clone()),
            "PointInstancer" => self.point_instancer(path, world)?,
            "Points" | "BasisCurves" | "NurbsCurves" | "HermiteCurves" | "NurbsPatch"
            | "TetMesh" | "Volume" => self.warn(
                path,
                "",
                format!("{kind} is not rendered (illum has no exact {kind}; author it as a Mesh)"),
            ),
            "Skeleton" | "SkelAnimation" | "BlendShape" => self.warn(
                path,
                "",
                format!("{kind}: skinning is not applied (meshes render in their bind pose)"),
            ),
            "CylinderLight" | "GeometryLight" | "PortalLight" | "PluginLight" => self.warn(
                path,
                "",
                format!("{kind} is not supported: the light is left out"),
            ),
            _ => {}
        }
        Ok(())
    }
}

/// The bytes of a file inside a USDZ package (`package.usdz[inner]`), if it is there.
fn packaged(path: &str) -> Option<Vec<u8>> {
    use openusd::ar::Resolver as _;
    use std::io::Read as _;
    let mut asset = openusd::ar::DefaultResolver::new()
        .open_asset(&openusd::ar::ResolvedPath::new(path))
        .ok()?;
    let mut bytes = Vec::new();
    asset.read_to_end(&mut bytes).ok()?;
    Some(bytes)
}

/// `a/./b/../c` as `a/c`, for paths inside a package (no file system to ask).
fn normalize(p: &Path) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for c in p.to_str().unwrap_or_default().split('/') {
        match c {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            c => parts.push(c),
        }
    }
    parts.join("/")
}
