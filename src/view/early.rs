//! The first generation of frames with an early image (the command line's fast start): the
//! view's kernels compile on a thread of their own while this one keeps the window answering and
//! shows the early image as soon as it comes.

use super::input::App;
use super::{EarlyImage, View, display, frames, present};
use crate::render::{PreparedScene, Progressive, RenderSettings, Renderer};
use anyhow::{Result, anyhow};
use std::time::Duration;
use winit::event_loop::EventLoop;
use winit::platform::pump_events::EventLoopExtPumpEvents;

impl View<'_> {
    /// `renderer.progressive(...)` (which compiles the kernels at its warm-up dispatch), with the
    /// early image shown while it runs. Input waits for the view's own frames.
    pub(super) fn progressive_showing<'p>(
        &mut self,
        mut early: Box<dyn EarlyImage>,
        (renderer, prepared, settings): (&'p Renderer, &'p PreparedScene, &RenderSettings),
        event_loop: &mut EventLoop<()>,
        app: &mut App,
        window: &winit::window::Window,
        present: &mut present::Present,
    ) -> Result<Progressive<'p>> {
        let camera = self.camera.clone();
        std::thread::scope(|s| -> Result<Progressive<'p>> {
            let compile = s.spawn(|| renderer.progressive(prepared, &camera, settings));
            loop {
                if compile.is_finished() && (self.early_shown || !early.wait() || !early.pending())
                {
                    break;
                }
                let _ = event_loop.pump_app_events(Some(Duration::from_millis(10)), app);
                if !self.early_shown
                    && let Some(values) = early.poll()
                {
                    self.show_early(&values, &early.origin(), window, present)?;
                }
            }
            let p = compile
                .join()
                .map_err(|_| anyhow!("the thread compiling the view's kernels panicked"))??;
            early.compiled();
            Ok(p)
        })
    }

    fn show_early(
        &mut self,
        values: &[[f32; 3]],
        origin: &str,
        window: &winit::window::Window,
        present: &mut present::Present,
    ) -> Result<()> {
        let image = display::encode(values, display::Plane::Beauty, self.exposure, &self.encoder);
        let status = format!("1 spp from {origin}; compiling the view's own kernels…");
        let size = window.inner_size();
        let image_size = [self.camera.width, self.camera.height];
        let bgra = present.bgra();
        let (text, bar, message) = (&self.text, self.bar, self.message.clone());
        let shown = present.frame([size.width, size.height], false, |bytes, extent| {
            frames::compose(
                bytes,
                extent,
                &image,
                image_size,
                bar,
                text,
                &status,
                message,
                &[],
                bgra,
            )
        })?;
        if shown {
            self.early_shown = true;
            let t = self.started.elapsed().as_secs_f64();
            self.first_frame = Some(t);
            crate::note!("illum view: first frame {t:.3} s after start (1 spp, from {origin})");
        }
        Ok(())
    }
}
