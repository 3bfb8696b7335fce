//! A persistent `VkPipelineCache`: read from a file when the context is created, written back
//! (through a temporary file and a rename) after each pipeline creation, so that a later run
//! creates its kernels from the cache where the driver keeps them there. The file is named after
//! the device and driver (vendor, device, driver version, pipelineCacheUUID) and its header is
//! checked against the device before the driver sees it: a stale or damaged file is ignored.
//!
//! Where: `$ILLUM_CACHE_DIR`, else `$XDG_CACHE_HOME/illum`, else `~/.cache/illum`;
//! `ILLUM_PIPELINE_CACHE=0` turns it off.

use ash::vk;
use std::path::PathBuf;

/// The cache file for a device with these properties, None when turned off or no folder is known.
pub(crate) fn path(props: &vk::PhysicalDeviceProperties) -> Option<PathBuf> {
    if std::env::var("ILLUM_PIPELINE_CACHE").is_ok_and(|v| v == "0") {
        return None;
    }
    let dir = cache_dir()?;
    let uuid: String = props
        .pipeline_cache_uuid
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    Some(dir.join(format!(
        "pipelines-{:04x}-{:04x}-{:x}-{uuid}.bin",
        props.vendor_id, props.device_id, props.driver_version
    )))
}

/// illum's cache folder: `$ILLUM_CACHE_DIR`, else `$XDG_CACHE_HOME/illum`, else
/// `~/.cache/illum`.
pub fn cache_dir() -> Option<PathBuf> {
    let env = |k| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    env("ILLUM_CACHE_DIR")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("illum")))
        .or_else(|| env("HOME").map(|h| h.join(".cache").join("illum")))
}

/// The file's data if its header (VkPipelineCacheHeaderVersionOne) is this device's.
pub(crate) fn initial_data(path: &PathBuf, props: &vk::PhysicalDeviceProperties) -> Vec<u8> {
    let Ok(data) = std::fs::read(path) else {
        return Vec::new();
    };
    let word = |i: usize| {
        data.get(4 * i..4 * i + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("four bytes")))
    };
    let ours = word(0) == Some(32)
        && word(1) == Some(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32)
        && word(2) == Some(props.vendor_id)
        && word(3) == Some(props.device_id)
        && data.get(16..32) == Some(&props.pipeline_cache_uuid[..]);
    if ours { data } else { Vec::new() }
}

/// Writes the cache's data to `path` (a temporary file renamed over it: a reader never sees
/// half a file). Failures are noted, never fatal: the cache only saves time.
pub(crate) fn save(device: &ash::Device, cache: vk::PipelineCache, path: &PathBuf) {
    // SAFETY: a live cache of this device.
    let data = match unsafe { device.get_pipeline_cache_data(cache) } {
        Ok(d) => d,
        Err(e) => {
            crate::note!("illum: note: the pipeline cache could not be read back: {e}");
            return;
        }
    };
    if data.len() <= 32 {
        return; // only the header: the driver keeps nothing here (lavapipe)
    }
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let written = path
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| std::fs::write(&tmp, &data))
        .and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        crate::note!(
            "illum: note: the pipeline cache was not saved to {}: {e}",
            path.display()
        );
    }
}
