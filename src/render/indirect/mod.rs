//! Indirect lighting (docs/techniques.md, "Indirect lighting: the three integrators"): the seed's
//! split into direct lighting, indirect diffuse through the radiosity cache and the reflection
//! integrator (`full`, glsl/indirect/full.comp), and a brute-force path tracer to check it against
//! (`path`, glsl/indirect/path.comp). Both light their camera hits exactly as the direct integrator
//! does and add the AOV planes Direct, IndirectDiffuse and Reflection, whose sum is the beauty.

mod radiosity;

use super::direct::{bind_film, configure_direct, dispatch_tile, film_pipeline, tile_groups};
use super::integrator::{Integrator, IntegratorPasses};
use super::{IntegratorSettings, PreparedScene, RenderSettings};
use crate::error::Result;
use crate::layout::*;
use crate::shaders;
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;
use radiosity::{CacheShape, RadiosityCache};
use std::cell::RefCell;

/// The AOV planes of both integrators, in the kernels' order.
const PLANES: &[&str] = &["Direct", "IndirectDiffuse", "Reflection"];

/// Spread angle (radians) of the cone a diffuse bounce starts: a cache cell read at distance t
/// is at most 0.15 t across, a ~9 degree blur of what the bounce integrates over its whole
/// hemisphere. Wider cones mix surfaces of a room in one cell (measured: 0.3 with two coarser
/// fallback levels biased the interior scene's ceiling 6% low).
const DIFFUSE_SPREAD: f32 = 0.15;

/// The brute-force path tracer.
pub struct Path(pub IntegratorSettings);

impl Integrator for Path {
    fn name(&self) -> &'static str {
        "path"
    }

    fn aov_planes(&self) -> &'static [&'static str] {
        PLANES
    }

    fn configure(&self, frame: &mut Frame) {
        configure_direct(&self.0, frame);
        frame.max_depth = u32::try_from(self.0.max_depth).unwrap_or(NONE);
        frame.diffuse_spread = DIFFUSE_SPREAD;
    }

    fn features(&self) -> u32 {
        self.0.kernel_features()
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        Ok(Box::new(FilmKernel(film_pipeline(
            ctx,
            scene,
            self.0.kernel_features(),
            "path",
            (shaders::PATH_RQ, shaders::PATH_BVH),
            true,
            std::mem::size_of::<PassConstants>(),
        )?)))
    }
}

struct FilmKernel(ComputePipeline);

impl IntegratorPasses for FilmKernel {
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        bind_film(&self.0, frame, film, aovs);
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        dispatch_tile(&self.0, cmd, pass);
    }
}

/// Direct lighting, indirect diffuse through the radiosity cache, and reflections.
pub struct Full(pub IntegratorSettings);

impl Integrator for Full {
    fn name(&self) -> &'static str {
        "full"
    }

    fn aov_planes(&self) -> &'static [&'static str] {
        PLANES
    }

    fn configure(&self, frame: &mut Frame) {
        configure_direct(&self.0, frame);
        frame.specular_depth = self.0.specular_depth;
        frame.diffuse_spread = DIFFUSE_SPREAD;
    }

    fn features(&self) -> u32 {
        self.0.kernel_features()
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        // One kernel for the film pass and the cache's update pass (glsl/indirect/full.comp).
        let kernel = film_pipeline(
            ctx,
            scene,
            self.0.kernel_features(),
            "full",
            (shaders::FULL_RQ, shaders::FULL_BVH),
            true,
            std::mem::size_of::<FullPass>(),
        )?;
        Ok(Box::new(FullKernels {
            kernel,
            cache: RefCell::new(None),
            off_reason: RefCell::new(String::new()),
        }))
    }
}

struct FullKernels {
    /// Runs both passes: FullPass.mode chooses.
    kernel: ComputePipeline,
    /// Created by the first render that uses a cache.
    cache: RefCell<Option<RadiosityCache>>,
    /// Why the last render had no cache ("" when it had one).
    off_reason: RefCell<String>,
}

impl IntegratorPasses for FullKernels {
    fn configure(
        &self,
        ctx: &Context,
        scene: &PreparedScene,
        frame: &mut Frame,
        settings: &RenderSettings,
    ) -> Result<()> {
        // Leave the cache out where nothing could read it: no diffuse material or no light.
        let reason = if !settings.integrator.radiosity_cache {
            "off (--radiosity-cache off: brute force)"
        } else if !(scene.max_albedo > 0.0 && scene.gpu.emitters > 0) {
            "off (no diffuse material or no light: nothing to cache)"
        } else {
            ""
        };
        *self.off_reason.borrow_mut() = reason.to_string();
        frame.radiosity_table = 0;
        // Cells from 2^-14 of the scene's size up to 32 times it.
        frame.radiosity_cell = (scene.extent * f32::powi(2.0, -14)).max(1e-30);
        frame.radiosity_levels = 20;
        if !reason.is_empty() {
            return Ok(());
        }
        let shape = CacheShape::new(frame.width, frame.height, scene.max_albedo);
        let mut cache = self.cache.borrow_mut();
        if cache.as_ref().is_none_or(|c| c.shape != shape) {
            *cache = Some(RadiosityCache::new(ctx, shape)?);
        }
        let c = cache.as_ref().expect("created above");
        c.configure(frame);
        c.set_refresh(settings.integrator.radiosity_refresh);
        c.reset();
        Ok(())
    }

    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        bind_film(&self.kernel, frame, film, aovs);
    }

    fn begin(&self, ctx: &Context, seed: u64, first: u32, count: u32) -> Result<u32> {
        match self.cache.borrow().as_ref() {
            // The update pass runs in the kernel bound to this render's buffers (bind comes
            // first): it reads none of the film's, but the descriptors must be valid.
            Some(c) if self.off_reason.borrow().is_empty() => {
                c.begin(ctx, &self.kernel, seed, first, count)
            }
            _ => Ok(count),
        }
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        let push = FullPass {
            film: *pass,
            mode: FULL_PASS_FILM,
            ..Default::default()
        };
        self.kernel
            .dispatch(cmd, bytemuck::bytes_of(&push), tile_groups(pass.tile));
    }

    fn report(&self) -> Vec<(String, String)> {
        let reason = self.off_reason.borrow();
        if !reason.is_empty() {
            return vec![("radiosityCache".into(), reason.clone())];
        }
        self.cache
            .borrow()
            .as_ref()
            .map(RadiosityCache::report)
            .unwrap_or_default()
    }
}
