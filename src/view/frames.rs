//! The frame loop of a view: input, edits, a step of the render, the frame composed and
//! presented; saving and the denoised preview.

use super::input::{Action, App};
use super::{FRAME_SECONDS, Next, Shown, View, display, orbit, present, text};
use crate::denoise::Denoiser;
use crate::output::{image_metadata, write_exr, write_rgb8_png};
use crate::render::{Peek, Progressive};
use crate::vk::Context;
use anyhow::{Result, anyhow, bail};
use display::Plane;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant, SystemTime};
use winit::event_loop::EventLoop;
use winit::platform::pump_events::{EventLoopExtPumpEvents, PumpStatus};

impl View<'_> {
    /// Frames of one prepared scene and its settings, until the user quits or the scene file
    /// changes (and loads).
    pub(super) fn frames_of(
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
            // The denoised preview replaces the beauty only (nothing is denoised for the other
            // planes).
            let denoised = match plane {
                Plane::Beauty => self.denoised(p, &peek),
                _ => None,
            };
            let values = match (denoised, &self.preview) {
                (Some(n), Some((image, ..))) => {
                    name = format!("beauty, denoised at {n} spp");
                    std::borrow::Cow::Borrowed(image.as_slice())
                }
                _ => std::borrow::Cow::Owned(display::values(&peek, plane, pixels)),
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

    pub(super) fn toggle_denoise(&mut self) {
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

    /// When the preview is on, brings `self.preview` (the denoised beauty) up to date: denoised
    /// again at most once a second while samples come in, and once more when the render is
    /// done. Returns the spp it was denoised at.
    fn denoised(&mut self, p: &Progressive, peek: &Peek) -> Option<u32> {
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
        self.preview.as_ref().map(|(_, n, _)| *n)
    }

    /// After a frame was presented: the first frame's time, an applied edit's latency.
    fn first_shown(&mut self, p: &Progressive) {
        if self.first_frame.is_none() || self.early_shown {
            self.ctx.set_kernel_listener(None);
            let t = self.started.elapsed().as_secs_f64();
            let own = if self.early_shown { "own " } else { "" };
            self.first_frame = Some(t);
            self.early_shown = false;
            crate::note!(
                "illum view: {own}first frame {t:.3} s after start ({} spp)",
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
pub(super) fn compose(
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
