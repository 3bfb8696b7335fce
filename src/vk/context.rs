//! Instance, device and queue: created by illum, or borrowed from an application that embeds it.

use super::devices::{DeviceInfo, describe, pick};
use super::error::{Error, Result, VkResultExt};
use super::memory::Allocator;
use ash::vk;
use std::ffi::{CStr, CString, c_void};
use std::sync::{Arc, Mutex};

#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Device index or a substring of its name; None picks the best (discrete, integrated, virtual, CPU).
    pub device: Option<String>,
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages (also on when ILLUM_VALIDATION=1).
    pub validation: bool,
    /// Instance extensions to enable besides illum's own (a window's surface extensions).
    pub instance_extensions: Vec<CString>,
    /// Device extensions to enable besides illum's own (VK_KHR_swapchain for a window).
    pub device_extensions: Vec<CString>,
}

/// Handles of an application's own Vulkan objects, for embedding illum on its device.
pub struct ExternalDevice {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    /// A compute-capable queue. illum submits to it and waits on its own fences; the application
    /// must not submit to the same queue from another thread while illum is recording work.
    pub queue: vk::Queue,
    pub queue_family_index: u32,
    /// What the application enabled when it created the device: at least one of the sets of
    /// [`super::requirements`] (with ray queries enabled, illum uses them).
    pub enabled: super::FeatureSet,
}

/// The handles behind a [`Context`], reachable through `Deref` (e.g. `ctx.device`) so that an
/// embedding application can record its own work against the same objects.
pub struct Inner {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub info: DeviceInfo,
    pub accel: Option<ash::khr::acceleration_structure::Device>,
    pub(crate) allocator: Allocator,
    pub(crate) command_pool: Mutex<vk::CommandPool>,
    pub limits: vk::PhysicalDeviceLimits,
    pub scratch_alignment: u64,
    /// Valid bits of timestamps on the queue (0: no timestamps) and nanoseconds per tick.
    pub timestamp_bits: u32,
    pub timestamp_period: f64,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: Arc<Mutex<Vec<String>>>,
    kernel_listener: Mutex<Option<KernelListener>>,
    /// Buffers uploaded through [`Context::upload`] and their bytes, for callers that check what
    /// a render re-uploads (a prepared scene's second render uploads only its frame constants).
    pub(crate) uploads: std::sync::atomic::AtomicU64,
    pub(crate) uploaded_bytes: std::sync::atomic::AtomicU64,
    /// Trace-structure levels built: bottom (per mesh or shape run) and top.
    pub(crate) builds: [std::sync::atomic::AtomicU64; 2],
    /// Pipelines are created through it; with a file, it persists across runs (illum's own
    /// devices only: an embedding application keeps its own caches).
    pub(crate) pipeline_cache: vk::PipelineCache,
    pub(crate) pipeline_cache_file: Option<std::path::PathBuf>,
    /// With ILLUM_KERNEL_STATS=1 on a device that has VK_KHR_pipeline_executable_properties:
    /// each kernel's compiled statistics (registers, spills, ...) are printed at creation.
    pub(crate) executable_stats: Option<ash::khr::pipeline_executable_properties::Device>,
    owned: bool,
}

/// What a kernel listener hears (see [`Context::set_kernel_listener`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelEvent<'a> {
    /// A compute kernel of this name is about to be created (and compiled then or at its first
    /// dispatch).
    Creating(&'a str),
    /// A render's kernels (this integrator's) have run their warm-up dispatch: compiled.
    Compiled(&'a str),
}

/// Hears every [`KernelEvent`] of a context.
pub type KernelListener = Arc<dyn Fn(KernelEvent<'_>) + Send + Sync>;

/// The Vulkan context every GPU object of illum lives on. Cheap to clone.
#[derive(Clone)]
pub struct Context(pub(crate) Arc<Inner>);

impl std::ops::Deref for Context {
    type Target = Inner;
    fn deref(&self) -> &Inner {
        &self.0
    }
}

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data; `user` is the Arc'd message list that outlives
    // the messenger (it is destroyed before the list in Inner::drop).
    unsafe {
        let msg = if data.is_null() || (*data).p_message.is_null() {
            "<no message>".to_string()
        } else {
            CStr::from_ptr((*data).p_message)
                .to_string_lossy()
                .into_owned()
        };
        crate::note!("[vulkan validation {severity:?}] {msg}");
        let list = &*(user as *const Mutex<Vec<String>>);
        if let Ok(mut l) = list.lock() {
            l.push(msg);
        }
    }
    vk::FALSE
}

pub(crate) fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading the system Vulkan loader library.
    unsafe { ash::Entry::load() }.map_err(|e| Error::Loader(e.to_string()))
}

pub(crate) fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    extra: &[CString],
) -> Result<ash::Instance> {
    // SAFETY: plain Vulkan calls with valid create infos.
    unsafe {
        let version = entry
            .try_enumerate_instance_version()
            .vk("vkEnumerateInstanceVersion")?
            .unwrap_or(vk::API_VERSION_1_0);
        if version < vk::API_VERSION_1_2 {
            return Err(Error::NoDevice(
                "the Vulkan loader is older than 1.2".into(),
            ));
        }
        let app = CString::new("illum").unwrap();
        let app_info = vk::ApplicationInfo::default()
            .application_name(&app)
            .engine_name(&app)
            .api_version(version.min(vk::API_VERSION_1_3));
        let mut layers = Vec::new();
        let mut exts: Vec<_> = extra.iter().map(|e| e.as_ptr()).collect();
        if validation {
            let available = entry
                .enumerate_instance_layer_properties()
                .vk("vkEnumerateInstanceLayerProperties")?;
            if !available
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
            {
                return Err(Error::MissingLayer(
                    VALIDATION_LAYER.to_string_lossy().into_owned(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            exts.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&exts);
        match entry.create_instance(&info, None) {
            // The loader found no driver manifest (ICD) it could load.
            Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => Err(Error::NoDevice(format!(
                "the Vulkan loader found no driver (vkCreateInstance: ERROR_INCOMPATIBLE_DRIVER); \
                 install one (mesa-vulkan-drivers for lavapipe, or the GPU vendor's) or point \
                 VK_DRIVER_FILES at its manifest (VK_DRIVER_FILES={})",
                std::env::var("VK_DRIVER_FILES").unwrap_or_else(|_| "unset".into())
            ))),
            r => r.vk("vkCreateInstance"),
        }
    }
}

impl Context {
    /// Creates an instance and a device of its own.
    pub fn new(opts: &ContextOptions) -> Result<Context> {
        let validation = opts.validation
            || std::env::var("ILLUM_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty());
        let entry = load_entry()?;
        let instance = create_instance(&entry, validation, &opts.instance_extensions)?;
        let messages = Arc::new(Mutex::new(Vec::new()));
        // SAFETY: valid instance; every object created here is owned by the returned Context or
        // destroyed on the error paths.
        unsafe {
            let debug = if validation {
                let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
                let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                    .message_severity(
                        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                            | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                    )
                    .message_type(
                        vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                            | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                            | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                    )
                    .pfn_user_callback(Some(debug_callback))
                    .user_data(Arc::as_ptr(&messages) as *mut c_void);
                let m = du
                    .create_debug_utils_messenger(&info, None)
                    .vk("vkCreateDebugUtilsMessengerEXT")?;
                Some((du, m))
            } else {
                None
            };
            let result = Self::create_device(&instance, opts);
            let (pd, device, qf, rq, info, stats) = match result {
                Ok(v) => v,
                Err(e) => {
                    if let Some((du, m)) = &debug {
                        du.destroy_debug_utils_messenger(*m, None);
                    }
                    instance.destroy_instance(None);
                    return Err(e);
                }
            };
            let queue = device.get_device_queue(qf, 0);
            let stats = stats
                .then(|| ash::khr::pipeline_executable_properties::Device::new(&instance, &device));
            Self::finish(
                entry, instance, pd, device, queue, qf, rq, info, debug, messages, true, stats,
            )
        }
    }

    /// Wraps an application's own device, after checking it against [`super::requirements`]:
    /// an error names what the device or `ext.enabled` lacks. illum destroys nothing it did not
    /// create.
    ///
    /// # Safety
    /// The handles must be valid, the device created with `ext.enabled`, and they must outlive
    /// the Context and every object made from it.
    pub unsafe fn from_external(ext: ExternalDevice) -> Result<Context> {
        unsafe {
            let pds = ext
                .instance
                .enumerate_physical_devices()
                .vk("vkEnumeratePhysicalDevices")?;
            let index = pds
                .iter()
                .position(|&p| p == ext.physical_device)
                .unwrap_or(0);
            let mut info = describe(&ext.instance, ext.physical_device, index);
            let req = super::requirements(&ext.instance, ext.physical_device)?;
            let family = ext
                .instance
                .get_physical_device_queue_family_properties(ext.physical_device)
                .get(ext.queue_family_index as usize)
                .map(|q| q.queue_flags);
            super::requirements::check_external(
                &req,
                &ext.enabled,
                ext.queue_family_index,
                family,
                &info.name,
            )?;
            info.ray_query &= ext.enabled.has_ray_query();
            let rq = info.ray_query;
            Self::finish(
                ext.entry,
                ext.instance,
                ext.physical_device,
                ext.device,
                ext.queue,
                ext.queue_family_index,
                rq,
                info,
                None,
                Arc::new(Mutex::new(Vec::new())),
                false,
                None,
            )
        }
    }

    unsafe fn create_device(
        instance: &ash::Instance,
        opts: &ContextOptions,
    ) -> Result<(vk::PhysicalDevice, ash::Device, u32, bool, DeviceInfo, bool)> {
        unsafe {
            let pds = instance
                .enumerate_physical_devices()
                .vk("vkEnumeratePhysicalDevices")?;
            let infos: Vec<DeviceInfo> = pds
                .iter()
                .enumerate()
                .map(|(i, &pd)| describe(instance, pd, i))
                .collect();
            let index = pick(&infos, opts.device.as_deref())?;
            let pd = pds[index];
            let info = infos[index].clone();
            let qf = instance
                .get_physical_device_queue_family_properties(pd)
                .iter()
                .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .ok_or_else(|| Error::Unsupported {
                    device: info.name.clone(),
                    what: "it has no compute queue".into(),
                })? as u32;
            let rq = info.ray_query;
            let prio = [1.0f32];
            let qinfo = [vk::DeviceQueueCreateInfo::default()
                .queue_family_index(qf)
                .queue_priorities(&prio)];
            let mut exts: Vec<_> = opts.device_extensions.iter().map(|e| e.as_ptr()).collect();
            if rq {
                exts.push(ash::khr::acceleration_structure::NAME.as_ptr());
                exts.push(ash::khr::ray_query::NAME.as_ptr());
                exts.push(ash::khr::deferred_host_operations::NAME.as_ptr());
            }
            let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
                .buffer_device_address(true)
                .scalar_block_layout(true);
            let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
                .acceleration_structure(true);
            let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
            // Kernel statistics only when asked for: capturing them may slow compilation.
            let stats = super::pipeline::kernel_stats()
                && instance
                    .enumerate_device_extension_properties(pd)
                    .unwrap_or_default()
                    .iter()
                    .any(|e| {
                        e.extension_name_as_c_str()
                            == Ok(ash::khr::pipeline_executable_properties::NAME)
                    });
            if super::pipeline::kernel_stats() && !stats {
                crate::note!(
                    "illum: ILLUM_KERNEL_STATS: {} has no VK_KHR_pipeline_executable_properties; \
                     no kernel statistics",
                    info.name
                );
            }
            let mut fstats = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
                .pipeline_executable_info(true);
            if stats {
                exts.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
            }
            // Kernels built to time their regions read the device clock (glsl/shared/profile.glsl).
            let mut fclock =
                vk::PhysicalDeviceShaderClockFeaturesKHR::default().shader_device_clock(true);
            if crate::shaders::PROFILED {
                exts.push(ash::khr::shader_clock::NAME.as_ptr());
            }
            let base = vk::PhysicalDeviceFeatures::default().shader_int64(true);
            let mut f2 = vk::PhysicalDeviceFeatures2::default()
                .features(base)
                .push_next(&mut f12);
            if crate::shaders::PROFILED {
                f2 = f2.push_next(&mut fclock);
            }
            if rq {
                f2 = f2.push_next(&mut fas).push_next(&mut frq);
            }
            if stats {
                f2 = f2.push_next(&mut fstats);
            }
            let dinfo = vk::DeviceCreateInfo::default()
                .queue_create_infos(&qinfo)
                .enabled_extension_names(&exts)
                .push_next(&mut f2);
            let device = instance
                .create_device(pd, &dinfo, None)
                .vk("vkCreateDevice")?;
            Ok((pd, device, qf, rq, info, stats))
        }
    }

    #[allow(clippy::too_many_arguments)]
    unsafe fn finish(
        entry: ash::Entry,
        instance: ash::Instance,
        pd: vk::PhysicalDevice,
        device: ash::Device,
        queue: vk::Queue,
        qf: u32,
        rq: bool,
        info: DeviceInfo,
        debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
        messages: Arc<Mutex<Vec<String>>>,
        owned: bool,
        executable_stats: Option<ash::khr::pipeline_executable_properties::Device>,
    ) -> Result<Context> {
        unsafe {
            let accel =
                rq.then(|| ash::khr::acceleration_structure::Device::new(&instance, &device));
            let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
            let mut props2 = vk::PhysicalDeviceProperties2::default();
            if rq {
                props2 = props2.push_next(&mut as_props);
            }
            instance.get_physical_device_properties2(pd, &mut props2);
            let limits = props2.properties.limits;
            let scratch_alignment =
                u64::from(as_props.min_acceleration_structure_scratch_offset_alignment).max(1);
            let timestamp_bits = instance
                .get_physical_device_queue_family_properties(pd)
                .get(qf as usize)
                .map_or(0, |q| q.timestamp_valid_bits);
            let allocator = Allocator::new(&instance, &device, pd)?;
            let pool = device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(qf)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .vk("vkCreateCommandPool")?;
            let props = instance.get_physical_device_properties(pd);
            let file = if owned {
                super::pipeline_cache::path(&props)
            } else {
                None
            };
            let data = file
                .as_ref()
                .map_or_else(Vec::new, |f| super::pipeline_cache::initial_data(f, &props));
            let pipeline_cache = device
                .create_pipeline_cache(
                    &vk::PipelineCacheCreateInfo::default().initial_data(&data),
                    None,
                )
                .vk("vkCreatePipelineCache")?;
            Ok(Context(Arc::new(Inner {
                entry,
                instance,
                physical_device: pd,
                device,
                queue,
                queue_family: qf,
                info,
                accel,
                allocator,
                command_pool: Mutex::new(pool),
                limits,
                scratch_alignment,
                timestamp_bits,
                timestamp_period: f64::from(limits.timestamp_period),
                debug,
                messages,
                kernel_listener: Mutex::new(None),
                uploads: Default::default(),
                uploaded_bytes: Default::default(),
                builds: Default::default(),
                pipeline_cache,
                pipeline_cache_file: file,
                executable_stats,
                owned,
            })))
        }
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.0.info
    }

    /// True when this context traces with hardware ray queries.
    pub fn ray_query(&self) -> bool {
        self.0.accel.is_some()
    }

    /// Validation messages received so far (warnings and errors), when validation is on.
    pub fn validation_messages(&self) -> Vec<String> {
        self.0
            .messages
            .lock()
            .map(|m| m.clone())
            .unwrap_or_default()
    }

    pub fn validation_enabled(&self) -> bool {
        self.0.debug.is_some()
    }

    /// Calls `listener` whenever a compute pipeline is created on this context (the driver
    /// compiles it then or at its first dispatch; lavapipe: up to half a minute the first time a
    /// feature combination is seen, fast afterwards from Mesa's shader cache) and when a render's
    /// warm-up dispatch has compiled its kernels. None removes the listener.
    pub fn set_kernel_listener(&self, listener: Option<KernelListener>) {
        if let Ok(mut l) = self.0.kernel_listener.lock() {
            *l = listener;
        }
    }

    /// Trace-structure levels built so far on this context: (bottom levels, top levels).
    pub fn build_counts(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (self.builds[0].load(Relaxed), self.builds[1].load(Relaxed))
    }

    pub(crate) fn count_builds(&self, bottom: usize, top: usize) {
        use std::sync::atomic::Ordering::Relaxed;
        self.builds[0].fetch_add(bottom as u64, Relaxed);
        self.builds[1].fetch_add(top as u64, Relaxed);
    }

    pub(crate) fn notify_kernel(&self, event: KernelEvent<'_>) {
        let listener = self.0.kernel_listener.lock().ok().and_then(|l| l.clone());
        if let Some(l) = listener {
            l(event);
        }
    }
}

impl Drop for Inner {
    fn drop(&mut self) {
        // SAFETY: every object made from this context holds an Arc to it, so none is alive here.
        unsafe {
            let _ = self.device.device_wait_idle();
            if let Ok(pool) = self.command_pool.lock() {
                self.device.destroy_command_pool(*pool, None);
            }
            self.allocator.shutdown();
            self.device
                .destroy_pipeline_cache(self.pipeline_cache, None);
            if self.owned {
                self.device.destroy_device(None);
                if let Some((du, m)) = &self.debug {
                    du.destroy_debug_utils_messenger(*m, None);
                }
                self.instance.destroy_instance(None);
            }
        }
    }
}
