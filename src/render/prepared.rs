//! A scene prepared for rendering: its buffers uploaded and its trace structure built, once, for
//! any number of renders (other settings, seeds, sample ranges, a moved camera).

use super::Renderer;
use super::integrator::IntegratorPasses;
use crate::error::Result;
use crate::gpu_scene::{GpuScene, SceneUpdate};
use crate::scene::{Camera, Scene};
use crate::trace::{BuildStats, TraceMode, TraceStructure};
use std::sync::Mutex;
use std::time::Instant;

pub struct PreparedScene {
    pub(super) gpu: GpuScene,
    pub(super) trace: TraceStructure,
    /// The camera the scene was prepared with: device positions are relative to its position.
    pub camera: Camera,
    /// Wall time of the upload and of the trace structure's build.
    pub upload_seconds: f64,
    pub build: BuildStats,
    /// The largest diffuse albedo of any material (textures included): how fast indirect
    /// diffuse light converges over bounces, and whether any can exist.
    pub max_albedo: f32,
    /// Diagonal of the scene's geometry bounds (scene units): the scale of cache cells.
    pub extent: f32,
    /// Kernels of the integrators that rendered it, by name and the settings' feature bits
    /// (Integrator::features): pipelines are created once.
    kernels: Mutex<Vec<KeptKernels>>,
}

/// An integrator's kernels kept by a prepared scene: (name, feature bits, kernels).
type KeptKernels = (&'static str, u32, Box<dyn IntegratorPasses>);

impl PreparedScene {
    /// The kernels of integrator `name` with feature bits `features` created by an earlier
    /// render, if any.
    pub(super) fn take_kernels(
        &self,
        name: &str,
        features: u32,
    ) -> Option<Box<dyn IntegratorPasses>> {
        let mut k = self.kernels.lock().unwrap_or_else(|e| e.into_inner());
        let at = k
            .iter()
            .position(|(n, f, _)| *n == name && *f == features)?;
        Some(k.swap_remove(at).2)
    }

    pub(super) fn keep_kernels(
        &self,
        name: &'static str,
        features: u32,
        kernels: Box<dyn IntegratorPasses>,
    ) {
        self.kernels
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((name, features, kernels));
    }

    /// Brings the prepared scene to `scene`, an edit of the one it was prepared from, without
    /// preparing it again: edited materials and lights rewrite their tables only, moved instances
    /// also rebuild the trace structure's top level (never a bottom level), and a moved camera
    /// changes nothing here (each render writes its frame constants). Geometry, the set of lights
    /// that emit and textures (sizes and pixels) cannot change this way, nor mesh normals, uvs and
    /// tangents: the error names what changed.
    pub fn update(&mut self, ctx: &crate::vk::Context, scene: &Scene) -> Result<SceneUpdate> {
        let t0 = Instant::now();
        let mut u = self.gpu.update(ctx, scene)?;
        if u.instances_moved {
            self.trace.update_top(ctx, &self.gpu)?;
        }
        u.seconds = t0.elapsed().as_secs_f64();
        Ok(u)
    }

    /// The trace path the structure was built for ("rayquery" or "bvh").
    /// Lights rendered, emissive shapes and triangles included.
    pub fn emitters(&self) -> u32 {
        self.gpu.emitters
    }

    pub fn trace_name(&self) -> &'static str {
        self.trace.name()
    }
}

impl Renderer {
    /// Uploads `scene` and builds its trace structure for the trace path `trace` resolves to.
    pub fn prepare(&self, scene: &Scene, trace: TraceMode) -> Result<PreparedScene> {
        let ctx = self.context();
        let t0 = Instant::now();
        let mode = trace.resolve(ctx)?;
        let gpu = GpuScene::new(ctx, scene, mode == TraceMode::RayQuery)?;
        let upload_seconds = t0.elapsed().as_secs_f64();
        let trace = TraceStructure::build(ctx, &gpu, mode)?;
        Ok(PreparedScene {
            max_albedo: max_albedo(scene),
            extent: extent(&gpu),
            build: trace.build_stats().clone(),
            gpu,
            trace,
            camera: scene.camera.clone(),
            upload_seconds,
            kernels: Mutex::new(Vec::new()),
        })
    }
}

fn max_albedo(scene: &Scene) -> f32 {
    let texture_max = |t: Option<u32>| {
        t.map_or(1.0, |t| {
            scene.textures[t as usize]
                .texels
                .iter()
                .map(|v| v.x.max(v.y).max(v.z))
                .fold(0.0f32, f32::max)
        })
    };
    scene
        .materials
        .iter()
        .map(|m| {
            let base = match &m.metallic_roughness {
                Some(mr) => mr.base_color.max_element(),
                None => m.diffuse.max_element(),
            };
            base * texture_max(m.diffuse_texture)
        })
        .fold(0.0f32, f32::max)
}

fn extent(gpu: &GpuScene) -> f32 {
    let (mut lo, mut hi) = (
        glam::Vec3::splat(f32::INFINITY),
        glam::Vec3::splat(f32::NEG_INFINITY),
    );
    for b in &gpu.shape_boxes {
        lo = lo.min(glam::Vec3::new(b[0], b[1], b[2]));
        hi = hi.max(glam::Vec3::new(b[3], b[4], b[5]));
    }
    for (mesh, rows) in &gpu.instances {
        let r = gpu.meshes[*mesh as usize];
        let first = r.first_vertex as usize;
        for p in &gpu.positions[first..first + r.vertex_count as usize] {
            let w = glam::Vec3::from_array(std::array::from_fn(|i| {
                rows[i][0] * p.x + rows[i][1] * p.y + rows[i][2] * p.z + rows[i][3]
            }));
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    let d = (hi - lo).length();
    if d.is_finite() { d } else { 1.0 }
}
