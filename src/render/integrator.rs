//! The seam between the driver (src/render/mod.rs: budget, passes, tiles, film blocks, progress,
//! cancel, evaluation) and the integrators, which turn camera samples into film sums. The driver
//! knows no integrator: it asks [`select`] for the one the settings name, lets it write its frame
//! constants and create its kernels, and has it record each dispatch. Adding an integrator is its
//! own module plus one line in [`select`].

use super::{IntegratorKind, PreparedScene, RenderSettings};
use crate::error::Result;
use crate::layout::{Frame, PassConstants};
use crate::vk::{Buffer, Context};
use ash::vk;

pub trait Integrator {
    /// Its name, for messages and headers, and the key under which a prepared scene keeps its
    /// kernels.
    fn name(&self) -> &'static str;
    /// The AOV planes its kernels add to the film (RGB each, at BINDING_AOVS in this order).
    fn aov_planes(&self) -> &'static [&'static str] {
        &[]
    }
    /// Writes its settings into the frame constants.
    fn configure(&self, frame: &mut Frame);
    /// Feature bits its settings add to the scene's (FEATURE_SHADOW_*); a prepared scene keeps
    /// kernels per name and these bits.
    fn features(&self) -> u32 {
        0
    }
    /// Creates its kernels (and the buffers they own) for `scene`.
    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>>;
}

/// An integrator's kernels. A prepared scene keeps them between renders; each render configures
/// and binds them first.
pub trait IntegratorPasses {
    /// Writes what the kernels own (e.g. a cache's address) into a render's frame constants.
    fn configure(
        &self,
        _ctx: &Context,
        _scene: &PreparedScene,
        _frame: &mut Frame,
        _settings: &RenderSettings,
    ) -> Result<()> {
        Ok(())
    }
    /// Points the kernels at a render's frame constants, film and AOV planes.
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>);
    /// Called before samples [first, first + count) of every pixel are recorded with `seed`:
    /// brings the integrator's own state (e.g. a cache generation) to what those samples see and
    /// returns how many of them one dispatch may take (at least 1) while it stays fixed.
    fn begin(&self, _ctx: &Context, _seed: u64, _first: u32, count: u32) -> Result<u32> {
        Ok(count)
    }
    /// Records what adds samples [first_sample, first_sample + sample_count) of the pixels in
    /// `pass.tile` to the film (dispatches and the barriers between them).
    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants);
    /// Figures about the last render for headers and summaries: (name, value).
    fn report(&self) -> Vec<(String, String)> {
        Vec::new()
    }
}

/// The integrator `settings` ask for.
pub fn select(settings: &RenderSettings) -> Box<dyn Integrator> {
    let it = settings.integrator;
    match it.kind {
        IntegratorKind::Direct => Box::new(super::direct::Direct(it)),
        IntegratorKind::Full => Box::new(super::indirect::Full(it)),
        IntegratorKind::Path => Box::new(super::indirect::Path(it)),
    }
}
