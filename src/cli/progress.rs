//! The progress shown while a command renders: a bar from the start, and a line on stderr when
//! the driver is still compiling kernels half a second in (render and compare alike).

use crate::vk::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A bar drawn from the start (a spinner while the kernels compile and the scene uploads), on
/// stderr; hidden with --quiet or when stderr is not a terminal.
pub(super) fn progress_bar(quiet: bool, spp: u32, time: Option<f64>) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let (len, unit) = match time {
        Some(_) => (1000, "‰ of the time"),
        None => (u64::from(spp), "spp"),
    };
    let b = ProgressBar::new(len);
    b.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {unit} (eta {{eta}}) {{msg}}"
        ))
        .expect("valid template"),
    );
    b.set_message("setting up");
    b.enable_steady_tick(Duration::from_millis(200));
    b
}

/// Says "compiling kernels…" on stderr when the driver is still compiling half a second after the
/// first kernel was created (the first render of a feature combination on lavapipe: 14–31 s;
/// later ones hit Mesa's shader cache and say nothing). `compiled` runs once the render's
/// kernels have compiled. Returns the flag that the first progress call (set-up over) sets.
pub(super) fn announce_compiles(
    ctx: &Context,
    bar: &ProgressBar,
    quiet: bool,
    compiled: Option<Box<dyn Fn() + Send + Sync>>,
) -> Arc<AtomicBool> {
    use crate::vk::KernelEvent;
    let done = Arc::new(AtomicBool::new(false));
    let started = Arc::new(AtomicBool::new(false));
    let (d, b) = (done.clone(), bar.clone());
    ctx.set_kernel_listener(Some(Arc::new(move |e| {
        if let (KernelEvent::Compiled(_), Some(f)) = (e, &compiled) {
            f();
        }
        if quiet || !matches!(e, KernelEvent::Creating(_)) || started.swap(true, Ordering::SeqCst) {
            return;
        }
        let (d, b) = (d.clone(), b.clone());
        std::thread::spawn(move || {
            let t = Instant::now();
            while t.elapsed() < Duration::from_millis(500) {
                if d.load(Ordering::SeqCst) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            if !d.load(Ordering::SeqCst) {
                b.suspend(|| {
                    crate::note!(
                        "illum: compiling kernels for this scene's features… (the first time a \
                         feature combination is seen this takes up to half a minute on a CPU \
                         driver; later renders reuse the driver's cache)"
                    )
                });
                b.set_message("compiling kernels");
            }
        });
    })));
    done
}
