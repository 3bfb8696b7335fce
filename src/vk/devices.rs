//! Physical devices: what each offers (`illum devices`), and which one illum picks.

use super::context::{create_instance, load_entry};
use super::error::{Error, Result, VkResultExt};
use ash::vk;
use std::ffi::CStr;

/// What a physical device offers, as listed by `illum devices`.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: &'static str,
    pub driver: String,
    /// VkDriverId (e.g. MESA_LLVMPIPE for lavapipe), for choices that depend on the driver.
    pub driver_id: vk::DriverId,
    pub api_version: String,
    /// Sum of the device-local heaps, in bytes.
    pub device_local_memory: u64,
    /// VK_KHR_ray_query and VK_KHR_acceleration_structure with their features.
    pub ray_query: bool,
    /// Missing features illum needs (empty when usable).
    pub missing: Vec<String>,
}

fn kind_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

fn kind_rank(kind: &str) -> u32 {
    match kind {
        "discrete GPU" => 4,
        "integrated GPU" => 3,
        "virtual GPU" => 2,
        "CPU" => 1,
        _ => 0,
    }
}

fn has_ext(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name))
}

/// # Safety
/// `pd` must be a physical device of `instance`.
pub(crate) unsafe fn describe(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    index: usize,
) -> DeviceInfo {
    unsafe {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        instance.get_physical_device_properties2(pd, &mut props2);
        let props = props2.properties;
        let mem = instance.get_physical_device_memory_properties(pd);
        let local: u64 = mem.memory_heaps[..mem.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .sum();
        let exts = instance
            .enumerate_device_extension_properties(pd)
            .unwrap_or_default();
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
        let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
        let rq_exts = has_ext(&exts, ash::khr::acceleration_structure::NAME)
            && has_ext(&exts, ash::khr::ray_query::NAME)
            && has_ext(&exts, ash::khr::deferred_host_operations::NAME);
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
        if rq_exts {
            f2 = f2.push_next(&mut fas).push_next(&mut frq);
        }
        instance.get_physical_device_features2(pd, &mut f2);
        let int64 = f2.features.shader_int64 == vk::TRUE;
        let mut missing = Vec::new();
        if props.api_version < vk::API_VERSION_1_2 {
            missing.push("Vulkan 1.2".to_string());
        }
        if f12.buffer_device_address != vk::TRUE {
            missing.push("bufferDeviceAddress".into());
        }
        if f12.scalar_block_layout != vk::TRUE {
            missing.push("scalarBlockLayout".into());
        }
        if !int64 {
            missing.push("shaderInt64".into());
        }
        let v = props.api_version;
        DeviceInfo {
            index,
            name: props
                .device_name_as_c_str()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            kind: kind_name(props.device_type),
            driver_id: driver.driver_id,
            driver: format!(
                "{} {}",
                driver
                    .driver_name_as_c_str()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                driver
                    .driver_info_as_c_str()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            )
            .trim()
            .to_string(),
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
            device_local_memory: local,
            ray_query: rq_exts
                && fas.acceleration_structure == vk::TRUE
                && frq.ray_query == vk::TRUE,
            missing,
        }
    }
}

/// Every Vulkan device of this machine.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let entry = load_entry()?;
    let instance = create_instance(&entry, false, &[])?;
    // SAFETY: the instance is valid and destroyed once, below.
    unsafe {
        let pds = instance.enumerate_physical_devices();
        let out = pds.map(|pds| {
            pds.iter()
                .enumerate()
                .map(|(i, &pd)| describe(&instance, pd, i))
                .collect()
        });
        instance.destroy_instance(None);
        out.vk("vkEnumeratePhysicalDevices")
    }
}

pub(crate) fn pick(infos: &[DeviceInfo], want: Option<&str>) -> Result<usize> {
    let listing = || {
        infos
            .iter()
            .map(|d| format!("{}: {} ({})", d.index, d.name, d.kind))
            .collect::<Vec<_>>()
            .join("; ")
    };
    if infos.is_empty() {
        return Err(Error::NoDevice(
            "the Vulkan loader reports no device (install a driver, e.g. mesa-vulkan-drivers)"
                .into(),
        ));
    }
    if let Some(w) = want {
        let found = match w.parse::<usize>() {
            Ok(i) => infos.iter().find(|d| d.index == i),
            Err(_) => {
                let wl = w.to_lowercase();
                infos.iter().find(|d| d.name.to_lowercase().contains(&wl))
            }
        };
        let d = found.ok_or_else(|| {
            Error::NoDevice(format!("--device {w:?} matches none of: {}", listing()))
        })?;
        if !d.missing.is_empty() {
            return Err(Error::Unsupported {
                device: d.name.clone(),
                what: format!("it lacks {}", d.missing.join(", ")),
            });
        }
        return Ok(d.index);
    }
    infos
        .iter()
        .filter(|d| d.missing.is_empty())
        .max_by_key(|d| (kind_rank(d.kind), d.ray_query, std::cmp::Reverse(d.index)))
        .map(|d| d.index)
        .ok_or_else(|| {
            Error::NoDevice(format!(
                "no device has what illum needs (Vulkan 1.2, bufferDeviceAddress, scalarBlockLayout, shaderInt64): {}",
                listing()
            ))
        })
}
