//! SIGINT and SIGTERM during a render. The first one asks the render to stop after its current
//! round of dispatches, so the samples done so far are written (a part job writes nothing: it is
//! all or nothing, and its scheduler reruns it).
//!
//! Which signals count again:
//! - a repeat within [`REPEAT_WINDOW_NS`] (200 ms) of the first is the same request delivered twice: `timeout`
//!   signals its child and then the child's process group, microseconds apart;
//! - SIGTERM never quits at once (schedulers send it, then SIGKILL after a grace period);
//! - a later SIGINT (Ctrl-C pressed again) quits at once: the file being written, if any, is
//!   removed before the process exits with status 1, so no half-written or temporary file stays
//!   and the status says that nothing was written.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicI64, AtomicPtr, Ordering};

/// Repeats of a signal closer than this to the first are one request (nanoseconds).
pub const REPEAT_WINDOW_NS: i64 = 200_000_000;

/// The first signal received (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);
/// When it came (CLOCK_MONOTONIC, nanoseconds).
static RECEIVED_AT: AtomicI64 = AtomicI64::new(0);
/// The render in progress is a part job (it writes nothing when interrupted).
static PART_JOB: AtomicBool = AtomicBool::new(false);
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
        // SAFETY: the handler only does async-signal-safe work (atomics, clock_gettime, write,
        // _exit).
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

/// Says that the render is a part job, so the first signal's message tells what will happen.
pub fn set_part_job() {
    PART_JOB.store(true, Ordering::SeqCst);
}

/// The signal that asked to stop, if one did.
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

#[cfg(unix)]
fn monotonic_ns() -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime is async-signal-safe and writes only `ts`.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec * 1_000_000_000 + ts.tv_nsec
}

#[cfg(unix)]
fn say(msg: &[u8]) {
    // SAFETY: write is async-signal-safe; a failed write is of no consequence.
    unsafe { libc::write(2, msg.as_ptr().cast(), msg.len()) };
}

#[cfg(unix)]
extern "C" fn handler(sig: libc::c_int) {
    let now = monotonic_ns();
    if RECEIVED
        .compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst)
        .is_ok()
    {
        RECEIVED_AT.store(now, Ordering::SeqCst);
        let flag = FLAG.load(Ordering::SeqCst);
        if !flag.is_null() {
            // SAFETY: the pointer comes from a leaked Arc and stays valid.
            unsafe { (*flag).store(true, Ordering::SeqCst) };
        }
        say(if PART_JOB.load(Ordering::SeqCst) {
            b"\nillum: stopping; an interrupted part job writes nothing (its scheduler reruns it)\n"
        } else {
            b"\nillum: stopping after the current dispatch to save the samples done so far (Ctrl-C again to quit at once)\n"
        });
        return;
    }
    let repeat = now - RECEIVED_AT.load(Ordering::SeqCst) < REPEAT_WINDOW_NS;
    if sig != libc::SIGINT || repeat {
        return;
    }
    if crate::output::abort_writes() {
        // The write in progress removes its temporary file and fails; the command exits 1.
        say(b"\nillum: quitting: the file being written is removed\n");
        return;
    }
    say(b"\nillum: quit at once; nothing was written\n");
    // SAFETY: _exit is async-signal-safe.
    unsafe { libc::_exit(1) }
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
