//! SIGINT and SIGTERM during a render: the first one asks the render to stop after its current
//! round of dispatches (so the samples done so far are written); a second one quits at once.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicPtr, Ordering};

/// The first signal received (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);
/// The cancel flag the handler sets: leaked from an `Arc`, so it lives as long as the process.
static FLAG: AtomicPtr<AtomicBool> = AtomicPtr::new(std::ptr::null_mut());

/// Installs the handlers (once) and returns the flag they set, for
/// [`RenderSettings::cancel`](crate::render::RenderSettings::cancel).
pub fn install() -> Arc<AtomicBool> {
    static ONCE: std::sync::OnceLock<Arc<AtomicBool>> = std::sync::OnceLock::new();
    ONCE.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        FLAG.store(Arc::into_raw(flag.clone()).cast_mut(), Ordering::SeqCst);
        #[cfg(unix)]
        // SAFETY: the handler only does async-signal-safe work (atomics, write, _exit).
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = handler as *const () as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            for sig in [libc::SIGINT, libc::SIGTERM] {
                libc::sigaction(sig, &action, std::ptr::null_mut());
            }
        }
        flag
    })
    .clone()
}

/// The signal that asked to stop, if one did.
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

#[cfg(unix)]
extern "C" fn handler(sig: libc::c_int) {
    if RECEIVED.swap(sig, Ordering::SeqCst) != 0 {
        // SAFETY: _exit is async-signal-safe.
        unsafe { libc::_exit(128 + sig) }
    }
    let flag = FLAG.load(Ordering::SeqCst);
    if !flag.is_null() {
        // SAFETY: the pointer comes from a leaked Arc and stays valid.
        unsafe { (*flag).store(true, Ordering::SeqCst) };
    }
    const MSG: &[u8] = b"\nillum: stopping after the current dispatch to save the samples done so far (again to quit at once)\n";
    // SAFETY: write is async-signal-safe; a failed write is of no consequence.
    unsafe { libc::write(2, MSG.as_ptr().cast(), MSG.len()) };
}

/// "SIGINT", "SIGTERM", or the number.
pub fn name(sig: i32) -> String {
    #[cfg(unix)]
    match sig {
        libc::SIGINT => return "SIGINT".into(),
        libc::SIGTERM => return "SIGTERM".into(),
        _ => {}
    }
    format!("signal {sig}")
}
