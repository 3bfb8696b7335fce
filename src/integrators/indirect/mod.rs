//! Indirect lighting (docs/techniques.md, "Indirect lighting: the three integrators"): the seed's
//! split into direct lighting, indirect diffuse through the radiosity cache and the reflection
//! integrator (`full`, glsl/indirect/full.comp), and a brute-force path tracer to check it against
//! (`path`, glsl/indirect/path.comp). Both light their camera hits exactly as the direct integrator
//! does and add the AOV planes Direct, IndirectDiffuse and Reflection, whose sum is the beauty.

mod radiosity;

use super::direct::DirectLighting;
use crate::error::Result;
use crate::layout::*;
use crate::render::film_kernel::{FilmKernel, tile_groups};
use crate::render::{Integrator, IntegratorPasses, Params, PreparedScene, Schedule};
use crate::shaders;
use crate::vk::{Buffer, Context};
use ash::vk;
use radiosity::{CacheShape, RadiosityCache};
use std::cell::RefCell;

/// The AOV planes of both integrators, in the kernels' order.
pub const PLANES: &[&str] = &["Direct", "IndirectDiffuse", "Reflection"];

/// Spread angle (radians) of the cone a diffuse bounce starts: a cache cell read at distance t
/// is at most 0.15 t across, a ~9 degree blur of what the bounce integrates over its whole
/// hemisphere. Wider cones mix surfaces of a room in one cell (measured: 0.3 with two coarser
/// fallback levels biased the interior scene's ceiling 6% low).
const DIFFUSE_SPREAD: f32 = 0.15;

/// The brute-force path tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Path {
    pub lighting: DirectLighting,
    /// The most path segments, as Mitsuba's `max_depth` (1: emission seen directly, 2: direct
    /// lighting); -1: unbounded (Russian roulette ends paths).
    pub max_depth: i32,
}

impl Default for Path {
    fn default() -> Self {
        Path {
            lighting: DirectLighting::default(),
            max_depth: -1,
        }
    }
}

impl Path {
    pub const PARAMS: &[&str] = &["max_depth"];

    pub fn parse(p: &Params) -> std::result::Result<Path, String> {
        let d = Path::default();
        let it = Path {
            lighting: DirectLighting::parse(p)?,
            max_depth: p.get("max_depth", d.max_depth)?,
        };
        it.check()?;
        p.finish("path", &[Path::PARAMS, DirectLighting::PARAMS].concat())?;
        Ok(it)
    }
}

impl Integrator for Path {
    fn name(&self) -> &'static str {
        "path"
    }

    fn aov_planes(&self) -> &'static [&'static str] {
        PLANES
    }

    fn check(&self) -> std::result::Result<(), String> {
        if self.max_depth == 0 || self.max_depth < -1 {
            return Err(format!(
                "--max-depth counts path segments: -1 (unbounded) or at least 1, got {}",
                self.max_depth
            ));
        }
        self.lighting.check()
    }

    fn configure(&self, frame: &mut Frame) {
        self.lighting.configure(frame);
        frame.max_depth = u32::try_from(self.max_depth).unwrap_or(NONE);
        frame.diffuse_spread = DIFFUSE_SPREAD;
    }

    fn features(&self) -> u32 {
        self.lighting.kernel_features()
    }

    fn identity(&self) -> String {
        self.lighting
            .identity("path", &format!("max_depth={} ", self.max_depth))
    }

    fn header(&self) -> Vec<(String, String)> {
        self.lighting.header()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        Ok(Box::new(PathKernel(FilmKernel::new(
            ctx,
            scene,
            self.lighting.kernel_features(),
            "path",
            (shaders::PATH_RQ, shaders::PATH_BVH),
            true,
            std::mem::size_of::<PassConstants>(),
        )?)))
    }
}

struct PathKernel(FilmKernel);

impl IntegratorPasses for PathKernel {
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        self.0.bind(frame, film, aovs);
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        self.0.dispatch_tile(cmd, pass);
    }
}

/// Direct lighting, indirect diffuse through the radiosity cache, and reflections.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Full {
    pub lighting: DirectLighting,
    /// The most specular bounces of the reflection integrator.
    pub specular_depth: u32,
    /// Indirect diffuse through the radiosity cache (false: by brute force, the same partition
    /// without the cache, to measure its bias and gain).
    pub radiosity_cache: bool,
    /// New cache generations during the render, at samples 1, 2, 4, … (false: the warm-up's
    /// table serves every sample, as in a render session; src/render/session.rs).
    pub radiosity_refresh: bool,
    /// The diffuse chain also goes on through the specular lobes it meets, so that light that
    /// reaches a diffuse surface through glossy or specular ones (L S+ D ...) is kept (false: the
    /// course's split, which leaves it out).
    pub caustics: bool,
}

impl Default for Full {
    fn default() -> Self {
        Full {
            lighting: DirectLighting::default(),
            specular_depth: 4,
            radiosity_cache: true,
            radiosity_refresh: true,
            caustics: true,
        }
    }
}

impl Full {
    pub const PARAMS: &[&str] = &[
        "specular_depth",
        "radiosity_cache",
        "radiosity_refresh",
        "caustics",
    ];

    pub fn parse(p: &Params) -> std::result::Result<Full, String> {
        let d = Full::default();
        let it = Full {
            lighting: DirectLighting::parse(p)?,
            specular_depth: p.get("specular_depth", d.specular_depth)?,
            radiosity_cache: p.get_switch("radiosity_cache", d.radiosity_cache)?,
            radiosity_refresh: p.get_switch("radiosity_refresh", d.radiosity_refresh)?,
            caustics: p.get_switch("caustics", d.caustics)?,
        };
        it.check()?;
        p.finish("full", &[Full::PARAMS, DirectLighting::PARAMS].concat())?;
        Ok(it)
    }
}

impl Integrator for Full {
    fn name(&self) -> &'static str {
        "full"
    }

    fn aov_planes(&self) -> &'static [&'static str] {
        PLANES
    }

    fn check(&self) -> std::result::Result<(), String> {
        if self.specular_depth > 64 {
            return Err(format!(
                "--specular-depth must be in 0..=64, got {}",
                self.specular_depth
            ));
        }
        self.lighting.check()
    }

    fn configure(&self, frame: &mut Frame) {
        self.lighting.configure(frame);
        frame.specular_depth = self.specular_depth;
        frame.diffuse_spread = DIFFUSE_SPREAD;
        if self.caustics {
            frame.integrator_flags |= INTEGRATOR_CAUSTICS;
        }
    }

    fn features(&self) -> u32 {
        self.lighting.kernel_features()
    }

    fn identity(&self) -> String {
        let own = format!(
            "specular_depth={} radiosity_cache={} {}",
            self.specular_depth,
            if self.radiosity_cache { "on" } else { "off" },
            // Named only when off, so that parts of earlier versions keep their text.
            if self.radiosity_refresh {
                ""
            } else {
                "radiosity_refresh=off "
            },
        ) + if self.caustics {
            // Always named: parts of earlier versions, which left this light out, do not merge.
            "caustics=on "
        } else {
            "caustics=off "
        };
        self.lighting.identity("full", &own)
    }

    fn header(&self) -> Vec<(String, String)> {
        self.lighting.header()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        // One kernel for the film pass and the cache's update pass (glsl/indirect/full.comp).
        let kernel = FilmKernel::new(
            ctx,
            scene,
            self.lighting.kernel_features(),
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
    kernel: FilmKernel,
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
        integrator: &dyn Integrator,
        schedule: Schedule,
    ) -> Result<()> {
        let full = integrator
            .as_any()
            .downcast_ref::<Full>()
            .expect("the full integrator's kernels run for it");
        // Leave the cache out where nothing could read it: no diffuse material or no light.
        let reason = if !full.radiosity_cache {
            "off (--radiosity-cache off: brute force)"
        } else if !(scene.max_albedo > 0.0 && scene.emitters() > 0) {
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
        // Recorded passes cannot refresh the cache (src/render/session.rs).
        c.set_refresh(full.radiosity_refresh && schedule == Schedule::Progressive);
        c.reset();
        Ok(())
    }

    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        self.kernel.bind(frame, film, aovs);
    }

    fn stateful(&self) -> bool {
        self.off_reason.borrow().is_empty() && self.cache.borrow().is_some()
    }

    fn begin(&self, ctx: &Context, seed: u64, first: u32, count: u32) -> Result<u32> {
        match self.cache.borrow().as_ref() {
            // The update pass runs in the kernel bound to this render's buffers (bind comes
            // first): it reads the frame constants, none of the film (its FullPass carries no
            // film address).
            Some(c) if self.off_reason.borrow().is_empty() => {
                c.begin(ctx, &self.kernel.pipeline, seed, first, count)
            }
            _ => Ok(count),
        }
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        let push = FullPass {
            film: self.kernel.pass(pass),
            mode: FULL_PASS_FILM,
            ..Default::default()
        };
        self.kernel
            .pipeline
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
