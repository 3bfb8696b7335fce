//! `illum devices`: every Vulkan device, its driver, memory and ray-query support.

use anyhow::{Result, bail};

pub fn run() -> Result<()> {
    let list = crate::vk::list_devices()?;
    if list.is_empty() {
        bail!("no Vulkan device found");
    }
    for d in list {
        println!(
            "{}: {} ({})\n    driver: {}\n    Vulkan {}, {:.1} GiB device-local memory, ray query: {}{}",
            d.index,
            d.name,
            d.kind,
            d.driver,
            d.api_version,
            d.device_local_memory as f64 / (1u64 << 30) as f64,
            if d.ray_query { "yes" } else { "no" },
            if d.missing.is_empty() {
                String::new()
            } else {
                format!("\n    unusable: lacks {}", d.missing.join(", "))
            }
        );
    }
    Ok(())
}
