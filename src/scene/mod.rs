//! Scene description: the JSON file format, its validation, glTF and USD loading, and the validated
//! host-side scene the renderer consumes. See docs/scene-format.md.

mod builder;
mod camera;
mod check;
pub mod dome_map;
mod error;
pub mod format;
mod gltf;
mod gltf_material;
mod gltf_mesh;
mod load;
mod schema;
mod texture;
mod transform;
mod types;
mod usd;

pub use builder::SceneBuilder;
pub(crate) use error::io_message;
pub use error::{MAX_ASSET_FILE_BYTES, MAX_SCENE_FILE_BYTES, SceneError};
pub use types::*;

use std::path::Path;

/// Reads and validates a scene file; relative paths in it are relative to its directory.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load::load_file(path)
}

/// Parses and validates scene JSON. `origin` names the text in error messages (usually its
/// file name); relative paths are resolved against `base_dir`.
pub fn from_json_str(text: &str, origin: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let file = load::parse(text, origin)?;
    load::build(&file, origin, base_dir)
}

/// The built-in look-development scene (scenes/default.json, embedded at compile time).
pub fn default_scene() -> Scene {
    const TEXT: &str = include_str!("../../scenes/default.json");
    from_json_str(TEXT, "<default scene>", Path::new("."))
        .unwrap_or_else(|e| panic!("the embedded default scene is invalid: {e}"))
}

/// The JSON Schema of the scene file format (docs/scene.schema.json is this, pretty-printed).
pub fn json_schema() -> serde_json::Value {
    schema::schema()
}
