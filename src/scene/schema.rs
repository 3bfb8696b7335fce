//! The JSON Schema of the scene format. Shapes, lights and the camera are parsed as flat
//! structs (for precise serde errors); the schema-only types here spell out their
//! alternatives, each a closed object with exactly one geometry key.
#![allow(dead_code)] // the schema-only types are never constructed

use super::format::*;
use schemars::{JsonSchema, Schema, SchemaGenerator};
use std::borrow::Cow;

/// The JSON Schema of `SceneFile`. Optional fields are described as absent-or-value, never
/// null: serde happens to accept null for them, but the format does not promise it.
pub fn schema() -> serde_json::Value {
    schemars::generate::SchemaSettings::draft2020_12()
        .with_transform(NoNull)
        .into_generator()
        .into_root_schema_for::<SceneFile>()
        .to_value()
}

#[derive(Clone)]
struct NoNull;

impl schemars::transform::Transform for NoNull {
    fn transform(&mut self, schema: &mut Schema) {
        use serde_json::Value;
        if let Some(Value::Array(types)) = schema.get_mut("type") {
            types.retain(|t| t != "null");
            if let [only] = types.as_slice() {
                let only = only.clone();
                schema.insert("type".into(), only);
            }
        }
        let null = serde_json::json!({ "type": "null" });
        if let Some(Value::Array(any)) = schema.get_mut("anyOf") {
            any.retain(|s| *s != null);
            if any.len() == 1 {
                // {"anyOf": [X]} → X, keeping this schema's description.
                if let Some(Value::Object(inner)) = any.pop() {
                    schema.remove("anyOf");
                    for (k, v) in inner {
                        if schema.get(&k).is_none() {
                            schema.insert(k, v);
                        }
                    }
                }
            }
        }
        schemars::transform::transform_subschemas(self, schema);
    }
}

macro_rules! schema_via {
    ($ty:ty, $schema:ty) => {
        impl JsonSchema for $ty {
            fn schema_name() -> Cow<'static, str> {
                <$schema>::schema_name()
            }
            fn json_schema(generator: &mut SchemaGenerator) -> Schema {
                <$schema>::json_schema(generator)
            }
        }
    };
}
schema_via!(CameraDef, Camera);
schema_via!(ShapeDef, Shape);
schema_via!(LightDef, Light);

/// The camera: a look-at camera, or a camera of a glTF shape.
#[derive(JsonSchema)]
#[serde(untagged)]
pub enum Camera {
    LookAt(LookAtCamera),
    Gltf(GltfCamera),
}

/// Pinhole camera given by position, target and vertical field of view.
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LookAtCamera {
    /// Eye position.
    position: V3,
    /// Point the camera looks at (must differ from `position`).
    look_at: V3,
    /// Up direction (must not be parallel to the view direction).
    #[serde(default = "up_y")]
    up: V3,
    /// Full vertical field of view in degrees, in (0, 180).
    fov_y: f64,
    /// Image size in pixels [width, height], each > 0.
    #[serde(default = "default_resolution")]
    resolution: [u32; 2],
}

fn up_y() -> V3 {
    [0.0, 1.0, 0.0]
}

/// A perspective camera of a glTF shape, placed by its node (and the shape's transform).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GltfCamera {
    /// Name of a shape of this scene with a `gltf` geometry.
    gltf: String,
    /// Index into the glTF file's `cameras` array.
    #[serde(default)]
    index: u32,
    /// Image size in pixels [width, height], each > 0.
    #[serde(default = "default_resolution")]
    resolution: [u32; 2],
}

/// A shape: exactly one geometry key plus its material.
#[derive(JsonSchema)]
#[serde(untagged)]
pub enum Shape {
    Sphere(SphereShape),
    Rect(RectShape),
    Disk(DiskShape),
    Mesh(MeshShape),
    Gltf(GltfShape),
    Instance(InstanceShape),
}

#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereShape {
    sphere: SphereDef,
    /// Material name.
    material: String,
    /// Axis of the sphere's parameterisation: the anisotropic tangent at p is
    /// normalize(pole × (p − center)), along the latitudes (Mitsuba 3's and pbrt-v4's dp/du with
    /// the pole as their local +Z). Default +Y.
    pole: Option<V3>,
}

#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RectShape {
    rect: RectDef,
    /// Material name.
    material: String,
}

#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiskShape {
    disk: DiskDef,
    /// Material name.
    material: String,
}

#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshShape {
    mesh: MeshDef,
    /// Material name.
    material: String,
    transform: Option<TransformDef>,
}

#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GltfShape {
    gltf: GltfDef,
    /// Material name; if given, replaces every material of the glTF file.
    material: Option<String>,
    transform: Option<TransformDef>,
}

/// Another placement of an earlier mesh shape's mesh (and material), without a copy.
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InstanceShape {
    /// Name of an earlier shape with a `mesh`.
    instance: String,
    transform: Option<TransformDef>,
}

/// A light: exactly one geometry key plus the common fields.
#[derive(JsonSchema)]
#[serde(untagged)]
pub enum Light {
    Rect(RectLight),
    Disk(DiskLight),
    Sphere(SphereLight),
    Dome(DomeLight),
    Sun(SunLight),
}

// Fields shared by all lights (no doc comment: it would become each light's description).
#[derive(JsonSchema)]
pub struct Common {
    /// Linear RGB, each >= 0.
    #[serde(default = "default_color")]
    color: V3,
    /// Scale >= 0 (W·m⁻²·sr⁻¹ per unit colour; W·m⁻² for the sun).
    #[serde(default = "default_intensity")]
    intensity: f64,
    /// Exposure in stops (multiplies by 2^exposure).
    #[serde(default)]
    exposure: f64,
    /// Area lights only: emit from both sides (must be false for dome and sun).
    #[serde(default)]
    two_sided: bool,
    /// Texture name multiplying the radiance (rect/disk uv, sphere lat-long, dome
    /// equirectangular map); not allowed on the sun.
    texture: Option<String>,
    /// Whether camera rays see the light (area lights and dome).
    #[serde(default = "default_visible")]
    visible: bool,
    /// Area lights only: whether the light's surface is an opaque object that blocks other
    /// lights and BRDF rays (default true, as in Mitsuba 3 and pbrt-v4); false makes it
    /// transparent to shadow rays.
    shadows: Option<bool>,
}

/// Rectangular area light (radiance = color · intensity · 2^exposure).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RectLight {
    rect: RectDef,
    #[serde(flatten)]
    common: Common,
}

/// Disk area light (radiance = color · intensity · 2^exposure).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiskLight {
    disk: DiskDef,
    #[serde(flatten)]
    common: Common,
}

/// Spherical area light (radiance = color · intensity · 2^exposure).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereLight {
    sphere: SphereDef,
    #[serde(flatten)]
    common: Common,
}

/// Environment light (radiance = color · intensity · 2^exposure, times the texture).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DomeLight {
    dome: DomeDef,
    #[serde(flatten)]
    common: Common,
}

/// Distant light (irradiance at normal incidence = color · intensity · 2^exposure, W·m⁻²).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SunLight {
    sun: SunDef,
    #[serde(flatten)]
    common: Common,
}

#[cfg(test)]
mod tests {
    #[test]
    fn schema_has_no_nulls() {
        let text = super::schema().to_string();
        assert!(!text.contains("\"null\""), "{text}");
    }
}
