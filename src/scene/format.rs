//! The JSON scene file format, as serde + schemars types. These mirror the file exactly;
//! `load.rs` validates them and builds the renderer-facing `Scene`.
//!
//! Objects that take one of several geometries (shapes, lights, the camera) are parsed as one
//! flat struct so that serde's errors stay precise ("unknown field" with line and column) —
//! untagged enums only say "data did not match any variant". Their schemas are described by
//! schema-only types in `schema.rs` that spell out the alternatives.

use indexmap::IndexMap;
use schemars::{JsonSchema, Schema, SchemaGenerator, json_schema};

use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use std::borrow::Cow;
use std::fmt;
use std::marker::PhantomData;

pub type V2 = [f64; 2];
pub type V3 = [f64; 3];

/// An illum scene file (see docs/scene-format.md).
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "illum scene")]
pub struct SceneFile {
    /// Optional reference to this schema, for editors; ignored by illum.
    #[serde(rename = "$schema")]
    pub _schema: Option<String>,
    /// Free text: what the scene is for (shown by `illum stress` and in reports).
    pub description: Option<String>,
    /// The viewpoint.
    pub camera: CameraDef,
    /// Images by name, referenced by materials and lights.
    #[serde(default)]
    pub textures: NamedMap<TextureDef>,
    /// Materials by name, referenced by shapes.
    #[serde(default)]
    pub materials: NamedMap<MaterialDef>,
    /// Geometry by name.
    #[serde(default)]
    pub shapes: NamedMap<ShapeDef>,
    /// Emitters by name.
    #[serde(default)]
    pub lights: NamedMap<LightDef>,
    /// The integrator this scene is meant for; the command line overrides each field.
    pub integrator: Option<IntegratorDef>,
}

/// Integrator defaults of a scene (`illum render --integrator` and its options override them):
/// its name and its parameters, each read by the integrator it names (docs/scene-format.md lists
/// them), which refuses a name it does not take.
#[derive(Debug, Clone, Default, serde::Deserialize, JsonSchema)]
pub struct IntegratorDef {
    /// direct (direct lighting only), full (direct + radiosity cache + reflection) or path
    /// (brute-force path tracer); default direct.
    #[serde(rename = "type")]
    pub kind: Option<String>,
    /// The integrator's parameters (e.g. `max_depth`, `light_samples`): numbers, booleans or
    /// strings.
    #[serde(flatten)]
    pub params: std::collections::BTreeMap<String, serde_json::Value>,
}

/// Camera: either the look-at form (`position`, `look_at`, `fov_y`) or the glTF form (`gltf`).
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    pub position: Option<V3>,
    pub look_at: Option<V3>,
    pub up: Option<V3>,
    pub fov_y: Option<f64>,
    pub gltf: Option<String>,
    pub index: Option<u32>,
    #[serde(default = "default_resolution")]
    pub resolution: [u32; 2],
}

pub fn default_resolution() -> [u32; 2] {
    [512, 512]
}

/// An image file.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TextureDef {
    /// Path relative to the scene file: .png, .jpg/.jpeg (8/16-bit), .exr or .hdr.
    pub file: String,
    /// Whether the RGB values are sRGB-encoded (decoded to linear on load). Default: true for
    /// .png/.jpg, false for .exr/.hdr.
    pub srgb: Option<bool>,
    /// Reconstruction between texel centres (Mitsuba 3's `filter_type`).
    #[serde(default)]
    pub filter: FilterDef,
    /// Texel indices outside the image, along both axes (Mitsuba 3's `wrap_mode`).
    #[serde(default)]
    pub wrap: WrapDef,
    /// Pixels handed over by an application ([`super::SceneBuilder::texture_pixels`]) instead
    /// of a file; not part of the file format.
    #[serde(skip)]
    #[schemars(skip)]
    pub pixels: Option<HostPixels>,
    /// The image file's bytes, read by the loader from where a plain path cannot reach (an
    /// image inside a USDZ package); `file` names it for messages and its kind. Not part of
    /// the file format.
    #[serde(skip)]
    #[schemars(skip)]
    pub bytes: Option<Vec<u8>>,
    /// Mirror the image left to right on load (a UsdLux rect light's texture, which its
    /// rectangle shows mirrored against illum's rect uvs). Not part of the file format.
    #[serde(skip)]
    #[schemars(skip)]
    pub mirror_u: bool,
}

/// An image in host memory: `rgba` holds width × height RGBA texels, row-major, top row first.
#[derive(Debug, Clone, Default)]
pub struct HostPixels {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<f32>,
}

/// Texture filter.
#[derive(Debug, Clone, Copy, Default, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FilterDef {
    /// The four nearest texels, weighted bilinearly.
    #[default]
    Bilinear,
    /// The texel that contains the point.
    Nearest,
}

/// Texture wrap mode.
#[derive(Debug, Clone, Copy, Default, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum WrapDef {
    /// Periodic.
    #[default]
    Repeat,
    /// The edge texel continues outward.
    Clamp,
    /// Reflected at each edge, the edge texel repeated.
    Mirror,
}

/// A surface material: Lambert diffuse plus up to two microfacet specular lobes, optionally
/// emissive.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    /// Lambert albedo, linear RGB, each in [0, 1].
    #[serde(default = "default_diffuse")]
    pub diffuse: V3,
    /// Texture name; its RGB multiplies `diffuse`.
    pub diffuse_texture: Option<String>,
    /// Specular lobes, at most 2, added on top of the diffuse.
    #[serde(default)]
    pub specular: Vec<LobeDef>,
    /// Emitted radiance in W·m⁻²·sr⁻¹ (linear RGB, each >= 0).
    #[serde(default)]
    pub emission: V3,
    /// Texture name; its RGB multiplies `emission`.
    pub emission_texture: Option<String>,
    /// Emit from both sides (default: only toward the geometric normal).
    #[serde(default)]
    pub two_sided: bool,
    /// Anisotropy (tangent) direction for surfaces without tangents, projected onto the
    /// tangent plane; default: derived from the normal.
    pub tangent: Option<V3>,
    /// The metallic-roughness model (glTF's, UsdPreviewSurface's metallic workflow): `diffuse`
    /// and `diffuse_texture` are then the base colour, and the material has one GGX-Smith lobe
    /// derived per texel (so `specular` must be left out).
    pub metallic_roughness: Option<MetallicRoughnessDef>,
}

/// Metallic-roughness parameters, each optionally multiplied per texel by a texture's channel.
/// Per texel, with base = diffuse × diffuse_texture: Lambert albedo base·(1 − metallic), one
/// GGX-Smith lobe of alpha max(roughness², 1e-4) and Schlick f0 = mix(((ior − 1)/(ior + 1))²,
/// base, metallic).
#[derive(Debug, Clone, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MetallicRoughnessDef {
    /// Metalness in [0, 1].
    #[serde(default)]
    pub metallic: f64,
    /// A texture channel multiplying `metallic` (default channel: b, glTF's).
    pub metallic_texture: Option<ChannelDef>,
    /// Perceptual roughness in [0, 1] (alpha = roughness²).
    #[serde(default = "default_roughness")]
    pub roughness: f64,
    /// A texture channel multiplying `roughness` (default channel: g, glTF's).
    pub roughness_texture: Option<ChannelDef>,
    /// Index of refraction of the dielectric part, >= 1 (1.5: f0 = 0.04, glTF's).
    #[serde(default = "default_ior")]
    pub ior: f64,
}

pub fn default_roughness() -> f64 {
    0.5
}

pub fn default_ior() -> f64 {
    1.5
}

/// One channel of a texture: a scalar map.
#[derive(Debug, Clone, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChannelDef {
    /// Texture name.
    pub texture: String,
    /// Which channel; default: the field's (glTF's packing).
    pub channel: Option<ChannelName>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ChannelName {
    R,
    G,
    B,
    A,
}

pub fn default_diffuse() -> V3 {
    [0.5, 0.5, 0.5]
}

/// One specular lobe.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LobeDef {
    /// Microfacet model.
    pub model: ModelDef,
    /// Roughness alpha in [0, 1]: one number (isotropic) or [alpha_t, alpha_b] (along the
    /// tangent and the bitangent). Below 1e-4 it is 1e-4 (Mitsuba 3's floor); 0 along both axes
    /// is a perfect mirror.
    pub roughness: NumOrArray<2>,
    /// Fresnel term; default {"schlick": [0.04, 0.04, 0.04]}.
    #[serde(default = "default_fresnel")]
    pub fresnel: FresnelDef,
}

#[derive(Debug, Clone, Copy, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ModelDef {
    /// The course's D-BRDF: Beckmann distribution, no shadowing term.
    Dbrdf,
    /// Cook-Torrance, Beckmann distribution with Smith shadowing.
    Beckmann,
    /// Cook-Torrance, GGX distribution with Smith shadowing.
    Ggx,
}

#[derive(Debug, Clone, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FresnelDef {
    /// Angle-independent reflectance, each in [0, 1].
    Constant(V3),
    /// Schlick's approximation with this reflectance at normal incidence, each in [0, 1].
    Schlick(V3),
    /// Exact conductor Fresnel with complex index of refraction eta + i k per channel.
    Conductor {
        /// Real part, each > 0.
        eta: V3,
        /// Imaginary part (extinction), each >= 0.
        k: V3,
    },
}

pub fn default_fresnel() -> FresnelDef {
    FresnelDef::Schlick([0.04; 3])
}

/// A shape: exactly one of `sphere`, `rect`, `disk`, `mesh`, `gltf`, `instance`.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeDef {
    pub sphere: Option<SphereDef>,
    pub rect: Option<RectDef>,
    pub disk: Option<DiskDef>,
    pub mesh: Option<MeshDef>,
    pub gltf: Option<GltfDef>,
    /// The name of an earlier mesh shape whose mesh (and material) this shape places again
    /// with its own transform, without a copy.
    pub instance: Option<String>,
    pub material: Option<String>,
    pub transform: Option<TransformDef>,
    /// Spheres only: the axis of the anisotropic tangent's latitudes.
    pub pole: Option<V3>,
}

/// A sphere in world space.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereDef {
    pub center: V3,
    /// Radius > 0 (>= 0 for lights).
    pub radius: f64,
}

/// A rectangle in world space.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RectDef {
    pub center: V3,
    /// Front-side normal (need not be unit length).
    pub normal: V3,
    /// Full edge lengths [along u, along v], each > 0 (>= 0 for lights).
    pub size: V2,
    /// Direction of the second (v) edge, projected onto the plane. Default +Y, or -Z when the
    /// normal is within 2.6° of ±Y. u = v × normal.
    pub up: Option<V3>,
}

/// A disk in world space.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiskDef {
    pub center: V3,
    /// Front-side normal (need not be unit length).
    pub normal: V3,
    /// Radius > 0 (>= 0 for lights).
    pub radius: f64,
}

/// An inline triangle mesh in object space.
#[derive(Debug, Default, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshDef {
    /// Vertex positions.
    pub positions: Vec<V3>,
    /// Triangle list (3 per triangle, counter-clockwise = front); default 0, 1, 2, ….
    pub indices: Option<Vec<u32>>,
    /// Per-vertex shading normals (one per position); default: flat shading.
    pub normals: Option<Vec<V3>>,
    /// Per-vertex texture coordinates (one per position).
    pub uvs: Option<Vec<V2>>,
    /// Per-vertex tangents [x, y, z, w] (one per position; xyz non-zero, w = ±1 the bitangent's
    /// handedness, as glTF's TANGENT): the anisotropy direction, before the material's `tangent`.
    pub tangents: Option<Vec<[f64; 4]>>,
}

/// A glTF 2.0 file (.gltf or .glb).
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GltfDef {
    /// Path relative to the scene file.
    pub file: String,
}

/// Object-to-world transform: `translate`/`rotate`/`scale` (M = T·Rz·Ry·Rx·S) or `matrix`.
#[derive(Debug, Default, Clone, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransformDef {
    /// Translation.
    pub translate: Option<V3>,
    /// Rotation angles in degrees about X, Y, Z, applied in that order.
    pub rotate: Option<V3>,
    /// Uniform scale or per-axis [sx, sy, sz].
    pub scale: Option<NumOrArray<3>>,
    /// 16 numbers, row-major (translation in elements 3, 7, 11; last row 0 0 0 1).
    pub matrix: Option<[f64; 16]>,
}

/// A light: exactly one of `rect`, `disk`, `sphere`, `dome`, `sun`, plus common fields.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    pub rect: Option<RectDef>,
    pub disk: Option<DiskDef>,
    pub sphere: Option<SphereDef>,
    pub dome: Option<DomeDef>,
    pub sun: Option<SunDef>,
    #[serde(default = "default_color")]
    pub color: V3,
    #[serde(default = "default_intensity")]
    pub intensity: f64,
    #[serde(default)]
    pub exposure: f64,
    #[serde(default)]
    pub two_sided: bool,
    pub texture: Option<String>,
    #[serde(default = "default_visible")]
    pub visible: bool,
    pub shadows: Option<bool>,
}

pub fn default_color() -> V3 {
    [1.0; 3]
}
pub fn default_intensity() -> f64 {
    1.0
}
pub fn default_visible() -> bool {
    true
}

/// Infinite environment light.
#[derive(Debug, Default, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DomeDef {
    /// Rotation of the map about +Y in degrees.
    #[serde(default)]
    pub rotation: f64,
    /// How the map covers the sphere: illum's lat-long (default), Mitsuba 3's `envmap` or
    /// pbrt-v4's equal-area `imageinfinite` (docs/scene-format.md gives each mapping).
    #[serde(default)]
    pub convention: DomeConventionDef,
}

/// Dome map convention.
#[derive(Debug, Clone, Copy, Default, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DomeConventionDef {
    /// Lat-long, u = 1/2 at -Z, texel centres at (i + 1/2)/size, the texture's filter and wrap.
    #[default]
    Illum,
    /// Mitsuba 3 envmap: lat-long, u = 0 at -Z, rows on the poles, bilinear.
    Mitsuba,
    /// pbrt-v4 imageinfinite: equal-area octahedral square map, nearest texel.
    Pbrt,
}

/// Distant light.
#[derive(Debug, serde::Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SunDef {
    /// Direction toward the sun (from the scene), need not be unit length.
    pub direction: V3,
    /// Apparent diameter in degrees, in [0, 180); 0 gives a delta (hard-shadow) light.
    #[serde(default = "default_angular_diameter")]
    pub angular_diameter: f64,
}

pub fn default_angular_diameter() -> f64 {
    0.53
}

/// A JSON object of named entries, in file order; a repeated name is an error (serde_json
/// would otherwise keep the last one silently).
#[derive(Debug)]
pub struct NamedMap<T>(pub IndexMap<String, T>);

impl<T> Default for NamedMap<T> {
    fn default() -> Self {
        NamedMap(IndexMap::new())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for NamedMap<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = NamedMap<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an object of named entries")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = IndexMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    if out.contains_key(&key) {
                        return Err(de::Error::custom(format!("duplicate name \"{key}\"")));
                    }
                    let value = map.next_value()?;
                    out.insert(key, value);
                }
                Ok(NamedMap(out))
            }
        }
        d.deserialize_map(V(PhantomData))
    }
}

impl<T: JsonSchema> JsonSchema for NamedMap<T> {
    fn schema_name() -> Cow<'static, str> {
        IndexMap::<String, T>::schema_name()
    }
    fn inline_schema() -> bool {
        true
    }
    fn json_schema(generator: &mut SchemaGenerator) -> Schema {
        IndexMap::<String, T>::json_schema(generator)
    }
}

/// A number or an array of exactly N numbers (roughness, scale).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NumOrArray<const N: usize> {
    One(f64),
    Many([f64; N]),
}

impl<'de, const N: usize> Deserialize<'de> for NumOrArray<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = NumOrArray<N>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a number or an array of {N} numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(NumOrArray::One(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(NumOrArray::One(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(NumOrArray::One(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [0.0; N];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(N + 1, &self));
                }
                Ok(NumOrArray::Many(out))
            }
        }
        d.deserialize_any(V::<N>)
    }
}

impl<const N: usize> JsonSchema for NumOrArray<N> {
    fn schema_name() -> Cow<'static, str> {
        format!("NumberOr{N}Numbers").into()
    }
    fn inline_schema() -> bool {
        true
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "anyOf": [
                { "type": "number" },
                { "type": "array", "items": { "type": "number" }, "minItems": N, "maxItems": N }
            ]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_or_array() {
        let one: NumOrArray<2> = serde_json::from_str("0.5").unwrap();
        assert_eq!(one, NumOrArray::One(0.5));
        let int: NumOrArray<3> = serde_json::from_str("2").unwrap();
        assert_eq!(int, NumOrArray::One(2.0));
        let many: NumOrArray<2> = serde_json::from_str("[0.1, 1]").unwrap();
        assert_eq!(many, NumOrArray::Many([0.1, 1.0]));
        for bad in ["[0.1]", "[1, 2, 3]", "\"x\"", "null"] {
            assert!(serde_json::from_str::<NumOrArray<2>>(bad).is_err(), "{bad}");
        }
    }
}
