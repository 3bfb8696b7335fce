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
}

#[derive(Clone, Debug)]
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
    ) -> Result<(), crate::Error> {
        if width == Some(0) || height == Some(0) {
            return Err(crate::Error::Invalid(
                "--width and --height must be at least 1".into(),
            ));
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
    /// glTF metallic-roughness: multiplies metallic (B) and roughness (G) per texel.
    pub metallic_roughness_texture: Option<TextureId>,
    /// glTF metallic-roughness factors. When present the shader re-derives, per texel, the
    /// diffuse albedo base·(1−metallic), the first lobe's Schlick f0 = mix(0.04, base, metallic)
    /// and its alpha = roughness², with base = base_color × the base-colour texture.
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

/// The factors of a glTF metallic-roughness material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    pub base_color: Vec3,
    pub metallic: f32,
    pub roughness: f32,
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
    /// Infinite environment; `texture` is an equirectangular map (u = longitude, v = 0 at +Y).
    /// `rotation_deg` rotates the map about +Y.
    Dome {
        rotation_deg: f64,
    },
    /// Distant light toward which `direction` points (from the scene to the sun); irradiance at
    /// normal incidence `irradiance` (W·m⁻²) is `color * intensity * 2^exposure`.
    Sun {
        direction: DVec3,
        angular_diameter_deg: f64,
    },
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
