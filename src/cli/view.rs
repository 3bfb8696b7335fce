//! `illum view`: the interactive window (src/view/), with render's scene, integrator and
//! sampling options.

use super::fast_start;
use super::{DeviceArgs, IntegratorArgs, SceneArgs, check_outputs, signal};
use crate::output::{image_metadata, write_exr};
use crate::render::RenderSettings;
use crate::render::Renderer;
use crate::scene::Scene;
use crate::view::{Source, ViewOptions};
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Samples per pixel to converge to; the image then stays as it is until the camera or the
    /// scene changes.
    #[arg(long, default_value_t = 1024)]
    pub spp: u32,
    /// Seed of the per-sample random streams (as `illum render --seed`).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub gpu: DeviceArgs,
    /// Direct lighting by BRDF sampling (brdf), light sampling (light), or both with MIS (mis).
    #[arg(long, value_name = "TECHNIQUE")]
    pub technique: Option<String>,
    #[command(flatten)]
    pub integrator: IntegratorArgs,
    /// Firefly clamp, as `illum render --clamp`.
    #[arg(long)]
    pub clamp: Option<f32>,
    /// Where the S key saves the image so far: an EXR with every plane and render's header.
    #[arg(short, long, default_value = "view.exr")]
    pub output: PathBuf,
    /// Exposure of the displayed image in stops (+/- change it, 0 resets it).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Window pixels per image pixel. [default: the largest that keeps the window within
    /// 1024x800]
    #[arg(long)]
    pub scale: Option<u32>,
    /// Start with the denoised preview on (D toggles it).
    #[arg(long)]
    pub denoise: bool,
    /// Quit after this many frames (for scripts and tests).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// At exit, write the last frame as the window showed it, status bar included (PNG).
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// At exit (the window closed, Q, a signal or --frames), also save the image as S does.
    #[arg(long)]
    pub save_at_exit: bool,
    /// Enable the Vulkan validation layers (also on with ILLUM_VALIDATION=1).
    #[arg(long)]
    pub validate: bool,
}

impl Source for ViewArgs {
    fn load(&self) -> Result<Scene> {
        self.scene.load()
    }

    fn settings(&self, scene: &Scene) -> Result<RenderSettings> {
        Ok(RenderSettings {
            integrator: self
                .integrator
                .integrator(scene, self.technique.as_deref())?,
            spp: self.spp,
            seed: self.seed,
            trace: self.gpu.trace,
            clamp: self.clamp,
            ..Default::default()
        })
    }
}

pub fn run(a: &ViewArgs) -> Result<()> {
    let cpu_at_start = fast_start::CpuTimes::now();
    let mode = fast_start::mode()?;
    if let Some(dir) = fast_start::staging() {
        return first_image(a, &dir);
    }
    if let Some(p) = &a.screenshot
        && !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!(
            "--screenshot {}: the screenshot is a PNG; name a .png file",
            p.display()
        );
    }
    if !a
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        bail!(
            "-o {}: the view saves an EXR; name a .exr file",
            a.output.display()
        );
    }
    let outputs = super::named([
        ("image", Some(a.output.as_path())),
        ("screenshot", a.screenshot.as_deref()),
    ]);
    check_outputs(
        &outputs,
        &super::named([("scene", a.scene.scene.as_deref())]),
    )?;
    let scene_file = a.scene.scene.clone();
    let opts = ViewOptions {
        title: format!("illum view: {}", a.scene.name()),
        watch: a.scene.scene.clone(),
        device: a.gpu.device.clone(),
        validation: a.validate,
        frames: a.frames,
        screenshot: a.screenshot.clone(),
        output: a.output.clone(),
        save_at_exit: a.save_at_exit,
        scale: a.scale,
        exposure: a.exposure,
        denoise: a.denoise,
        cancel: signal::install(),
        early_image: Some(Box::new(move |ctx: &Context, [w, h]: [u32; 2]| {
            let key = fast_start::warm_key(ctx, scene_file.as_deref());
            fast_start::FirstView::start(mode, cpu_at_start, (ctx, key), (w, h))
                .map(|f| Box::new(f) as Box<dyn crate::view::EarlyImage>)
        })),
    };
    crate::view::run(&opts, a)
}

/// The second process of the view's fast start (src/cli/fast_start/): the view's first image,
/// one sample a pixel of its scene and settings, written to `dir` for the view to show while it
/// compiles its own kernels.
fn first_image(a: &ViewArgs, dir: &Path) -> Result<()> {
    let scene = a.load()?;
    let settings = RenderSettings {
        spp: 1,
        ..a.settings(&scene)?
    };
    let ctx = Context::new(&ContextOptions {
        device: a.gpu.device.clone(),
        validation: a.validate,
        ..Default::default()
    })?;
    let out = Renderer::new(ctx.clone()).render(&scene, &settings, &mut |_, _| {})?;
    let meta = image_metadata(&out, &settings, &ctx.info().name);
    write_exr(&fast_start::first_view_image(dir), &out.film, &meta)?;
    super::check_validation(&ctx)
}
