//! Writing outputs safely. Every file is written under a temporary name in its target's folder,
//! flushed to disk, and renamed over the target, so a crash, a power loss or an interrupted write
//! never leaves a half-written image or report; output paths are checked before a render starts,
//! not after it.
//!
//! The policy for an existing target (docs/outputs.md):
//! - a symbolic link is written through: the file it names is replaced, the link stays;
//! - a regular file is replaced and keeps its permissions; a write-protected one (no write bit
//!   set) is refused, as are folders, devices, fifos and sockets;
//! - temporary files that a killed process left beside a target (`.NAME.illum-tmp-PID-N.ext`,
//!   whose process is gone) are removed by the next write to that folder.

use super::OutputError;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};

/// The marker in a temporary file's name, between the target's name and the process id.
const TEMP_MARK: &str = ".illum-tmp-";

/// The temporary file `write_atomically` writes `path` to first: in the same folder (a rename
/// within one file system is atomic), hidden, named after the process, ending in the target's own
/// extension (image encoders pick the format from it).
pub fn temp_path_for(path: &Path) -> PathBuf {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let name = path.file_name().unwrap_or_default();
    let mut tmp = OsString::from(".");
    tmp.push(name);
    tmp.push(format!(
        "{TEMP_MARK}{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    if let Some(ext) = path.extension() {
        tmp.push(".");
        tmp.push(ext);
    }
    path.with_file_name(tmp)
}

/// Writes in progress, and whether a signal asked to abandon them (see [`abort_writes`]).
static WRITING: AtomicUsize = AtomicUsize::new(0);
static ABORT: AtomicBool = AtomicBool::new(false);

/// Asks every write in progress to remove its temporary file and fail, and every later one to fail
/// at once. Returns whether a write was in progress (then the caller must let it clean up rather
/// than end the process). Async-signal-safe: atomics only.
pub fn abort_writes() -> bool {
    ABORT.store(true, Ordering::SeqCst);
    WRITING.load(Ordering::SeqCst) > 0
}

/// Counts a write in progress for [`abort_writes`].
struct InProgress;

impl InProgress {
    fn start(path: &Path) -> Result<InProgress, OutputError> {
        WRITING.fetch_add(1, Ordering::SeqCst);
        let guard = InProgress;
        guard.check(path)?;
        Ok(guard)
    }
    fn check(&self, path: &Path) -> Result<(), OutputError> {
        if ABORT.load(Ordering::SeqCst) {
            return Err(OutputError::Aborted {
                path: path.to_path_buf(),
            });
        }
        Ok(())
    }
}

impl Drop for InProgress {
    fn drop(&mut self) {
        WRITING.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Runs `write` on a temporary path beside the file `path` names (through symbolic links), flushes
/// it to disk, gives it the replaced file's permissions, renames it over that file and flushes the
/// folder. On any error, or when [`abort_writes`] was called, the temporary file is removed and
/// the target is left as it was.
pub fn write_atomically<E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let target = resolve_target(path)?;
    let existing = existing_target(&target)?;
    remove_stale_temps(&target);
    let guard = InProgress::start(path)?;
    let tmp = temp_path_for(&target);
    let io = |cause| OutputError::Io {
        path: path.to_path_buf(),
        cause,
    };
    let result = write(&tmp).and_then(|()| {
        guard.check(path)?;
        if let Some(meta) = &existing {
            std::fs::set_permissions(&tmp, meta.permissions()).map_err(io)?;
        }
        std::fs::File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(io)?;
        guard.check(path)?;
        std::fs::rename(&tmp, &target).map_err(io)?;
        sync_folder(&target).map_err(io)?;
        Ok(())
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(guard);
    result
}

/// Flushes the folder of `path`, so that a rename in it survives a power loss. File systems that
/// cannot flush a folder (EINVAL) are taken as they are.
fn sync_folder(path: &Path) -> std::io::Result<()> {
    let dir = folder_of(path);
    match std::fs::File::open(dir).and_then(|d| d.sync_all()) {
        Err(e) if e.raw_os_error() == Some(libc::EINVAL) => Ok(()),
        r => r,
    }
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The file a write to `path` replaces: `path` itself, or the file its chain of symbolic links
/// names (which need not exist yet).
pub fn resolve_target(path: &Path) -> Result<PathBuf, OutputError> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&p).map_err(|cause| OutputError::Io {
                    path: path.to_path_buf(),
                    cause,
                })?;
                p = folder_of(&p).join(link);
            }
            _ => return Ok(p),
        }
    }
    Err(OutputError::NotWritable {
        path: path.to_path_buf(),
        reason: "its symbolic links loop or nest more than 40 deep".into(),
    })
}

/// The metadata of the file that `target` (already resolved) would replace, after checking that
/// it may be replaced: a regular file with a write permission bit set.
fn existing_target(target: &Path) -> Result<Option<std::fs::Metadata>, OutputError> {
    let fail = |reason: String| OutputError::NotWritable {
        path: target.to_path_buf(),
        reason,
    };
    let meta = match std::fs::metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(fail(crate::scene::io_message(&e))),
    };
    if meta.is_dir() {
        return Err(fail("it is a folder; name a file in it".into()));
    }
    if !meta.is_file() {
        return Err(fail(
            "it exists and is not a regular file (a device, fifo or socket): illum replaces only files"
                .into(),
        ));
    }
    if meta.permissions().readonly() {
        use std::os::unix::fs::PermissionsExt;
        return Err(fail(format!(
            "it is write-protected (mode {:04o}): illum does not replace a protected file; \
             remove it or make it writable",
            meta.permissions().mode() & 0o7777
        )));
    }
    Ok(Some(meta))
}

/// Removes the temporary files of `target` that processes no longer running left behind (a
/// SIGKILL or a power loss mid-write). A process id that is in use again is left alone.
fn remove_stale_temps(target: &Path) {
    let Some(name) = target.file_name().and_then(|n| n.to_str()) else {
        return;
    };
    let prefix = format!(".{name}{TEMP_MARK}");
    let Ok(entries) = std::fs::read_dir(folder_of(target)) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(rest) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<i32>().ok()) else {
            continue;
        };
        if pid > 0 && !process_exists(pid) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

fn process_exists(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only checks for the process.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

/// Whether `a` and `b` name the same file, existing or to be created (through symbolic links,
/// `.` and `..`, and hard links).
pub fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        return ma.dev() == mb.dev() && ma.ino() == mb.ino();
    }
    let canonical = |p: &Path| -> Option<PathBuf> {
        let t = resolve_target(p).ok()?;
        let dir = std::fs::canonicalize(folder_of(&t)).ok()?;
        Some(dir.join(t.file_name()?))
    };
    matches!((canonical(a), canonical(b)), (Some(x), Some(y)) if x == y)
}

/// Checks that no output would replace an input or another output: each pair named, so that
/// `--report x.exr -o x.exr` or `merge a.exr b.exr -o b.exr` fails before any work.
pub fn check_distinct(
    outputs: &[(&str, &Path)],
    inputs: &[(&str, &Path)],
) -> Result<(), OutputError> {
    for (k, (what, out)) in outputs.iter().enumerate() {
        let clash = outputs[..k]
            .iter()
            .map(|(w, p)| (format!("the {w} output"), p))
            .chain(inputs.iter().map(|(w, p)| (format!("the {w}"), p)))
            .find(|(_, p)| same_file(out, p));
        if let Some((other, p)) = clash {
            return Err(OutputError::NotWritable {
                path: out.to_path_buf(),
                reason: format!(
                    "the {what} output would replace {other} ({}); name another file",
                    p.display()
                ),
            });
        }
    }
    Ok(())
}

/// Checks, before any work, that `path` can be written: a file that may be replaced or none, in
/// a folder that exists and takes a new file (probed by creating and removing one).
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    let fail = |reason: String| OutputError::NotWritable {
        path: path.to_path_buf(),
        reason,
    };
    if path.as_os_str().is_empty() {
        return Err(fail("the path is empty".into()));
    }
    let target = resolve_target(path)?;
    let dir = folder_of(&target);
    match std::fs::metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(fail(format!("the folder {} does not exist", dir.display())));
        }
        Err(e) => return Err(fail(format!("the folder {}: {e}", dir.display()))),
        Ok(m) if !m.is_dir() => {
            return Err(fail(format!("{} is not a folder", dir.display())));
        }
        Ok(_) => {}
    }
    existing_target(&target).map_err(|e| match e {
        OutputError::NotWritable { reason, .. } => fail(reason),
        e => e,
    })?;
    remove_stale_temps(&target);
    let probe = temp_path_for(&target);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| {
            fail(format!(
                "cannot create a file in the folder {}: {}",
                dir.display(),
                crate::scene::io_message(&e)
            ))
        })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("illum-file-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn temp_path_keeps_folder_and_extension() {
        let t = temp_path_for(Path::new("out/dir/a.b.png"));
        assert_eq!(t.parent(), Some(Path::new("out/dir")));
        assert_eq!(t.extension().unwrap(), "png");
        assert!(
            t.file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .starts_with(".a.b.png.illum-tmp-")
        );
    }

    #[test]
    fn failed_write_leaves_target_and_no_temp_file() {
        let d = dir("atomic");
        let target = d.join("x.txt");
        std::fs::write(&target, "old").unwrap();
        let r: Result<(), OutputError> = write_atomically(&target, |tmp| {
            std::fs::write(tmp, "half").unwrap();
            Err(OutputError::NotWritable {
                path: target.clone(),
                reason: "test".into(),
            })
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old");
        write_atomically::<OutputError>(&target, |tmp| {
            std::fs::write(tmp, "new").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            1,
            "a temporary file is left"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn check_names_the_problem() {
        let d = dir("check");
        let msg = |p: &Path| check_writable(p).unwrap_err().to_string();
        assert!(msg(&d).contains("is a folder"));
        let m = msg(&d.join("missing/x.exr"));
        assert!(m.contains("missing") && m.contains("does not exist"), "{m}");
        std::fs::write(d.join("file"), "").unwrap();
        assert!(msg(&d.join("file/x.exr")).contains("is not a folder"));
        check_writable(&d.join("ok.exr")).unwrap();
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn writes_through_links_and_keeps_the_mode() {
        use std::os::unix::fs::PermissionsExt;
        let d = dir("policy");
        let real = d.join("real.txt");
        std::fs::write(&real, "old").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = d.join("link.txt");
        std::os::unix::fs::symlink("real.txt", &link).unwrap();
        check_writable(&link).unwrap();
        write_atomically::<OutputError>(&link, |tmp| {
            std::fs::write(tmp, "new").unwrap();
            Ok(())
        })
        .unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "new");
        let mode = std::fs::metadata(&real).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
        // A dangling link names the file to create.
        let dangling = d.join("dangling.txt");
        std::os::unix::fs::symlink("made.txt", &dangling).unwrap();
        write_atomically::<OutputError>(&dangling, |tmp| {
            std::fs::write(tmp, "made").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(d.join("made.txt")).unwrap(), "made");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn refuses_protected_files_and_non_files() {
        use std::os::unix::fs::PermissionsExt;
        let d = dir("protected");
        let ro = d.join("ro.exr");
        std::fs::write(&ro, "keep").unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).unwrap();
        let m = check_writable(&ro).unwrap_err().to_string();
        assert!(m.contains("write-protected") && m.contains("0444"), "{m}");
        let r: Result<(), OutputError> = write_atomically(&ro, |tmp| {
            std::fs::write(tmp, "new").unwrap();
            Ok(())
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&ro).unwrap(), "keep");
        let fifo = d.join("fifo.exr");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid C string.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
        let m = check_writable(&fifo).unwrap_err().to_string();
        assert!(m.contains("not a regular file"), "{m}");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn removes_the_temporary_files_of_dead_processes() {
        let d = dir("stale");
        let target = d.join("x.exr");
        // A process id that is not running: a child that has exited and been reaped.
        let dead = std::process::Command::new("true").spawn().unwrap();
        let pid = dead.id();
        let mut dead = dead;
        dead.wait().unwrap();
        let stale = d.join(format!(".x.exr{TEMP_MARK}{pid}-3.exr"));
        let live = d.join(format!(".x.exr{TEMP_MARK}{}-9.exr", std::process::id()));
        let other = d.join(format!(".y.exr{TEMP_MARK}{pid}-3.exr"));
        for p in [&stale, &live, &other] {
            std::fs::write(p, "tmp").unwrap();
        }
        check_writable(&target).unwrap();
        assert!(!stale.exists(), "the dead process's temporary file is left");
        assert!(live.exists() && other.exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn outputs_must_not_replace_inputs() {
        let d = dir("distinct");
        let a = d.join("a.exr");
        std::fs::write(&a, "in").unwrap();
        let via_dots = d.join("sub/../a.exr");
        std::fs::create_dir_all(d.join("sub")).unwrap();
        let e = check_distinct(&[("image", &via_dots)], &[("reference", &a)]).unwrap_err();
        assert!(e.to_string().contains("would replace the reference"), "{e}");
        let r = d.join("new.csv");
        let e = check_distinct(&[("image", &r), ("report", &r)], &[]).unwrap_err();
        assert!(e.to_string().contains("the image output"), "{e}");
        check_distinct(&[("image", &r)], &[("reference", &a)]).unwrap();
        std::fs::remove_dir_all(&d).unwrap();
    }
}
