//! Scene → GPU buffers: the uploaded scene that the trace structures (src/trace) are built over
//! and the integrators (src/render) read. Below both: nothing here imports either.
//! Positions become camera-relative (encode.rs), in double precision, before the conversion to
//! f32: a scene 1e5 units from the origin keeps the precision of one at the origin.

pub mod dome;
mod dome_sh;
mod encode;
mod light_mean;
pub mod light_tree;
mod lights;
mod update;
pub use update::SceneUpdate;

use crate::error::Result;
use crate::layout::*;
use crate::scene::Scene;
use crate::vk::{Buffer, Context};
use ash::vk;
use encode::encode_scene;
use glam::{DVec3, Vec3};

/// Index ranges of one mesh inside the shared vertex and index buffers.
#[derive(Clone, Copy, Debug)]
pub struct MeshRange {
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub triangle_count: u32,
}

/// The scene in device memory, plus what the trace structures need to be built over it.
pub struct GpuScene {
    pub frame: Frame,
    pub features: u32,
    /// With FEATURE_FLAT_SHAPES, the shapes' kinds (SPEC_FLAT_KINDS): the kernels' second
    /// specialization constant.
    pub flat_kinds: u32,
    pub meshes: Vec<MeshRange>,
    /// (mesh index, rows of the camera-relative object-to-world matrix) per instance.
    pub instances: Vec<(u32, [[f32; 4]; 3])>,
    pub shapes: Vec<GpuShape>,
    /// Ray mask of each shape (MASK_*): scene geometry first, then the light surfaces.
    pub shape_masks: Vec<u32>,
    /// Boxes of the shapes (lo.xyz, hi.xyz), padded so that rounding never clips a hit.
    pub shape_boxes: Vec<[f32; 6]>,
    /// Camera position in world space: the origin of the render's coordinates.
    pub origin: DVec3,
    /// Names of the scene's lights that emit nothing (zero radiance or area), left out.
    pub dark_lights: Vec<String>,
    /// Lights uploaded, emissive geometry included.
    pub emitters: u32,
    /// Object-space vertex positions and triangle indices of every mesh (the `MeshRange`s index
    /// them as they do the GPU buffers): what the compute BVH is built from on the host.
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    pub vertex_buffer: Option<Buffer>,
    pub index_buffer: Option<Buffer>,
    pub aabb_buffer: Option<Buffer>,
    /// The tables the kernels reach through the frame constants, with what is needed to tell
    /// whether an edited scene changes them (see `update.rs`).
    tables: update::Tables,
    /// A digest of what an update does not upload again (texture pixels, vertex attributes).
    fixed_data: [u64; 2],
}

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}
/// Writes `cam` into the frame constants of a scene uploaded relative to `origin` (in double
/// precision: the camera may have moved since the upload).
pub fn set_camera(frame: &mut Frame, cam: &crate::scene::Camera, origin: DVec3) {
    let forward = (cam.look_at - cam.position).normalize();
    let right_dir = forward.cross(cam.up).normalize();
    let up_dir = right_dir.cross(forward);
    let tan_half = (cam.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = f64::from(cam.width) / f64::from(cam.height);
    frame.cam_forward = v4(forward, 0.0);
    frame.cam_right = v4(right_dir * tan_half * aspect, 0.0);
    frame.cam_up = v4(up_dir * tan_half, 0.0);
    frame.cam_origin = v4(cam.position - origin, 0.0);
    frame.width = cam.width;
    frame.height = cam.height;
}

/// The scene encoded for the device, on the host: what `GpuScene::new` uploads, and what
/// `GpuScene::update` compares with what it uploaded.
pub(crate) struct Host {
    features: u32,
    vertices: Vec<GpuVertex>,
    positions: Vec<Vec3>,
    indices: Vec<u32>,
    meshes: Vec<MeshRange>,
    gpu_instances: Vec<GpuInstance>,
    instances: Vec<(u32, [[f32; 4]; 3])>,
    shapes: Vec<GpuShape>,
    shape_masks: Vec<u32>,
    aabbs: Vec<[f32; 6]>,
    lights: Vec<GpuLight>,
    materials: Vec<GpuMaterial>,
    textures: Vec<GpuTexture>,
    dark_lights: Vec<String>,
    dome: u32,
    light_bvh: lights::LightBvh,
    /// The light tree that light samples descend when there are too many lights to loop over.
    light_tree: Option<light_tree::LightTree>,
    dome_table: Option<dome::DomeTable>,
}

impl GpuScene {
    pub fn new(ctx: &Context, scene: &Scene, ray_query: bool) -> Result<GpuScene> {
        let origin = scene.camera.position;
        let h = encode_scene(scene, origin, true)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let build_input = if ray_query {
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
        } else {
            vk::BufferUsageFlags::empty()
        };
        let upload = |name: &str, data: &[u8], usage| -> Result<Option<Buffer>> {
            if data.is_empty() {
                return Ok(None);
            }
            Ok(Some(ctx.upload(name, data, usage)?))
        };
        let vertex_buffer = upload(
            "vertices",
            bytemuck::cast_slice(&h.vertices),
            storage | build_input,
        )?;
        let index_buffer = upload(
            "indices",
            bytemuck::cast_slice(&h.indices),
            storage | build_input,
        )?;
        let aabb_buffer = upload(
            "shape AABBs",
            bytemuck::cast_slice(&h.aabbs),
            storage | build_input,
        )?;
        let tables = update::Tables::upload(ctx, &h, scene)?;
        let fixed_data = update::fixed_data(scene);
        let mut frame = Frame::default();
        tables.write_frame(&mut frame, &h);
        let addr = |b: &Option<Buffer>| b.as_ref().map_or(0, |b| b.address);
        frame.vertices = addr(&vertex_buffer);
        frame.indices = addr(&index_buffer);
        set_camera(&mut frame, &scene.camera, origin);
        Ok(GpuScene {
            frame,
            flat_kinds: flat_kinds(h.features, &h.shapes),
            features: h.features,
            meshes: h.meshes,
            instances: h.instances,
            shapes: h.shapes,
            shape_masks: h.shape_masks,
            shape_boxes: h.aabbs,
            origin,
            dark_lights: h.dark_lights,
            emitters: h.lights.len() as u32,
            positions: h.positions,
            indices: h.indices,
            vertex_buffer,
            index_buffer,
            aabb_buffer,
            tables,
            fixed_data,
        })
    }
}

/// SPEC_FLAT_KINDS of a scene with these features and shapes: shape i's kind + 1 in bits 2i and
/// 2i + 1 where the scene is traced flat, else 0.
pub fn flat_kinds(features: u32, shapes: &[GpuShape]) -> u32 {
    if features & FEATURE_FLAT_SHAPES == 0 {
        return 0;
    }
    shapes
        .iter()
        .take(BVH_FLAT_MAX as usize)
        .enumerate()
        .fold(0, |k, (i, s)| k | ((s.kind + 1) & 3) << (2 * i))
}
