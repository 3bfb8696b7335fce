//! What an application must enable on its own device for illum to run on it: asked of the
//! device, not guessed, and checked again when the device is handed over
//! ([`super::Context::from_external`]).

use super::error::{Error, Result, VkResultExt};
use ash::vk;
use std::ffi::{CStr, CString};

/// Extensions and features of one way of running illum (with or without ray queries), in the
/// structs the host chains into its `VkDeviceCreateInfo`. Fields illum does not need stay false.
#[derive(Clone, Debug)]
pub struct FeatureSet {
    /// Lowest `VkPhysicalDeviceProperties::apiVersion` (and instance API version).
    pub api_version: u32,
    /// Device extensions to enable.
    pub extensions: Vec<CString>,
    pub features: vk::PhysicalDeviceFeatures,
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    /// illum needs nothing of Vulkan 1.3 (all false); kept so hosts merge one complete set.
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
    pub acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    pub ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR<'static>,
}

/// What illum needs of a physical device (see [`requirements`]).
#[derive(Clone, Debug)]
pub struct Requirements {
    /// The compute BVH path: what every device needs.
    pub base: FeatureSet,
    /// Hardware ray queries: `base` plus acceleration structures and ray queries. None when the
    /// device lacks them (illum then traces with its compute BVH).
    pub ray_query: Option<FeatureSet>,
    /// Capabilities of the queue illum submits to or records for.
    pub queue_flags: vk::QueueFlags,
    /// The first queue family with `queue_flags`, if any.
    pub queue_family: Option<u32>,
    /// What the device lacks of `base` (empty when illum can run on it).
    pub missing: Vec<String>,
}

const BASE_EXTENSIONS: &[&CStr] = &[];
fn owned(names: &[&CStr]) -> Vec<CString> {
    names.iter().map(|&n| n.to_owned()).collect()
}

const RQ_EXTENSIONS: &[&CStr] = &[
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_query::NAME,
    ash::khr::deferred_host_operations::NAME,
];

impl FeatureSet {
    fn base() -> FeatureSet {
        FeatureSet {
            api_version: vk::API_VERSION_1_2,
            extensions: owned(BASE_EXTENSIONS),
            features: vk::PhysicalDeviceFeatures::default().shader_int64(true),
            vulkan12: vk::PhysicalDeviceVulkan12Features::default()
                .buffer_device_address(true)
                .scalar_block_layout(true),
            vulkan13: vk::PhysicalDeviceVulkan13Features::default(),
            acceleration_structure: Default::default(),
            ray_query: Default::default(),
        }
    }

    fn with_ray_query() -> FeatureSet {
        FeatureSet {
            extensions: owned(RQ_EXTENSIONS),
            acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
                .acceleration_structure(true),
            ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true),
            ..Self::base()
        }
    }

    /// Whether any Vulkan 1.3 feature is asked for (none today).
    pub fn vulkan13_needed(&self) -> bool {
        let none = vk::PhysicalDeviceVulkan13Features::default();
        let bytes = |f: &vk::PhysicalDeviceVulkan13Features| -> Vec<vk::Bool32> {
            vec![
                f.robust_image_access,
                f.inline_uniform_block,
                f.pipeline_creation_cache_control,
                f.private_data,
                f.shader_demote_to_helper_invocation,
                f.shader_terminate_invocation,
                f.subgroup_size_control,
                f.compute_full_subgroups,
                f.synchronization2,
                f.texture_compression_astc_hdr,
                f.shader_zero_initialize_workgroup_memory,
                f.dynamic_rendering,
                f.shader_integer_dot_product,
                f.maintenance4,
            ]
        };
        bytes(&self.vulkan13) != bytes(&none)
    }

    /// True when this set enables ray queries.
    pub fn has_ray_query(&self) -> bool {
        self.ray_query.ray_query == vk::TRUE
    }

    /// The names of what `self` asks for and `enabled` lacks ("extension VK_KHR_ray_query",
    /// "feature VkPhysicalDeviceVulkan12Features::bufferDeviceAddress").
    pub fn missing_from(&self, enabled: &FeatureSet) -> Vec<String> {
        let mut out = Vec::new();
        for e in &self.extensions {
            if !enabled.extensions.contains(e) {
                out.push(format!("extension {}", e.to_string_lossy()));
            }
        }
        for (name, want, have) in self
            .flags()
            .into_iter()
            .zip(enabled.flags())
            .map(|((name, want), (_, have))| (name, want, have))
        {
            if want && !have {
                out.push(format!("feature {name}"));
            }
        }
        if enabled.api_version < self.api_version {
            out.push(format!(
                "Vulkan {}.{}",
                vk::api_version_major(self.api_version),
                vk::api_version_minor(self.api_version)
            ));
        }
        out
    }

    /// Every feature flag illum may ask for, by name.
    fn flags(&self) -> Vec<(&'static str, bool)> {
        let t = |b: vk::Bool32| b == vk::TRUE;
        vec![
            (
                "VkPhysicalDeviceFeatures::shaderInt64",
                t(self.features.shader_int64),
            ),
            (
                "VkPhysicalDeviceVulkan12Features::bufferDeviceAddress",
                t(self.vulkan12.buffer_device_address),
            ),
            (
                "VkPhysicalDeviceVulkan12Features::scalarBlockLayout",
                t(self.vulkan12.scalar_block_layout),
            ),
            (
                "VkPhysicalDeviceAccelerationStructureFeaturesKHR::accelerationStructure",
                t(self.acceleration_structure.acceleration_structure),
            ),
            (
                "VkPhysicalDeviceRayQueryFeaturesKHR::rayQuery",
                t(self.ray_query.ray_query),
            ),
        ]
    }

    /// Creates a device with exactly this set enabled and one queue of `queue_family`: for hosts
    /// (and tests) that have nothing of their own to add. The caller owns and destroys it.
    ///
    /// # Safety
    /// `instance` and `physical_device` must be valid; the device must be destroyed by the caller.
    pub unsafe fn create_device(
        &self,
        instance: &ash::Instance,
        physical_device: vk::PhysicalDevice,
        queue_family: u32,
    ) -> Result<ash::Device> {
        let names: Vec<*const std::ffi::c_char> =
            self.extensions.iter().map(|e| e.as_ptr()).collect();
        let (mut f12, mut f13) = (self.vulkan12, self.vulkan13);
        let (mut fas, mut frq) = (self.acceleration_structure, self.ray_query);
        let prio = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&prio)];
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .features(self.features)
            .push_next(&mut f12);
        // The 1.3 struct is chained only when it asks for something: it is invalid under an
        // instance of API version 1.2.
        if self.vulkan13_needed() {
            f2 = f2.push_next(&mut f13);
        }
        if self.has_ray_query() {
            f2 = f2.push_next(&mut fas).push_next(&mut frq);
        }
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&names)
            .push_next(&mut f2);
        // SAFETY: valid create info whose chain lives until the call returns.
        unsafe { instance.create_device(physical_device, &info, None) }.vk("vkCreateDevice")
    }
}

/// What illum needs of `physical_device`, with and without ray queries, and what it lacks.
///
/// # Safety
/// `instance` and `physical_device` must be valid handles.
pub unsafe fn requirements(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
) -> Result<Requirements> {
    // SAFETY: plain queries of valid handles.
    unsafe {
        let props = instance.get_physical_device_properties(physical_device);
        let exts = instance
            .enumerate_device_extension_properties(physical_device)
            .vk("vkEnumerateDeviceExtensionProperties")?;
        let supported: Vec<CString> = exts
            .iter()
            .filter_map(|e| e.extension_name_as_c_str().ok().map(CStr::to_owned))
            .collect();
        let has = |n: &CStr| supported.iter().any(|s| s.as_c_str() == n);
        let rq_exts = RQ_EXTENSIONS.iter().all(|e| has(e));
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
        let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
        if rq_exts {
            f2 = f2.push_next(&mut fas).push_next(&mut frq);
        }
        instance.get_physical_device_features2(physical_device, &mut f2);
        let offered = FeatureSet {
            api_version: props.api_version,
            extensions: Vec::new(),
            features: f2.features,
            vulkan12: strip(f12),
            vulkan13: Default::default(),
            acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
                .acceleration_structure(fas.acceleration_structure == vk::TRUE),
            ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR::default()
                .ray_query(frq.ray_query == vk::TRUE),
        };
        let base = FeatureSet::base();
        let missing = base.missing_from(&offered);
        let rq = FeatureSet::with_ray_query();
        let rq_ok = rq_exts
            && missing.is_empty()
            && rq
                .missing_from(&FeatureSet {
                    extensions: owned(RQ_EXTENSIONS),
                    ..offered.clone()
                })
                .is_empty();
        let queue_flags = vk::QueueFlags::COMPUTE;
        let queue_family = instance
            .get_physical_device_queue_family_properties(physical_device)
            .iter()
            .position(|q| q.queue_flags.contains(queue_flags))
            .map(|i| i as u32);
        let mut missing = missing;
        if queue_family.is_none() {
            missing.push("a queue family with compute".into());
        }
        Ok(Requirements {
            base,
            ray_query: rq_ok.then_some(rq),
            queue_flags,
            queue_family,
            missing,
        })
    }
}

/// The queried 1.2 features without the driver's p_next pointer (it dangles after the query).
fn strip(f: vk::PhysicalDeviceVulkan12Features<'_>) -> vk::PhysicalDeviceVulkan12Features<'static> {
    vk::PhysicalDeviceVulkan12Features {
        p_next: std::ptr::null_mut(),
        _marker: std::marker::PhantomData,
        ..f
    }
}

/// Checks an external device against the requirements: `enabled` is what the host enabled at
/// creation, `queue_family` the family of the queue it hands over.
pub(crate) fn check_external(
    req: &Requirements,
    enabled: &FeatureSet,
    queue_family: u32,
    family_flags: Option<vk::QueueFlags>,
    device: &str,
) -> Result<()> {
    let unsupported = |what: String| Error::Unsupported {
        device: device.to_string(),
        what,
    };
    if !req.missing.is_empty() {
        return Err(unsupported(format!("it lacks {}", req.missing.join(", "))));
    }
    let want = if enabled.has_ray_query() {
        req.ray_query.as_ref().ok_or_else(|| {
            unsupported("ray queries were enabled, but the device does not offer them".into())
        })?
    } else {
        &req.base
    };
    let missing = want.missing_from(enabled);
    if !missing.is_empty() {
        return Err(unsupported(format!(
            "the application's device was created without {} (see illum::vk::requirements)",
            missing.join(", ")
        )));
    }
    match family_flags {
        None => Err(unsupported(format!(
            "queue_family_index {queue_family} does not exist on the device"
        ))),
        Some(f) if !f.contains(req.queue_flags) => Err(unsupported(format!(
            "queue family {queue_family} has {f:?}, illum needs {:?}",
            req.queue_flags
        ))),
        Some(_) => Ok(()),
    }
}
