//! The seam between the driver (src/render/driver.rs: set-up and tiles; blocking.rs: budget,
//! passes, film blocks, progress, cancel, evaluation) and the integrators (src/integrators), which turn camera samples
//! into film sums. The driver knows no integrator: the settings hold one, which writes its frame
//! constants, creates its kernels and has them record each dispatch.

use super::PreparedScene;
use crate::error::Result;
use crate::layout::{Frame, PassConstants};
use crate::vk::{Buffer, Context};
use ash::vk;

/// How the render drives an integrator's own state (e.g. a cache) between dispatches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    /// The blocking render: the state may change between dispatches ([`IntegratorPasses::begin`]).
    Progressive,
    /// Passes recorded into a host's command buffers: the state stays as it was when set up.
    Fixed,
}

/// An integrator with its parameters: what a render's settings hold. Each integrator parses its
/// own parameters (`crate::integrators` keeps the table of them).
pub trait Integrator: Send + Sync + std::fmt::Debug {
    /// Its name, for messages and headers, and the key under which a prepared scene keeps its
    /// kernels.
    fn name(&self) -> &'static str;
    /// The AOV planes its kernels add to the film (RGB each, at BINDING_AOVS in this order).
    fn aov_planes(&self) -> &'static [&'static str] {
        &[]
    }
    /// Checks its parameters (a message naming the one that is wrong).
    fn check(&self) -> std::result::Result<(), String>;
    /// Writes its settings into the frame constants.
    fn configure(&self, frame: &mut Frame);
    /// Feature bits its settings add to the scene's (FEATURE_SHADOW_*); a prepared scene keeps
    /// kernels per name and these bits.
    fn features(&self) -> u32 {
        0
    }
    /// Creates its kernels (and the buffers they own) for `scene`.
    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>>;
    /// Every parameter that changes its samples, as text: jobs of one image must agree on it.
    fn identity(&self) -> String;
    /// Its parameters for an image's header: (name, value).
    fn header(&self) -> Vec<(String, String)>;
    /// Itself, for its kernels to read its parameters.
    fn as_any(&self) -> &dyn std::any::Any;
    /// Whether its direct-lighting counts are to be measured by a pilot before it renders
    /// (src/render/allocation/), starting from the counts its `configure` writes.
    fn measured_allocation(&self) -> bool {
        false
    }
}

/// An integrator's kernels. A prepared scene keeps them between renders; each render configures
/// and binds them first.
pub trait IntegratorPasses: Send {
    /// Writes what the kernels own (e.g. a cache's address) into a render's frame constants;
    /// `integrator` is the one that created them, with this render's parameters.
    fn configure(
        &self,
        _ctx: &Context,
        _scene: &PreparedScene,
        _frame: &mut Frame,
        _integrator: &dyn Integrator,
        _schedule: Schedule,
    ) -> Result<()> {
        Ok(())
    }
    /// Points the kernels at a render's frame constants, film and AOV planes.
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>);
    /// Whether the kernels keep state that [`IntegratorPasses::begin`] brings up to date (a
    /// cache to warm up before the first pass).
    fn stateful(&self) -> bool {
        false
    }
    /// Called before samples [first, first + count) of every pixel are recorded with `seed`:
    /// brings the integrator's own state (e.g. a cache generation) to what those samples see and
    /// returns how many of them one dispatch may take (at least 1) while it stays fixed.
    fn begin(&self, _ctx: &Context, _seed: u64, _first: u32, count: u32) -> Result<u32> {
        Ok(count)
    }
    /// Records what adds samples [first_sample, first_sample + sample_count) of the pixels in
    /// `pass.tile` to the film (dispatches and the barriers between them). The driver records
    /// the tiles of the same samples one after the other into one command buffer with no barrier
    /// between them, so that the device may run them at once: what one tile's dispatches write
    /// must be its own pixels' film and AOVs only.
    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants);
    /// Figures about the last render for headers and summaries: (name, value).
    fn report(&self) -> Vec<(String, String)> {
        Vec::new()
    }
}
