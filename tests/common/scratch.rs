//! The tests' scratch folders: each test process writes under $TMPDIR/illum-tests/<its pid>/, and
//! the first use in a process removes the folders of processes that are no longer running (a test
//! binary has no hook at its exit, so each run cleans up after the ones before it).

use std::path::{Path, PathBuf};
use std::sync::Once;

/// This process's scratch folder (made if need be).
pub fn scratch_root() -> PathBuf {
    let root = std::env::temp_dir().join("illum-tests");
    static SWEEP: Once = Once::new();
    SWEEP.call_once(|| sweep(&root));
    let dir = root.join(std::process::id().to_string());
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A fresh, empty folder `name` in this process's scratch folder.
#[allow(dead_code)] // capi.rs takes only the root
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = scratch_root().join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Removes the scratch folders of processes that have ended (Linux: /proc/<pid> is gone).
fn sweep(root: &Path) {
    let Ok(entries) = std::fs::read_dir(root) else {
        return;
    };
    for e in entries.flatten() {
        let Some(pid) = e.file_name().to_str().and_then(|s| s.parse::<u32>().ok()) else {
            continue;
        };
        if cfg!(target_os = "linux")
            && pid != std::process::id()
            && !Path::new(&format!("/proc/{pid}")).exists()
        {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}
