//! The seam between the driver (src/render/mod.rs: budget, passes, tiles, film blocks, progress,
//! cancel, evaluation) and the integrators, which turn camera samples into film sums. The driver
//! knows no integrator: it asks [`select`] for the one the settings name, lets it write its frame
//! constants and create its kernels, and has it record each dispatch. Adding an integrator is its
//! own module plus one line in [`select`].

use super::{PreparedScene, RenderSettings};
use crate::error::Result;
use crate::layout::{Frame, PassConstants};
use crate::vk::{Buffer, Context};
use ash::vk;

pub trait Integrator {
    /// Its name, for messages and headers.
    fn name(&self) -> &'static str;
    /// Writes its settings into the frame constants.
    fn configure(&self, frame: &mut Frame);
    /// The RGB planes it adds to the film besides FilmPixel's (e.g. `["Direct",
    /// "IndirectDiffuse"]`), each a layer `<Name>.R/G/B` of the final EXR holding the per-pixel
    /// mean over all samples; names as `film::check_aov_names` wants. With P > 0 planes the
    /// driver gives the kernels an "aovs" buffer at BINDING_AOVS (glsl/shared/layout.glsl) of
    /// pixels x P vec4 sums, plane k of pixel p at `aovs[p * P + k]` (.rgb: sums; .w unused),
    /// cleared and moved off the device with the film, and merged as exactly.
    fn aov_planes(&self) -> &'static [&'static str] {
        &[]
    }
    /// Creates its kernels for `scene`, bound to the frame constants, the film and, when it
    /// declares AOV planes, their buffer (None when it declares none).
    fn kernels(
        &self,
        ctx: &Context,
        scene: &PreparedScene,
        frame: &Buffer,
        film: &Buffer,
        aovs: Option<&Buffer>,
    ) -> Result<Box<dyn IntegratorPasses>>;
}

/// An integrator's kernels. A prepared scene keeps them between renders; each render binds its
/// own frame constants and film first.
pub trait IntegratorPasses {
    /// Points the kernels at a render's frame constants, film and AOV planes' buffer (None when
    /// the integrator declares no planes).
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>);
    /// Records what adds samples [first_sample, first_sample + sample_count) of the pixels in
    /// `pass.tile` to the film (dispatches and the barriers between them).
    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants);
}

/// The integrator `settings` ask for.
pub fn select(settings: &RenderSettings) -> Box<dyn Integrator> {
    Box::new(super::direct::Direct(settings.integrator))
}
