//! glTF 2.0 shapes (.gltf and .glb): container and buffers, the node hierarchy, cameras.
//! Meshes and materials are converted in `gltf_mesh.rs` and `gltf_material.rs`.

use super::check::Ctx;
use super::error::{MAX_ASSET_FILE_BYTES, SceneError, fmt_num, io_message, quoted, read_capped};
use super::load::Parts;
use super::transform::check_invertible;
use super::types::MaterialId;
use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3};
use std::collections::HashMap;
use std::path::Path;

type Result<T> = std::result::Result<T, SceneError>;

/// Required extensions illum implements; any other one in `extensionsRequired` is an error.
pub(crate) const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &["KHR_materials_emissive_strength"];

/// One glTF shape to load.
pub(crate) struct Request<'a> {
    /// The scene file and the field naming the glTF file, for errors before it is opened.
    pub scene_file: &'a str,
    pub field: &'a str,
    pub base_dir: &'a Path,
    /// As written in the scene file, relative to `base_dir`.
    pub file: &'a str,
    /// The scene shape's name: prefix of the names of everything loaded from the file.
    pub shape: &'a str,
    /// The shape's transform, applied on top of the node hierarchy.
    pub transform: DMat4,
    /// Replaces every glTF material when set.
    pub material_override: Option<MaterialId>,
}

/// A glTF camera (by index in the file's `cameras` array), placed by the first node using it.
#[derive(Clone, Debug)]
pub(crate) enum GltfCamera {
    Perspective {
        position: DVec3,
        /// Unit vectors: -Z and +Y of the camera node in world space.
        forward: DVec3,
        up: DVec3,
        yfov_deg: f64,
    },
    Orthographic,
    /// No node of the loaded scene references it.
    Unplaced,
}

/// The loaded document with its buffers, plus what was already converted (for sharing).
pub(crate) struct Loader<'a> {
    pub req: &'a Request<'a>,
    /// The glTF file's path as shown in messages.
    pub gfile: String,
    /// Directory of the glTF file, for relative URIs.
    pub dir: &'a Path,
    pub buffers: Vec<Vec<u8>>,
    pub parts: &'a mut Parts,
    /// (mesh, primitive) → index in `parts.meshes`.
    pub mesh_ids: HashMap<(usize, usize), u32>,
    /// glTF material index (None: the default material) → index in `parts.materials`.
    pub material_ids: HashMap<Option<usize>, MaterialId>,
    /// (glTF image, sRGB) → index in `parts.textures`.
    pub image_ids: HashMap<(usize, bool), u32>,
    pub cameras: Vec<GltfCamera>,
}

impl Loader<'_> {
    pub fn ctx(&self) -> Ctx<'_> {
        Ctx { file: &self.gfile }
    }

    pub fn unsupported(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::unsupported(&self.gfile, field, message)
    }
}

/// Loads the glTF file of `req` into `parts`; returns its cameras by glTF index.
pub(crate) fn load(req: &Request, parts: &mut Parts) -> Result<Vec<GltfCamera>> {
    let path = req.base_dir.join(req.file);
    let gfile = path.display().to_string();
    let bytes = read_capped(&path, MAX_ASSET_FILE_BYTES)
        .map_err(|e| SceneError::file_read(req.scene_file, req.field, req.file, &e))?;
    let (json, blob) = if bytes.starts_with(b"glTF") {
        // The gltf crate subtracts the header size from this length unchecked.
        let length = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if length.is_none_or(|l| l < 12) {
            let e = "invalid GLB: truncated header";
            return Err(SceneError::decode(req.scene_file, req.field, req.file, e));
        }
        let glb = gltf::binary::Glb::from_slice(&bytes).map_err(|e| {
            SceneError::decode(
                req.scene_file,
                req.field,
                req.file,
                format!("invalid GLB: {e}"),
            )
        })?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes, None)
    };
    check_required_extensions(&json, &gfile)?;
    // Parsed by us (not `Gltf::from_slice`) to report line, column and field path.
    let mut de = serde_json::Deserializer::from_slice(&json);
    let root: gltf::json::Root = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| SceneError::from_json(&gfile, e.path().to_string(), e.inner()))?;
    prevalidate(&root, &gfile)?;
    let doc = gltf::Document::from_json(root).map_err(|e| validation_error(&gfile, e))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = load_buffers(&doc, blob, dir, &gfile)?;

    let mut loader = Loader {
        req,
        gfile,
        dir,
        buffers,
        parts,
        mesh_ids: HashMap::new(),
        material_ids: HashMap::new(),
        image_ids: HashMap::new(),
        cameras: vec![GltfCamera::Unplaced; doc.cameras().len()],
    };
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scenes: every node that is nobody's child is a root.
            let mut is_child = vec![false; doc.nodes().len()];
            for node in doc.nodes() {
                for child in node.children() {
                    is_child[child.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut on_path = vec![false; doc.nodes().len()];
    for node in roots {
        loader.visit(&node, req.transform, &mut on_path)?;
    }
    Ok(loader.cameras)
}

/// Our own check, before the gltf crate's validation, so that the message names the extension
/// and what illum supports.
fn check_required_extensions(json: &[u8], gfile: &str) -> Result<()> {
    let value: serde_json::Value = serde_json::from_slice(json)
        .map_err(|e| SceneError::from_json(gfile, String::new(), &e))?;
    let Some(required) = value.get("extensionsRequired").and_then(|v| v.as_array()) else {
        return Ok(());
    };
    for ext in required {
        let name = ext.as_str().unwrap_or_default();
        if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&name) {
            return Err(SceneError::unsupported(
                gfile,
                "extensionsRequired",
                format!(
                    "unsupported required extension {} (illum supports: {})",
                    if name.is_empty() {
                        ext.to_string()
                    } else {
                        quoted(name)
                    },
                    SUPPORTED_REQUIRED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Checks the gltf crate relies on without making them: its validation indexes `accessors`
/// with POSITION unchecked, and its accessors unwrap image sources and camera projections.
fn prevalidate(root: &gltf::json::Root, gfile: &str) -> Result<()> {
    use gltf::json::validation::Checked;
    let position = Checked::Valid(gltf::json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim.attributes.get(&position).map(|i| i.value())
                && i >= root.accessors.len()
            {
                return Err(SceneError::invalid(
                    gfile,
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    i,
                    format!(
                        "accessor index out of range ({} accessors)",
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        let problem = match (&image.uri, &image.buffer_view, &image.mime_type) {
            (Some(_), None, _) | (None, Some(_), Some(_)) => continue,
            (None, Some(_), None) => "an image in a bufferView needs a mimeType",
            _ => "needs exactly one of uri and bufferView",
        };
        return Err(SceneError::unsupported(
            gfile,
            format!("images[{i}]"),
            problem,
        ));
    }
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        let ok = match camera.type_ {
            Checked::Valid(Type::Perspective) => camera.perspective.is_some(),
            Checked::Valid(Type::Orthographic) => camera.orthographic.is_some(),
            Checked::Invalid => true, // reported by validation
        };
        if !ok {
            return Err(SceneError::unsupported(
                gfile,
                format!("cameras[{i}]"),
                "the object named by \"type\" is missing",
            ));
        }
    }
    Ok(())
}

fn validation_error(gfile: &str, e: gltf::Error) -> SceneError {
    match e {
        gltf::Error::Validation(errors) if !errors.is_empty() => {
            let (path, error) = &errors[0];
            let more = match errors.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            SceneError::unsupported(
                gfile,
                path.to_string(),
                format!("invalid glTF: {error}{more}"),
            )
        }
        other => SceneError::unsupported(gfile, "(document)", format!("invalid glTF: {other}")),
    }
}

fn load_buffers(
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    dir: &Path,
    gfile: &str,
) -> Result<Vec<Vec<u8>>> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let field = format!("buffers[{}]", buffer.index());
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                SceneError::unsupported(
                    gfile,
                    &field,
                    "refers to the GLB binary chunk, but there is none (or it is used twice)",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, dir, gfile, &format!("{field}.uri"))?,
        };
        if data.len() < buffer.length() {
            return Err(SceneError::invalid(
                gfile,
                format!("{field}.byteLength"),
                buffer.length(),
                format!("exceeds the buffer's data ({} bytes)", data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Reads a `data:` URI (base64) or a file path relative to the glTF file.
pub(crate) fn read_uri(uri: &str, dir: &Path, gfile: &str, field: &str) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return Err(SceneError::decode(
                gfile,
                field,
                "data: URI",
                "no ',' separator",
            ));
        };
        if !header.ends_with(";base64") {
            return Err(SceneError::unsupported(
                gfile,
                field,
                "only base64 data: URIs are supported",
            ));
        }
        let engine = base64::engine::GeneralPurpose::new(
            &base64::alphabet::STANDARD,
            base64::engine::GeneralPurposeConfig::new()
                .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
        );
        return engine
            .decode(payload.trim())
            .map_err(|e| SceneError::decode(gfile, field, "data: URI", e));
    }
    if uri.contains("://") {
        return Err(SceneError::unsupported(
            gfile,
            field,
            format!(
                "only relative file paths and data: URIs are supported, got {}",
                quoted(uri)
            ),
        ));
    }
    let rel = percent_decode(uri);
    // glTF URIs are relative to the file (glTF 2.0, 2.8): an absolute path (`/etc/passwd`)
    // would read whatever it names.
    if Path::new(&rel).has_root() {
        return Err(SceneError::unsupported(
            gfile,
            field,
            format!(
                "URIs are relative to the glTF file, got the absolute path {}",
                quoted(uri)
            ),
        ));
    }
    read_capped(&dir.join(&rel), MAX_ASSET_FILE_BYTES).map_err(|e| SceneError::FileRead {
        file: gfile.to_owned(),
        field: field.to_owned(),
        path: rel,
        message: io_message(&e),
    })
}

/// URIs in glTF are percent-encoded ("my%20file.bin").
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn node_matrix(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation: t,
            rotation: r,
            scale: s,
        } => {
            let q = DQuat::from_xyzw(r[0].into(), r[1].into(), r[2].into(), r[3].into());
            DMat4::from_scale_rotation_translation(
                DVec3::new(s[0].into(), s[1].into(), s[2].into()),
                q.normalize(),
                DVec3::new(t[0].into(), t[1].into(), t[2].into()),
            )
        }
    }
}

fn node_name(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) if !n.is_empty() => n.to_owned(),
        _ => format!("nodes[{}]", node.index()),
    }
}

impl Loader<'_> {
    fn visit(&mut self, node: &gltf::Node, parent: DMat4, on_path: &mut [bool]) -> Result<()> {
        let i = node.index();
        let field = format!("nodes[{i}]");
        let local = node_matrix(node);
        if !local.is_finite() {
            return Err(self.ctx().err(
                &field,
                "a non-finite matrix",
                "transform must be finite (and its rotation a non-zero quaternion)",
            ));
        }
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            check_invertible(self.ctx(), &format!("{field} (world transform)"), &world)?;
            for prim in mesh.primitives() {
                let id = self.mesh_id(&mesh, &prim)?;
                self.parts.instances.push(super::types::MeshInstance {
                    mesh: id,
                    transform: world,
                    name: format!("{}/{}", self.req.shape, node_name(node)),
                });
            }
        }
        if let Some(cam) = node.camera() {
            self.place_camera(&cam, &world, &field)?;
        }
        on_path[i] = true;
        for child in node.children() {
            if on_path[child.index()] {
                return Err(self.unsupported(
                    format!("{field}.children"),
                    format!(
                        "the node hierarchy has a cycle (back to nodes[{}])",
                        child.index()
                    ),
                ));
            }
            self.visit(&child, world, on_path)?;
        }
        on_path[i] = false;
        Ok(())
    }

    fn place_camera(&mut self, cam: &gltf::Camera, world: &DMat4, field: &str) -> Result<()> {
        let c = cam.index();
        if !matches!(self.cameras[c], GltfCamera::Unplaced) {
            return Ok(());
        }
        self.cameras[c] = match cam.projection() {
            gltf::camera::Projection::Orthographic(_) => GltfCamera::Orthographic,
            gltf::camera::Projection::Perspective(p) => {
                let yfov = f64::from(p.yfov());
                if !(yfov > 0.0 && yfov < std::f64::consts::PI) {
                    return Err(self.ctx().err(
                        format!("cameras[{c}].perspective.yfov"),
                        fmt_num(yfov),
                        "must be in (0, π) radians",
                    ));
                }
                check_invertible(self.ctx(), &format!("{field} (world transform)"), world)?;
                GltfCamera::Perspective {
                    position: world.transform_point3(DVec3::ZERO),
                    forward: world.transform_vector3(DVec3::NEG_Z).normalize(),
                    up: world.transform_vector3(DVec3::Y).normalize(),
                    yfov_deg: yfov.to_degrees(),
                }
            }
        };
        Ok(())
    }

    fn mesh_id(&mut self, mesh: &gltf::Mesh, prim: &gltf::Primitive) -> Result<u32> {
        let key = (mesh.index(), prim.index());
        if let Some(&id) = self.mesh_ids.get(&key) {
            return Ok(id);
        }
        let material = match self.req.material_override {
            Some(m) => m,
            None => self.material_id(&prim.material())?,
        };
        let mesh_name = match mesh.name() {
            Some(n) if !n.is_empty() => n.to_owned(),
            _ => format!("meshes[{}]", mesh.index()),
        };
        let name = format!("{}/{}/{}", self.req.shape, mesh_name, prim.index());
        let converted = self.primitive(mesh, prim, name, material)?;
        let id = self.parts.meshes.len() as u32;
        self.parts.meshes.push(converted);
        self.mesh_ids.insert(key, id);
        Ok(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_percent_decoded() {
        assert_eq!(percent_decode("mesh%20data.bin"), "mesh data.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("a%zzb"), "a%zzb");
    }

    /// The gltf crate rejects unknown required extensions on its own too, but with a terse
    /// "extensionsRequired[0] = ...: Unsupported extension"; ours must come first.
    #[test]
    fn required_extensions_are_checked_before_the_gltf_crate() {
        let json = br#"{"asset": {"version": "2.0"}, "extensionsRequired": ["KHR_draco_mesh_compression"]}"#;
        assert!(matches!(
            gltf::Gltf::from_slice(json),
            Err(gltf::Error::Validation(_))
        ));
        let msg = check_required_extensions(json, "a.gltf")
            .unwrap_err()
            .to_string();
        assert_eq!(
            msg,
            "a.gltf: extensionsRequired: unsupported required extension \
             \"KHR_draco_mesh_compression\" (illum supports: KHR_materials_emissive_strength)"
        );
        let ok = br#"{"asset": {"version": "2.0"}, "extensionsRequired": ["KHR_materials_emissive_strength"]}"#;
        assert!(check_required_extensions(ok, "a.gltf").is_ok());
    }

    #[test]
    fn data_uris_decode_with_or_without_padding() {
        let dir = Path::new(".");
        let f = "buffers[0].uri";
        let a = read_uri(
            "data:application/octet-stream;base64,AAEC",
            dir,
            "a.gltf",
            f,
        );
        assert_eq!(a.unwrap(), [0, 1, 2]);
        let b = read_uri("data:application/gltf-buffer;base64,AAE", dir, "a.gltf", f);
        assert_eq!(b.unwrap(), [0, 1]);
        let e = read_uri("data:text/plain,hello", dir, "a.gltf", f).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.gltf: buffers[0].uri: only base64 data: URIs are supported"
        );
        let e = read_uri("/etc/passwd", dir, "a.gltf", f).unwrap_err();
        assert!(e.to_string().contains("absolute path"), "{e}");
        let e = read_uri("%2Fetc/passwd", dir, "a.gltf", f).unwrap_err();
        assert!(e.to_string().contains("absolute path"), "{e}");
        let e = read_uri("https://example.com/a.bin", dir, "a.gltf", f).unwrap_err();
        assert!(
            e.to_string()
                .contains("only relative file paths and data: URIs"),
            "{e}"
        );
    }
}
