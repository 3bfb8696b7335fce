//! `illum view`: a window showing a render converge pass by pass, the camera under the mouse and
//! the scene file under watch (docs/view.md). It renders through [`Progressive`], the blocking
//! render's driver stepped a few samples a frame, so that what it saves after N samples is what
//! `illum render --spp N` writes, bit for bit; an edit of the scene goes through
//! [`crate::render::PreparedScene::update`] (only the tables that changed are rewritten), and a
//! bad edit leaves the last good scene rendering with the error in the status bar.

mod display;
mod input;
mod orbit;
mod present;
mod text;
mod watch;

use crate::denoise::Denoiser;
use crate::output::{SrgbEncoder, image_metadata, write_exr, write_rgb8_png};
use crate::render::Peek;
use crate::render::{PreparedScene, Progressive, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, anyhow, bail};
use display::Plane;
use input::{Action, App};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
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
    let ctx = Context::new(&ContextOptions {
        device: opts.device.clone(),
        validation: opts.validation,
        instance_extensions: present::instance_extensions(&window)?,
        device_extensions: vec![ash::khr::swapchain::NAME.to_owned()],
    })?;
    let mut present = present::Present::new(&ctx, &window)?;
    let renderer = Renderer::new(ctx.clone());
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
        let next = {
            let mut p = renderer.progressive(&prepared, &view.camera, &settings)?;
            view.frames_of(&mut p, &mut event_loop, &mut app, &window, &mut present)?
        };
        let Next::Edit(edited, saved) = next else {
            break;
        };
        let t0 = Instant::now();
        let how = match view.apply(&renderer, &mut prepared, &edited) {
            Ok((s, how)) => {
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
    let messages = ctx.validation_messages();
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

impl View<'_> {
    /// Frames of one prepared scene and its settings, until the user quits or the scene file
    /// changes (and loads).
    fn frames_of(
        &mut self,
        p: &mut Progressive,
        event_loop: &mut EventLoop<()>,
        app: &mut App,
        window: &winit::window::Window,
        present: &mut present::Present,
    ) -> Result<Next> {
        let spp = p.settings().spp;
        let aovs = p.settings().integrator.aov_planes();
        let planes = display::planes(aovs.len());
        self.plane = self.plane.min(planes.len() - 1);
        self.curve.clear();
        self.preview = None;
        let mut last_estimate = Instant::now();
        let mut finished_said = false;
        let mut last_shown = None;
        self.restarts += 1;
        loop {
            let idle = p.finished();
            let wait = if idle {
                Some(Duration::from_millis(30))
            } else {
                Some(Duration::ZERO)
            };
            let mut quit = matches!(event_loop.pump_app_events(wait, app), PumpStatus::Exit(_));
            let input = app.take();
            quit |= input.close || self.opts.cancel.load(Ordering::SeqCst);
            if input.resized {
                present.invalidate();
            }
            let mut camera = self.camera.clone();
            for key in &input.keys {
                match key {
                    Action::ExposureUp => self.exposure += 0.5,
                    Action::ExposureDown => self.exposure -= 0.5,
                    Action::ExposureReset => self.exposure = 0.0,
                    Action::NextPlane => self.plane = (self.plane + 1) % planes.len(),
                    Action::PreviousPlane => {
                        self.plane = (self.plane + planes.len() - 1) % planes.len()
                    }
                    Action::Save => self.save(p),
                    Action::ResetCamera => camera = self.file_camera.clone(),
                    Action::Quit => quit = true,
                    Action::Denoise => self.toggle_denoise(),
                }
            }
            if input.orbit != (0.0, 0.0) {
                camera = orbit::orbit(&camera, input.orbit.0, input.orbit.1);
            }
            if input.pan != (0.0, 0.0) {
                camera = orbit::pan(&camera, input.pan.0, input.pan.1);
            }
            if input.dolly != 0.0 {
                camera = orbit::dolly(&camera, input.dolly);
            }
            if camera != self.camera {
                // The move restarts the image in this frame.
                p.restart(&camera)?;
                self.restarts += 1;
                self.preview = None;
                self.camera = camera;
                self.curve.clear();
                finished_said = false;
            }
            if !quit && let Some(saved) = self.watch.as_mut().and_then(|w| w.changed()) {
                match self.source.load() {
                    Ok(scene) => return Ok(Next::Edit(Box::new(scene), saved)),
                    Err(e) => self.error(format!(
                        "{}: {e:#}; keeping the last good scene",
                        self.file()
                    )),
                }
            }
            if !p.finished() {
                // As many samples as fit the frame's time at the last step's rate.
                let n = self
                    .spf
                    .map_or(1, |s| (FRAME_SECONDS / s).clamp(1.0, 256.0) as u32);
                let t = Instant::now();
                let before = p.done();
                p.step(n)?;
                let done = p.done() - before;
                if done > 0 {
                    self.spf = Some(t.elapsed().as_secs_f64() / f64::from(done));
                }
            }
            // Nothing new to show (converged, no input): no frame, so that an idle window
            // costs nothing. Scripted runs (--frames) count every frame.
            let size = window.inner_size();
            let shown = Shown {
                restarts: self.restarts,
                done: p.done(),
                plane: self.plane,
                exposure: self.exposure.to_bits(),
                message: self.message.clone(),
                denoise: self.denoise,
                size: [size.width, size.height],
            };
            let exiting = quit || self.opts.frames.is_some_and(|f| self.frames + 1 >= f);
            if self.opts.frames.is_none()
                && !exiting
                && !input.redraw
                && last_shown.as_ref() == Some(&shown)
            {
                continue;
            }
            last_shown = Some(shown);
            let peek = p.peek()?;
            let pixels = (self.camera.width * self.camera.height) as usize;
            if p.done() >= 2
                && (last_estimate.elapsed() > Duration::from_millis(250) || p.finished())
                && self.curve.last().is_none_or(|c| c.0 < p.wall_seconds())
                && let Some(e) = display::estimate(&peek, pixels)
            {
                self.curve.push((p.wall_seconds(), e));
                last_estimate = Instant::now();
            }
            let plane = planes[self.plane];
            let mut name = plane.name(aovs);
            let values = match (plane, self.denoised(p, &peek)) {
                (Plane::Beauty, Some((image, n))) => {
                    name = format!("beauty, denoised at {n} spp");
                    image
                }
                _ => display::values(&peek, plane, pixels),
            };
            let image = display::encode(&values, plane, self.exposure, &self.encoder);
            let status = self.status(p, spp, name);
            self.frames += 1;
            let capture = exiting && self.opts.screenshot.is_some();
            let bgra = present.bgra();
            let (text, bar, message) = (&self.text, self.bar, self.message.clone());
            let curve = &self.curve;
            let image_size = [self.camera.width, self.camera.height];
            let shown = present.frame([size.width, size.height], capture, |bytes, extent| {
                compose(
                    bytes, extent, &image, image_size, bar, text, &status, message, curve, bgra,
                )
            })?;
            if shown {
                self.first_shown(p);
            }
            if p.finished() && !finished_said {
                finished_said = true;
                crate::note!(
                    "illum view: {spp} spp done at frame {}, {:.2} s of rendering",
                    self.frames,
                    p.wall_seconds()
                );
            }
            if exiting {
                if let Some(path) = &self.opts.screenshot {
                    let shot = present.captured()?;
                    let (rgb, extent) =
                        shot.ok_or_else(|| anyhow!("no frame was read back for the screenshot"))?;
                    write_rgb8_png(path, &rgb, extent[0], extent[1])?;
                    crate::note!("illum view: wrote the screenshot {}", path.display());
                }
                if self.opts.save_at_exit {
                    self.save(p);
                    if let Some((m, true)) = &self.message {
                        bail!("{m}");
                    }
                }
                return Ok(Next::Quit);
            }
        }
    }

    fn toggle_denoise(&mut self) {
        if self.denoise {
            self.denoise = false;
            self.say("denoised preview off".into());
            return;
        }
        match self.denoiser.get_or_insert_with(Denoiser::new) {
            Ok(d) => {
                let what = d.description();
                self.denoise = true;
                self.say(format!("denoised preview on: {what}"));
            }
            Err(e) => {
                let e = e.clone();
                self.error(e);
            }
        }
    }

    /// The denoised beauty to show, when the preview is on: denoised again at most once a
    /// second while samples come in, and once more when the render is done.
    fn denoised(&mut self, p: &Progressive, peek: &Peek) -> Option<(Vec<[f32; 3]>, u32)> {
        let Some(Ok(d)) = self.denoiser.as_ref().filter(|_| self.denoise) else {
            return None;
        };
        let stale = self.preview.as_ref().is_none_or(|(_, n, at)| {
            *n != p.done() && (at.elapsed() > Duration::from_secs(1) || p.finished())
        });
        if stale && p.done() > 0 {
            let film = display::film(peek, self.camera.width, self.camera.height);
            match d.denoise_film(&film) {
                Ok(image) => self.preview = Some((image, p.done(), Instant::now())),
                Err(e) => {
                    self.denoise = false;
                    self.error(e);
                    return None;
                }
            }
        }
        self.preview
            .as_ref()
            .map(|(image, n, _)| (image.clone(), *n))
    }

    /// After a frame was presented: the first frame's time, an applied edit's latency.
    fn first_shown(&mut self, p: &Progressive) {
        if self.first_frame.is_none() {
            let t = self.started.elapsed().as_secs_f64();
            self.first_frame = Some(t);
            crate::note!(
                "illum view: first frame {t:.3} s after start ({} spp)",
                p.done()
            );
        }
        if let Some((saved, applied, how)) = self.applied.take() {
            let since_save = SystemTime::now()
                .duration_since(saved)
                .map_or(f64::NAN, |d| d.as_secs_f64());
            self.say(format!(
                "applied the edit of {}: {how}; first updated frame {:.3} s after applying it, \
                 {since_save:.3} s after the save",
                self.file(),
                applied.elapsed().as_secs_f64()
            ));
        }
    }

    fn status(&self, p: &Progressive, spp: u32, plane: String) -> String {
        let rate = if p.wall_seconds() > 0.0 {
            f64::from(p.done()) * f64::from(self.camera.width * self.camera.height)
                / p.wall_seconds()
                / 1e6
        } else {
            0.0
        };
        let estimate = self
            .curve
            .last()
            .map_or("–".into(), |c| format!("{:.2e}", c.1));
        format!(
            "{plane} · {}/{spp} spp · {rate:.2} M samples/s · est. relMSE {estimate} · {:+.1} EV · {}",
            p.done(),
            self.exposure,
            p.settings().integrator.name()
        )
    }

    /// Writes the image so far (the S key) as `illum render` would at this sample count.
    fn save(&mut self, p: &Progressive) {
        let path = self.opts.output.clone();
        match save(&self.ctx, p, &path) {
            Ok(spp) => self.say(format!("saved {} ({spp} spp)", path.display())),
            Err(e) => self.error(format!("could not save {}: {e:#}", path.display())),
        }
    }
}

fn save(ctx: &Context, p: &Progressive, path: &Path) -> Result<u32> {
    let out = p.output()?;
    write_exr(
        path,
        &out.film,
        &image_metadata(&out, p.settings(), &ctx.info().name),
    )?;
    Ok(out.stats.spp)
}

/// The frame: the image scaled into the area above the status bar, the bar's two lines and the
/// error curve at its right.
#[allow(clippy::too_many_arguments)]
fn compose(
    bytes: &mut [u8],
    extent: [u32; 2],
    image: &[[u8; 3]],
    image_size: [u32; 2],
    bar: u32,
    text: &text::Text,
    status: &str,
    message: Option<(String, bool)>,
    curve: &[(f64, f64)],
    bgra: bool,
) {
    const BACKGROUND: [u8; 3] = [16, 16, 16];
    const BAR: [u8; 3] = [32, 32, 36];
    let mut frame = text::Frame {
        pixels: bytes,
        width: extent[0],
        height: extent[1],
    };
    let top = extent[1].saturating_sub(bar);
    frame.fill_rows(0, top, BACKGROUND);
    frame.fill_rows(top, extent[1], BAR);
    let at = display::place(image_size, extent, bar);
    display::blit(frame.pixels, extent, image, image_size, at);
    let curve_width = if extent[0] >= 480 { 120 } else { 0 };
    let right = extent[0].saturating_sub(curve_width + 8);
    text.draw(&mut frame, 6, top + 2, right, status, [225, 225, 225]);
    let help = "drag: orbit · shift/right drag: pan · wheel: dolly · A: plane · +/-: exposure · D: denoise · S: save · R: camera · Q: quit";
    let (line, color) = match &message {
        Some((m, true)) => (m.as_str(), [255, 110, 100]),
        Some((m, false)) => (m.as_str(), [150, 220, 150]),
        None => (help, [150, 150, 160]),
    };
    text.draw(&mut frame, 6, top + 2 + text.line(), right, line, color);
    if curve_width > 0 {
        frame.curve(
            extent[0] - curve_width - 4,
            top + 3,
            [curve_width, bar.saturating_sub(6)],
            curve,
            [120, 190, 255],
        );
    }
    if bgra {
        for p in frame.pixels.chunks_exact_mut(4) {
            p.swap(0, 2);
        }
    }
}
