//! Writing outputs safely: every file is written under a temporary name in its own folder and
//! renamed over the target, so a crash or an interrupted write never leaves a half-written image
//! or report; and output paths are checked before a render starts, not after it.

use super::OutputError;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// The temporary file `write_atomically` writes `path` to first: in the same folder (a rename
/// within one file system is atomic), hidden, named after the process, ending in the target's own
/// extension (image encoders pick the format from it).
pub fn temp_path_for(path: &Path) -> PathBuf {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let name = path.file_name().unwrap_or_default();
    let mut tmp = OsString::from(".");
    tmp.push(name);
    tmp.push(format!(
        ".illum-tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    if let Some(ext) = path.extension() {
        tmp.push(".");
        tmp.push(ext);
    }
    path.with_file_name(tmp)
}

/// Runs `write` on a temporary path beside `path`, then renames it to `path`. On any error the
/// temporary file is removed and `path` is left as it was.
pub fn write_atomically<E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = temp_path_for(path);
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).map_err(|cause| {
            E::from(OutputError::Io {
                path: path.to_path_buf(),
                cause,
            })
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Checks, before any work, that `path` can be written: it is not a folder, and its folder
/// exists, is a folder and takes a new file (probed by creating and removing one).
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    let fail = |reason: String| OutputError::NotWritable {
        path: path.to_path_buf(),
        reason,
    };
    if path.as_os_str().is_empty() {
        return Err(fail("the path is empty".into()));
    }
    if path.is_dir() {
        return Err(fail("it is a folder; name a file in it".into()));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
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
    let probe = temp_path_for(path);
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
}
