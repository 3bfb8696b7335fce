//! Fast start on a CPU driver. On lavapipe a kernel's first dispatch waits for LLVM to compile it,
//! in one thread: 2.3–2.6 s for the default scene's `full` kernel, most of a cold render of a small
//! image. With its optimisations off (Mesa's `GALLIVM_PERF=nopt`) LLVM takes 0.9 s and the code runs
//! about 2.7× slower. So, while this process compiles the optimised kernels, a second process (this
//! program again, with the same arguments) renders the same image with unoptimised kernels on the
//! core the compile leaves idle, and writes its image to a staging folder. Whichever is done first
//! gives the result: the second process for a short render (its image is put in place and its
//! messages printed), this one otherwise (it stops the second as soon as its own kernels have
//! compiled). The pixels are the same either way: llvmpipe sets no fast-math flags, so LLVM's
//! optimisations should keep every floating-point result; tests/fast_start.rs renders four
//! kernels both ways and compares them bit for bit on the machine it runs on.
//! docs/performance-kernels.md, "Fast start", has the figures.
//!
//! When the second process won, the optimised kernels are compiled into Mesa's cache by a third
//! process left in the background, so that the next render starts warm.
//!
//! `ILLUM_FAST_START`: unset, on when the driver is llvmpipe, the sample count is fixed and no pass
//! is measured (no `--time`, `--report`, `--report-plot`, `--reference`), a core has been idle
//! since this process started (half a core's worth of idle or niced time, from /proc/stat),
//! memory holds two renders and the kernels are not noted as compiled (warm.rs); `0` off; `1` on
//! whatever the load; `wait` on, and this process waits for the second before it compiles
//! anything (a test's way to take the second process's path every time).

mod view;
mod warm;

pub(super) use view::{FirstView, first_view_image};
use warm::known_warm;
pub(super) use warm::{mark_warm, warm_key};

use anyhow::{Result, bail};
use indicatif::ProgressBar;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Names the staging folder in the second process's environment (its presence makes a process
/// the second one).
const CHILD_ENV: &str = "ILLUM_FAST_START_CHILD";
const MODE_ENV: &str = "ILLUM_FAST_START";

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Mode {
    Off,
    Auto,
    On,
    /// On, and the first process waits for the second whatever happens.
    Wait,
}

/// The mode `ILLUM_FAST_START` asks for.
pub(super) fn mode() -> Result<Mode> {
    parse_mode(std::env::var(MODE_ENV).ok().as_deref())
}

fn parse_mode(v: Option<&str>) -> Result<Mode> {
    Ok(match v {
        None | Some("") => Mode::Auto,
        Some("0") | Some("off") => Mode::Off,
        Some("1") | Some("on") => Mode::On,
        Some("wait") => Mode::Wait,
        Some(other) => bail!(
            "environment variable {MODE_ENV}={other:?}: expected 0 (off), 1 (on whatever the \
             load), wait (on, and wait for the second process) or nothing (automatic)"
        ),
    })
}

/// The staging folder when this process is the second one of a fast start.
pub(super) fn staging() -> Option<PathBuf> {
    std::env::var_os(CHILD_ENV).map(PathBuf::from)
}

/// Where the second process writes the output `p`: the staging folder, the same file name.
pub(super) fn staged(dir: &Path, p: &Path) -> PathBuf {
    dir.join(p.file_name().unwrap_or(std::ffi::OsStr::new("output")))
}

/// Idle and total CPU time of all cores (/proc/stat's first line, in clock ticks).
#[derive(Clone, Copy, Debug)]
pub(super) struct CpuTimes {
    idle: u64,
    total: u64,
}

impl CpuTimes {
    pub(super) fn now() -> Option<CpuTimes> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        parse_cpu_line(stat.lines().next()?)
    }
}

fn parse_cpu_line(line: &str) -> Option<CpuTimes> {
    let mut f = line.split_whitespace();
    (f.next()? == "cpu").then_some(())?;
    let v: Vec<u64> = f.map_while(|x| x.parse().ok()).collect();
    // user nice system idle iowait irq softirq steal (guest time is already in user). Time of
    // niced processes counts as idle: they yield to this one and its second process (a
    // background compile of an earlier fast start runs at nice 19).
    let total = v.iter().take(8).sum();
    Some(CpuTimes {
        idle: v.get(3)? + v.get(4).unwrap_or(&0) + v.get(1)?,
        total,
    })
}

/// Whether a core has been idle since `since` (this process's start, which has kept one core
/// busy): idle time worth at least half a core. Without a long enough interval, whether the
/// 1-minute load average leaves a core.
fn idle_core(since: Option<CpuTimes>) -> bool {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cores < 2 {
        return false;
    }
    if let (Some(a), Some(b)) = (since, CpuTimes::now())
        && b.total >= a.total + 8
    {
        return idle_cores(a, b, cores) >= 0.5;
    }
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok());
    load.is_some_and(|l| l <= cores as f64 - 1.0)
}

/// Cores' worth of idle time between two readings.
fn idle_cores(a: CpuTimes, b: CpuTimes, cores: usize) -> f64 {
    let total = b.total.saturating_sub(a.total).max(1) as f64;
    cores as f64 * b.idle.saturating_sub(a.idle) as f64 / total
}

/// The host memory a render of `pixels` pixels may take (16 AOV planes: more than any
/// integrator declares), to tell whether a second one fits beside it.
pub(super) fn render_bytes(pixels: u64, evaluate: bool) -> u64 {
    use crate::film::memory::{PROCESS_BYTES, film_bytes};
    PROCESS_BYTES + film_bytes(pixels, 16, evaluate, false)
}

#[derive(Debug)]
enum State {
    Running(Child),
    /// The second process finished first: its outputs are being moved, then the process ends.
    SecondWon,
    /// This process goes on alone (it took over, or the second process failed or was refused).
    Over,
}

/// A second process rendering the same image with unoptimised kernels (see the module's text).
pub(super) struct FastStart {
    state: Arc<Mutex<State>>,
    dir: PathBuf,
    mode: Mode,
}

/// Outputs of the render: (where the second process writes it, where it belongs).
pub(super) type Outputs = Vec<(PathBuf, PathBuf)>;

impl FastStart {
    /// Starts the second process where `mode` and the machine allow it (`since`: CPU times at
    /// this process's start, to tell whether a core is idle; `key`: the kernels', see
    /// [`warm_key`]; `bytes`: what one render takes, see
    /// [`render_bytes`]); `outputs` gives, for its staging folder, the files it will write there
    /// and where each belongs. `ctx` is this process's
    /// device (only llvmpipe compiles at the first dispatch). `bar` is cleared before the second
    /// process's messages are printed.
    pub(super) fn start(
        mode: Mode,
        since: Option<CpuTimes>,
        (ctx, key): (&crate::vk::Context, &str),
        bytes: u64,
        outputs: impl FnOnce(&Path) -> Outputs,
        bar: &ProgressBar,
    ) -> Option<FastStart> {
        if !wanted(mode, since, ctx, bytes, key) {
            return None;
        }
        let dir = match folder() {
            Ok(d) => d,
            Err(e) => {
                crate::note!("illum: note: no fast start (no staging folder: {e})");
                return None;
            }
        };
        let outputs = outputs(&dir);
        let (child, out, err) = match spawn(&dir) {
            Ok(c) => c,
            Err(e) => {
                crate::note!("illum: note: no fast start (the second process did not start: {e})");
                let _ = std::fs::remove_dir_all(&dir);
                return None;
            }
        };
        let state = Arc::new(Mutex::new(State::Running(child)));
        let (s, d, b) = (state.clone(), dir.clone(), bar.clone());
        std::thread::spawn(move || watch(&s, &d, &outputs, out, err, &b));
        Some(FastStart { state, dir, mode })
    }

    /// This process's kernels have compiled: stop the second process, unless it already won (then
    /// this returns only if its outputs could not be put in place: otherwise its result is
    /// written and the process ends). With `ILLUM_FAST_START=wait`, let it finish first.
    pub(super) fn take_over(&self) {
        self.settle(self.mode == Mode::Wait);
    }

    /// Waits until the race is decided for this process: kills a running second process (or,
    /// `wait`ing, waits for it), and blocks for good if the second process won.
    fn settle(&self, wait: bool) {
        loop {
            let mut state = lock(&self.state);
            match &mut *state {
                State::Running(child) if !wait => {
                    let _ = child.kill();
                    let _ = child.wait();
                    *state = State::Over;
                    return;
                }
                State::Over => return,
                // The watcher decides: it ends the process, or gives up and says Over.
                State::Running(_) | State::SecondWon => {}
            }
            drop(state);
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

impl Drop for FastStart {
    fn drop(&mut self) {
        self.settle(false);
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn lock(m: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes staging folders of processes that are gone (killed before they could).
fn remove_stale_folders() {
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let pid = name
            .strip_prefix("illum-fast-start-")
            .and_then(|rest| rest.split('-').next())
            .and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid
            && !Path::new(&format!("/proc/{pid}")).exists()
        {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Whether a second process runs: on llvmpipe, where `mode` and the machine allow it (unless
/// asked for whatever the load, not for kernels `key` says are in Mesa's cache), and never from
/// a second process.
fn wanted(
    mode: Mode,
    since: Option<CpuTimes>,
    ctx: &crate::vk::Context,
    bytes: u64,
    key: &str,
) -> bool {
    let llvmpipe = ctx.info().driver_id == ash::vk::DriverId::MESA_LLVMPIPE;
    let allowed = match mode {
        Mode::Off => false,
        Mode::Auto => {
            !known_warm(key)
                && idle_core(since)
                && crate::film::memory::available_bytes().is_some_and(|a| a / 2 >= bytes)
        }
        Mode::On | Mode::Wait => true,
    };
    llvmpipe && allowed && staging().is_none()
}

/// Creates the staging folder of this process's second process: a new one, private (0700),
/// never a name that exists already (one made by another user could lead elsewhere).
fn folder() -> std::io::Result<PathBuf> {
    use std::os::unix::fs::DirBuilderExt;
    remove_stale_folders();
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let name = format!("illum-fast-start-{}-{nanos:09}", std::process::id());
    let dir = std::env::temp_dir().join(name);
    std::fs::DirBuilder::new().mode(0o700).create(&dir)?;
    Ok(dir)
}

/// Polls the second process. When it succeeds first, moves its outputs into place, prints its
/// messages and ends this process with its status (0). When it fails, says so and leaves the
/// render to this process.
fn watch(
    state: &Mutex<State>,
    dir: &Path,
    outputs: &Outputs,
    out: Capture,
    err: Capture,
    bar: &ProgressBar,
) {
    let status = loop {
        std::thread::sleep(Duration::from_millis(10));
        let mut s = lock(state);
        let State::Running(child) = &mut *s else {
            return; // this process took over
        };
        if super::signal::received().is_some() {
            // Interrupted: this process writes what it has and says so in its exit status (the
            // second process's image would hide the interruption); the second one stops now.
            let _ = child.kill();
            let _ = child.wait();
            *s = State::Over;
            return;
        }
        match child.try_wait() {
            Ok(None) => continue,
            Ok(Some(status)) if status.success() => {
                *s = State::SecondWon;
                break status;
            }
            Ok(Some(status)) => {
                *s = State::Over;
                drop(s);
                let last = last_line(err);
                bar.suspend(|| {
                    crate::note!(
                        "illum: note: the fast-start process (unoptimised kernels) failed \
                         ({status}): {last}; this process renders the image"
                    )
                });
                return;
            }
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                *s = State::Over;
                drop(s);
                bar.suspend(|| crate::note!("illum: note: the fast-start process was lost: {e}"));
                return;
            }
        }
    };
    if let Err(e) = outputs.iter().try_for_each(|(from, to)| place(from, to)) {
        *lock(state) = State::Over;
        bar.suspend(|| {
            crate::note!(
                "illum: note: the fast-start process's image could not be moved into place \
                 ({e}); this process renders it"
            )
        });
        return;
    }
    bar.finish_and_clear();
    let (o, e) = (
        out.join().unwrap_or_default(),
        err.join().unwrap_or_default(),
    );
    let mut stdout = std::io::stdout().lock();
    let _ = stdout.write_all(&o);
    let _ = stdout.flush();
    let mut stderr = std::io::stderr().lock();
    let _ = stderr.write_all(&e);
    if !e.is_empty() {
        let _ = writeln!(
            stderr,
            "illum: fast start: this image is the second process's, rendered with the driver's \
             unoptimised kernels (GALLIVM_PERF=nopt) before the optimised ones had compiled; the \
             same pixels"
        );
    }
    let _ = stderr.flush();
    let _ = std::fs::remove_dir_all(dir);
    compile_in_background();
    // SAFETY: ends the process at once. Not exit(): its handlers would wait for the driver's
    // queue thread, which is still compiling kernels that `compile_in_background` now compiles.
    unsafe { libc::_exit(status.code().unwrap_or(0)) }
}

/// Set in the environment of the process that [`compile_in_background`] starts.
const COMPILE_ENV: &str = "ILLUM_FAST_START_COMPILE";

/// Whether this process only compiles the optimised kernels into the driver's cache (see
/// [`compile_in_background`]).
pub(super) fn compile_only() -> bool {
    std::env::var_os(COMPILE_ENV).is_some()
}

/// When the second process won, the optimised kernels were never compiled, so Mesa's disk cache
/// does not have them and the next render of these features would compile them again (and the
/// next short one race again, at 1.2–1.5 s where a warm start takes 1 s). This process's last
/// act: start this program again with the same arguments to compile them and nothing else, in
/// the background (its own session, the lowest priority, no output), and not wait for it. Not
/// where Mesa's cache is off.
fn compile_in_background() {
    use std::os::unix::process::CommandExt;
    if mesa_cache_off() {
        return;
    }
    if background_compile_running() {
        return; // one at a time: a loop of short renders must not pile them up
    }
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    let mut cmd = Command::new(exe);
    cmd.args(std::env::args_os().skip(1))
        .env(COMPILE_ENV, "1")
        .env(MODE_ENV, "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    // SAFETY: setsid and setpriority are async-signal-safe.
    unsafe {
        cmd.pre_exec(|| {
            libc::setsid();
            libc::setpriority(libc::PRIO_PROCESS, 0, 19);
            Ok(())
        });
    }
    let _ = cmd.spawn();
}

/// Whether Mesa's disk cache is turned off.
fn mesa_cache_off() -> bool {
    let off = |k| std::env::var(k).is_ok_and(|v| matches!(v.as_str(), "1" | "true" | "yes"));
    off("MESA_SHADER_CACHE_DISABLE") || off("MESA_DISK_CACHE_DISABLE")
}

/// Whether a background compile of this user's is running (its environment says so).
fn background_compile_running() -> bool {
    let marker = format!("{COMPILE_ENV}=1");
    std::fs::read_dir("/proc").is_ok_and(|entries| {
        entries.flatten().any(|e| {
            std::fs::read(e.path().join("environ"))
                .is_ok_and(|env| env.split(|&b| b == 0).any(|var| var == marker.as_bytes()))
        })
    })
}

/// Puts a staged output where it belongs the way every output is written
/// (`output::write_atomically`: through a symbolic link, keeping a replaced file's permissions,
/// synced, a temporary file renamed over it, removed by a second Ctrl-C).
fn place(from: &Path, to: &Path) -> Result<(), crate::output::OutputError> {
    crate::output::write_atomically(to, |tmp| {
        std::fs::copy(from, tmp)
            .map(|_| ())
            .map_err(|cause| crate::output::OutputError::Io {
                path: to.to_path_buf(),
                cause,
            })
    })
}

type Capture = JoinHandle<Vec<u8>>;

/// The last line of a captured output that is not blank (what a failed process said last).
fn last_line(c: Capture) -> String {
    let text = String::from_utf8_lossy(&c.join().unwrap_or_default()).into_owned();
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .to_string()
}

/// The second process: this program with the same arguments, the staging folder in its
/// environment, LLVM's optimisations off, the lowest CPU priority, its own process group (a
/// Ctrl-C at the terminal goes to this process, which stops it), killed if this process dies
/// first.
fn spawn(dir: &Path) -> std::io::Result<(Child, Capture, Capture)> {
    use std::os::unix::process::CommandExt;
    let exe = std::env::current_exe()?;
    let perf = match std::env::var("GALLIVM_PERF") {
        Ok(v) if !v.is_empty() => format!("{v},nopt"),
        _ => "nopt".to_string(),
    };
    let mut cmd = Command::new(exe);
    cmd.args(std::env::args_os().skip(1))
        .env(CHILD_ENV, dir)
        .env("GALLIVM_PERF", perf)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0);
    // SAFETY: prctl and setpriority are async-signal-safe; nothing else runs between fork and
    // exec.
    unsafe {
        cmd.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // The lowest priority: the second process takes the time this one leaves idle, and
            // never slows the compile it races (its render threads would).
            if libc::setpriority(libc::PRIO_PROCESS, 0, 19) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let mut child = cmd.spawn()?;
    let capture = |r: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            buf
        })
    };
    let out = capture(
        child
            .stdout
            .take()
            .map(|s| Box::new(s) as Box<dyn Read + Send>),
    );
    let err = capture(
        child
            .stderr
            .take()
            .map(|s| Box::new(s) as Box<dyn Read + Send>),
    );
    Ok((child, out, err))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_parse_and_a_bad_one_is_named() {
        assert_eq!(parse_mode(None).unwrap(), Mode::Auto);
        assert_eq!(parse_mode(Some("0")).unwrap(), Mode::Off);
        assert_eq!(parse_mode(Some("1")).unwrap(), Mode::On);
        assert_eq!(parse_mode(Some("wait")).unwrap(), Mode::Wait);
        let e = parse_mode(Some("yes")).unwrap_err().to_string();
        assert!(e.contains("ILLUM_FAST_START=\"yes\""), "{e}");
    }

    #[test]
    fn idle_time_is_counted_in_cores() {
        let a = parse_cpu_line("cpu  100 0 50 1000 10 0 0 0 0 0").unwrap();
        // 40 ticks on 2 cores: 20 busy, 18 idle and 2 waiting: one core's worth idle.
        let b = parse_cpu_line("cpu  115 0 55 1018 12 0 0 0 0 0").unwrap();
        assert_eq!((a.idle, a.total), (1010, 1160));
        // Niced time counts as idle.
        assert_eq!(parse_cpu_line("cpu  1 7 1 10 2 0 0 0").unwrap().idle, 19);
        assert!((idle_cores(a, b, 2) - 1.0).abs() < 1e-12);
        assert!(parse_cpu_line("cpu0 1 2 3 4").is_none());
    }

    #[test]
    fn staged_outputs_keep_their_names() {
        let d = Path::new("/s");
        assert_eq!(staged(d, Path::new("out/a.png")), Path::new("/s/a.png"));
        assert_eq!(staged(d, Path::new("a.exr")), Path::new("/s/a.exr"));
    }
}
