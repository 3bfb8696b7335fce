//! The note of kernels compiled with LLVM's optimisations (see the parent module): no automatic
//! fast start for them.

use std::path::{Path, PathBuf};

/// Kernels compiled with LLVM's optimisations into Mesa's cache on this machine, by a key of what
/// decides them (see [`warm_key`]): for them a second process is no gain (the view's warm start
/// would pay for it). A file of recent keys in illum's cache folder; a key whose kernels Mesa
/// has since dropped only costs a fast start that does not happen.
fn warm_file() -> Option<PathBuf> {
    crate::vk::cache_dir().map(|d| d.join("warm-kernels.txt"))
}

/// What decides the kernels of this command: the program (its size and time), its arguments
/// but the outputs and display settings, the scene file's size and time, the device, and where
/// Mesa keeps its cache.
pub(in crate::cli) fn warm_key(ctx: &crate::vk::Context, scene: Option<&Path>) -> String {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let stamp = |p: &Path| {
        std::fs::metadata(p)
            .ok()
            .map(|m| (m.len(), m.modified().ok()))
    };
    std::env::current_exe()
        .ok()
        .as_deref()
        .map(stamp)
        .hash(&mut h);
    scene.map(stamp).hash(&mut h);
    const SKIP: [&str; 7] = [
        "-o",
        "--output",
        "--report",
        "--report-plot",
        "--screenshot",
        "--frames",
        "--scale",
    ];
    let mut skip_next = false;
    for a in std::env::args_os().skip(1) {
        let s = a.to_string_lossy();
        if std::mem::take(&mut skip_next) {
            continue;
        }
        if SKIP.contains(&s.as_ref()) {
            skip_next = true;
            continue;
        }
        if SKIP.iter().any(|k| s.starts_with(&format!("{k}="))) {
            continue;
        }
        s.hash(&mut h);
    }
    for k in [
        "MESA_SHADER_CACHE_DIR",
        "XDG_CACHE_HOME",
        "HOME",
        "GALLIVM_PERF",
        "LP_NATIVE_VECTOR_WIDTH",
    ] {
        std::env::var_os(k).hash(&mut h);
    }
    let info = ctx.info();
    (&info.name, &info.driver).hash(&mut h);
    format!("{:016x}", h.finish())
}

/// Whether these kernels are known to be in Mesa's cache.
pub(super) fn known_warm(key: &str) -> bool {
    warm_file()
        .and_then(|f| std::fs::read_to_string(f).ok())
        .is_some_and(|t| t.lines().any(|l| l == key))
}

/// Notes that these kernels are in Mesa's cache (the last 256 keys kept; written through a
/// rename, failures ignored: it only saves time).
pub(in crate::cli) fn mark_warm(key: &str) {
    if super::mesa_cache_off() {
        return; // nothing stays compiled
    }
    let Some(file) = warm_file() else { return };
    let text = std::fs::read_to_string(&file).unwrap_or_default();
    if text.lines().any(|l| l == key) {
        return;
    }
    let mut keys: Vec<&str> = text.lines().filter(|l| !l.is_empty()).collect();
    keys.push(key);
    let keep = &keys[keys.len().saturating_sub(256)..];
    let tmp = file.with_extension(format!("tmp-{}", std::process::id()));
    let written = file
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| std::fs::write(&tmp, keep.join("\n") + "\n"))
        .and_then(|()| std::fs::rename(&tmp, &file));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
}
