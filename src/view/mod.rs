//! `illum view`: a window showing a render converge pass by pass, the camera under the mouse and
//! the scene file under watch (docs/view.md). It renders through [`Progressive`], the blocking
//! render's driver stepped a few samples a frame, so that what it saves after N samples is what
//! `illum render --spp N` writes, bit for bit; an edit of the scene goes through
//! [`crate::render::PreparedScene::update`] (only the tables that changed are rewritten), and a
//! bad edit leaves the last good scene rendering with the error in the status bar.

mod display;
mod early;
mod frames;
mod input;
mod orbit;
mod present;
mod text;
mod watch;

use crate::denoise::Denoiser;
use crate::output::SrgbEncoder;
use crate::render::{PreparedScene, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, anyhow, bail};
use input::App;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant, SystemTime};
use winit::event_loop::EventLoop;
use winit::platform::pump_events::{EventLoopExtPumpEvents, PumpStatus};

/// Where the scene comes from and how it renders: the command line's scene arguments and
/// render options, asked again after each edit of the file.
pub trait Source {
    /// Loads the scene (again, after an edit).
    fn load(&self) -> Result<Scene>;
    /// The render settings for it (integrator and its parameters, spp, seed, trace path).
    fn settings(&self, scene: &Scene) -> Result<RenderSettings>;
}

pub struct ViewOptions {
    /// The window's title.
    pub title: String,
    /// The scene file watched for edits, with the files it names (None: nothing to watch,
    /// e.g. the default scene).
    pub watch: Option<PathBuf>,
    pub device: Option<String>,
    pub validation: bool,
    /// Quit after this many frames (tests and scripts).
    pub frames: Option<u64>,
    /// At exit, write the last frame as the window showed it (PNG).
    pub screenshot: Option<PathBuf>,
    /// Where the S key saves the image (EXR, every plane, `illum render`'s header).
    pub output: PathBuf,
    /// Also save at exit.
    pub save_at_exit: bool,
    /// Window pixels per image pixel (None: the largest that keeps the window within 1024x800).
    pub scale: Option<u32>,
    /// Exposure of the displayed beauty, in stops.
    pub exposure: f32,
    /// Start with the denoised preview on.
    pub denoise: bool,
    /// Set by a signal: quit as if the window were closed (saving what `save_at_exit` asks).
    pub cancel: Arc<AtomicBool>,
    /// Starts an image that comes sooner than the view's own first frame, given the view's device
    /// and the image's size (the command line's fast start); None when there is none.
    #[allow(clippy::type_complexity)]
    pub early_image: Option<Box<dyn Fn(&Context, [u32; 2]) -> Option<Box<dyn EarlyImage>>>>,
}

/// An image of the scene at the view's size that can come before the view's own first frame
/// while its kernels compile (the command line's fast start: a second process renders one sample
/// a pixel with the driver's unoptimised kernels). Shown until the view's own frames come.
pub trait EarlyImage {
    /// Its linear RGB, once ready (then once only); None until then, or if it never comes.
    fn poll(&mut self) -> Option<Vec<[f32; 3]>>;
    /// Whether it can still come.
    fn pending(&mut self) -> bool;
    /// Whether the view should wait for it before its own first frame (tests).
    fn wait(&self) -> bool;
    /// What made it, for the status bar and the log.
    fn origin(&self) -> String;
    /// The view's own kernels have compiled.
    fn compiled(&mut self);
}

/// Rows of the status bar under the image.
const BAR_LINES: u32 = 2;
/// Seconds of rendering a frame aims at (the window answers the mouse between frames).
const FRAME_SECONDS: f64 = 1.0 / 30.0;

pub fn run(opts: &ViewOptions, source: &dyn Source) -> Result<()> {
    let started = Instant::now();
    if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        bail!(
            "no display to open a window on (DISPLAY is not set): run it in an X11 session, \
             or headless under Xvfb (xvfb-run -a illum view …)"
        );
    }
    let mut scene = source.load()?;
    let mut settings = source.settings(&scene)?;
    let mut event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "cannot open the display {:?}: {e}",
            std::env::var("DISPLAY").unwrap_or_default()
        )
    })?;
    let text = text::Text::new(13.0);
    let bar = BAR_LINES * text.line() + 4;
    let image = [scene.camera.width, scene.camera.height];
    let scale = opts.scale.unwrap_or_else(|| auto_scale(image)).max(1);
    let mut app = App::new(
        opts.title.clone(),
        [image[0] * scale, image[1] * scale + bar],
    );
    let window = open_window(&mut event_loop, &mut app)?;
    let present_ctx = Context::new(&ContextOptions {
        device: opts.device.clone(),
        validation: opts.validation,
        instance_extensions: present::instance_extensions(&window)?,
        device_extensions: vec![ash::khr::swapchain::NAME.to_owned()],
    })?;
    let mut early = opts
        .early_image
        .as_ref()
        .and_then(|start| start(&present_ctx, image));
    // An early image is shown while the view's kernels compile, which on lavapipe holds its
    // device's one queue: the render then takes a device of its own, and the window keeps this
    // one.
    let ctx = match early {
        Some(_) => Context::new(&ContextOptions {
            device: opts.device.clone(),
            validation: opts.validation,
            ..Default::default()
        })?,
        None => present_ctx.clone(),
    };
    let mut present = present::Present::new(&present_ctx, &window)?;
    let renderer = Renderer::new(ctx.clone());
    // Until the first frame, a cold driver cache compiles for seconds: say so (once).
    let said = std::sync::atomic::AtomicBool::new(false);
    ctx.set_kernel_listener(Some(Arc::new(move |e| {
        if matches!(e, crate::vk::KernelEvent::Creating(_))
            && !said.swap(true, std::sync::atomic::Ordering::SeqCst)
        {
            crate::note!(
                "illum view: compiling kernels for this scene's features… (the first time a \
                 feature combination is seen this takes up to half a minute on a CPU driver; \
                 later runs reuse the driver's cache)"
            );
        }
    })));
    let mut prepared = renderer.prepare(&scene, settings.trace)?;
    let mut view = View {
        opts,
        source,
        ctx: ctx.clone(),
        text,
        bar,
        encoder: SrgbEncoder::new(),
        camera: scene.camera.clone(),
        file_camera: scene.camera.clone(),
        plane: 0,
        exposure: opts.exposure,
        message: None,
        curve: Vec::new(),
        frames: 0,
        started,
        first_frame: None,
        early_shown: false,
        applied: None,
        watch: opts.watch.as_ref().map(|f| {
            watch::Watch::new(if scene.inputs.is_empty() {
                std::slice::from_ref(f)
            } else {
                &scene.inputs
            })
        }),
        spf: None,
        denoiser: None,
        denoise: false,
        preview: None,
        restarts: 0,
    };
    if opts.denoise {
        view.toggle_denoise();
    }
    crate::note!(
        "illum view: {}x{} with {} on {} via {}, set up in {:.2} s",
        image[0],
        image[1],
        settings.integrator.name(),
        ctx.info().name,
        prepared.trace_name(),
        started.elapsed().as_secs_f64()
    );
    loop {
        let (next, decided) = {
            let mut p = match early.take() {
                Some(e) => view.progressive_showing(
                    e,
                    (&renderer, &prepared, &settings),
                    &mut event_loop,
                    &mut app,
                    &window,
                    &mut present,
                )?,
                None => renderer.progressive(&prepared, &view.camera, &settings)?,
            };
            let next = view.frames_of(&mut p, &mut event_loop, &mut app, &window, &mut present)?;
            (next, p.settings().allocation.clone())
        };
        let Next::Edit(edited, saved) = next else {
            break;
        };
        let t0 = Instant::now();
        let how = match view.apply(&renderer, &mut prepared, &edited) {
            Ok((mut s, how)) => {
                // The allocation pilot ran once, at the start: an edit keeps its counts (a pilot
                // an edit would hold back the first updated frame), unless the integrator or
                // its parameters changed.
                if s.integrator.identity() == settings.integrator.identity() {
                    s.allocation = decided;
                }
                settings = s;
                how
            }
            Err(e) => {
                view.error(format!(
                    "{}: {e:#}; keeping the last good scene",
                    view.file()
                ));
                continue;
            }
        };
        if (edited.camera.width, edited.camera.height) != (scene.camera.width, scene.camera.height)
        {
            let size = [
                edited.camera.width * scale,
                edited.camera.height * scale + bar,
            ];
            let _ = window.request_inner_size(winit::dpi::PhysicalSize::new(size[0], size[1]));
        }
        scene = *edited;
        if let Some(w) = &mut view.watch
            && !scene.inputs.is_empty()
        {
            w.set_files(&scene.inputs);
        }
        view.applied = Some((saved, t0, how));
    }
    drop(present);
    let mut messages = ctx.validation_messages();
    if !Arc::ptr_eq(&ctx.0, &present_ctx.0) {
        messages.extend(present_ctx.validation_messages());
    }
    if !messages.is_empty() {
        bail!(
            "{} Vulkan validation message(s) (see above)",
            messages.len()
        );
    }
    Ok(())
}

/// The largest integer scale that keeps the window within 1024 x 800 (at least 1).
fn auto_scale(image: [u32; 2]) -> u32 {
    (1024 / image[0].max(1))
        .min(760 / image[1].max(1))
        .clamp(1, 8)
}

/// Pumps the event loop until the window is open.
fn open_window(event_loop: &mut EventLoop<()>, app: &mut App) -> Result<winit::window::Window> {
    let t0 = Instant::now();
    while app.window.is_none() {
        if let PumpStatus::Exit(code) =
            event_loop.pump_app_events(Some(Duration::from_millis(10)), app)
        {
            bail!("the event loop ended before the window opened (code {code})");
        }
        if let Some(e) = app.error.take() {
            bail!(e);
        }
        if t0.elapsed() > Duration::from_secs(10) {
            bail!("the window did not open within 10 s");
        }
    }
    Ok(app.window.take().expect("the window is open"))
}

/// Why a generation of frames (one prepared scene and settings) ended.
enum Next {
    Quit,
    /// The scene file changed and loaded: apply it (the file's modification time).
    Edit(Box<Scene>, SystemTime),
}

struct View<'o> {
    opts: &'o ViewOptions,
    source: &'o dyn Source,
    ctx: Context,
    text: text::Text,
    bar: u32,
    encoder: SrgbEncoder,
    /// The camera rendered (moved by the mouse) and the scene file's.
    camera: Camera,
    file_camera: Camera,
    plane: usize,
    exposure: f32,
    /// The status bar's second line, and whether it is an error.
    message: Option<(String, bool)>,
    /// (seconds, estimated relMSE) since the last restart.
    curve: Vec<(f64, f64)>,
    frames: u64,
    started: Instant,
    first_frame: Option<f64>,
    /// Whether an early image (the fast start's) was shown before the view's own first frame.
    early_shown: bool,
    /// An edit applied, waiting for its first frame: the file's save time, when it was applied
    /// and how.
    applied: Option<(SystemTime, Instant, String)>,
    watch: Option<watch::Watch>,
    /// Seconds per sample of the last step.
    spf: Option<f64>,
    /// The denoiser, loaded at the first D; whether the preview is on; the last denoised
    /// beauty, its spp and when it was made.
    denoiser: Option<Result<Denoiser, String>>,
    denoise: bool,
    preview: Option<(Vec<[f32; 3]>, u32, Instant)>,
    /// Restarts of the image (camera moves, edits): a frame after one is always shown.
    restarts: u64,
}

/// What a frame shows, to tell whether the next would show anything new.
#[derive(PartialEq)]
struct Shown {
    restarts: u64,
    done: u32,
    plane: usize,
    exposure: u32,
    message: Option<(String, bool)>,
    denoise: bool,
    size: [u32; 2],
}

impl View<'_> {
    fn file(&self) -> String {
        self.opts
            .watch
            .as_deref()
            .map_or("the scene".into(), |p| p.display().to_string())
    }

    fn error(&mut self, message: String) {
        crate::note!("illum view: {message}");
        self.message = Some((message, true));
    }

    fn say(&mut self, message: String) {
        crate::note!("illum view: {message}");
        self.message = Some((message, false));
    }

    /// Brings `prepared` to the edited scene: an update where only tables and instance
    /// transforms changed, else a new preparation. Returns the scene's settings and what was
    /// done.
    fn apply(
        &mut self,
        renderer: &Renderer,
        prepared: &mut PreparedScene,
        edited: &Scene,
    ) -> Result<(RenderSettings, String)> {
        let settings = self.source.settings(edited)?;
        let how = match prepared.update(&self.ctx, edited) {
            Ok(u) if u.tables.is_empty() && !u.instances_moved => "nothing uploaded".to_string(),
            Ok(u) => format!(
                "rewrote the {} table{}{} in {:.3} s",
                u.tables.join(", "),
                if u.tables.len() == 1 { "" } else { "s" },
                if u.instances_moved {
                    ", moved instances"
                } else {
                    ""
                },
                u.seconds
            ),
            Err(why) => {
                let t = Instant::now();
                *prepared = renderer.prepare(edited, settings.trace)?;
                format!(
                    "prepared the scene again in {:.3} s ({why})",
                    t.elapsed().as_secs_f64()
                )
            }
        };
        if edited.camera != self.file_camera {
            self.camera = edited.camera.clone();
            self.file_camera = edited.camera.clone();
        }
        Ok((settings, how))
    }
}
