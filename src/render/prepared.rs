//! A scene prepared for rendering: its buffers uploaded and its trace structure built, once, for
//! any number of renders (other settings, seeds, sample ranges, a moved camera).

use super::Renderer;
use crate::error::Result;
use crate::gpu_scene::GpuScene;
use crate::scene::{Camera, Scene};
use crate::trace::{BuildStats, TraceMode, TraceStructure};
use std::time::Instant;

pub struct PreparedScene {
    pub(super) gpu: GpuScene,
    pub(super) trace: TraceStructure,
    /// The camera the scene was prepared with: device positions are relative to its position.
    pub camera: Camera,
    /// Wall time of the upload and of the trace structure's build.
    pub upload_seconds: f64,
    pub build: BuildStats,
}

impl PreparedScene {
    /// The trace path the structure was built for ("rayquery" or "bvh").
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
            build: trace.build_stats().clone(),
            gpu,
            trace,
            camera: scene.camera.clone(),
            upload_seconds,
        })
    }
}
