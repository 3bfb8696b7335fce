//! The view's fast start (see the parent module and src/view/early.rs).

use super::{Capture, CpuTimes, Mode, folder, last_line, mark_warm, render_bytes, spawn, wanted};
use std::path::{Path, PathBuf};
use std::process::Child;

/// The view's fast start: a second process (this program with the same `view` arguments) renders
/// the view's first image, one sample a pixel, with unoptimised kernels, to show while the view
/// compiles its own (src/view/early.rs).
pub(in crate::cli) struct FirstView {
    child: Option<(Child, Capture)>,
    dir: PathBuf,
    mode: Mode,
    size: (u32, u32),
    key: String,
}

/// The image the second process of a view writes in its staging folder.
pub(in crate::cli) fn first_view_image(dir: &Path) -> PathBuf {
    dir.join("first.exr")
}

impl FirstView {
    /// Starts the second process where `mode` and the machine allow it (as [`FastStart::start`])
    /// for an image of `width` x `height`.
    pub(in crate::cli) fn start(
        mode: Mode,
        since: Option<CpuTimes>,
        (ctx, key): (&crate::vk::Context, String),
        (width, height): (u32, u32),
    ) -> Option<FirstView> {
        let bytes = render_bytes(u64::from(width) * u64::from(height), false);
        if !wanted(mode, since, ctx, bytes, &key) {
            return None;
        }
        let dir = folder().ok()?;
        match spawn(&dir) {
            Ok((child, _, err)) => Some(FirstView {
                child: Some((child, err)),
                dir,
                mode,
                size: (width, height),
                key,
            }),
            Err(e) => {
                crate::note!(
                    "illum view: note: no fast start (the second process did not start: {e})"
                );
                let _ = std::fs::remove_dir_all(&dir);
                None
            }
        }
    }
}

impl crate::view::EarlyImage for FirstView {
    fn poll(&mut self) -> Option<Vec<[f32; 3]>> {
        let (child, _) = self.child.as_mut()?;
        let status = match child.try_wait() {
            Ok(None) => return None,
            Ok(Some(s)) => s,
            Err(_) => {
                let _ = child.kill();
                let _ = child.wait();
                self.child = None;
                return None;
            }
        };
        let (_, err) = self.child.take()?;
        let image = first_view_image(&self.dir);
        let read = if status.success() {
            crate::output::read_reference(&image, self.size.0, self.size.1)
                .map_err(|e| e.to_string())
        } else {
            Err(format!("{status}: {}", last_line(err)))
        };
        read.map_err(|e| {
            crate::note!("illum view: note: the fast start's second process failed ({e})")
        })
        .ok()
    }

    fn pending(&mut self) -> bool {
        self.child.is_some()
    }

    fn wait(&self) -> bool {
        self.mode == Mode::Wait
    }

    fn origin(&self) -> String {
        "a second process with the driver's unoptimised kernels (fast start)".into()
    }

    fn compiled(&mut self) {
        mark_warm(&self.key);
    }
}

impl Drop for FirstView {
    fn drop(&mut self) {
        if let Some((mut child, _)) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
