//! The "application" of the embedding tests: its own instance (validation with synchronization
//! validation on, its own messenger), and devices created from what illum asks for.

use ash::vk;
use illum::vk::{Context, ExternalDevice, FeatureSet};
use std::ffi::c_void;
use std::sync::{Arc, Mutex};

pub struct App {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub pd: vk::PhysicalDevice,
    pub queue_family: u32,
    debug: (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT),
    messages: Arc<Mutex<Vec<String>>>,
}

unsafe extern "system" fn collect(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid data; `user` is the App's message list, alive while the
    // messenger is.
    unsafe {
        let msg = (*data)
            .message_as_c_str()
            .map_or("<none>".into(), |m| m.to_string_lossy().into_owned());
        eprintln!("[application's validation] {msg}");
        (*(user as *const Mutex<Vec<String>>))
            .lock()
            .unwrap()
            .push(msg);
    }
    vk::FALSE
}

impl App {
    pub fn new() -> App {
        // SAFETY: plain Vulkan set-up; everything is destroyed in Drop.
        unsafe {
            let entry = ash::Entry::load().expect("Vulkan loader");
            let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
            let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
            let exts = [ash::ext::debug_utils::NAME.as_ptr()];
            let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
            let mut features =
                vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
            let instance = entry
                .create_instance(
                    &vk::InstanceCreateInfo::default()
                        .application_info(&app)
                        .enabled_layer_names(&layers)
                        .enabled_extension_names(&exts)
                        .push_next(&mut features),
                    None,
                )
                .expect("instance");
            let messages = Arc::new(Mutex::new(Vec::new()));
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
                .pfn_user_callback(Some(collect))
                .user_data(Arc::as_ptr(&messages) as *mut c_void);
            let m = du.create_debug_utils_messenger(&info, None).unwrap();
            let pds = instance.enumerate_physical_devices().unwrap();
            let want = std::env::var("ILLUM_TEST_DEVICE").ok();
            let pd = pds
                .iter()
                .copied()
                .find(|&pd| {
                    let name = instance
                        .get_physical_device_properties(pd)
                        .device_name_as_c_str()
                        .unwrap()
                        .to_string_lossy()
                        .to_lowercase();
                    want.as_ref()
                        .is_none_or(|w| name.contains(&w.to_lowercase()))
                })
                .expect("a device");
            let req = illum::vk::requirements(&instance, pd).expect("requirements");
            App {
                queue_family: req.queue_family.expect("a compute queue"),
                entry,
                instance,
                pd,
                debug: (du, m),
                messages,
            }
        }
    }

    pub fn requirements(&self) -> illum::vk::Requirements {
        // SAFETY: valid handles.
        unsafe { illum::vk::requirements(&self.instance, self.pd) }.unwrap()
    }

    /// A device with `set` enabled, and illum's context on it.
    pub fn device(&self, set: &FeatureSet) -> (ash::Device, illum::Result<Context>) {
        // SAFETY: the device is destroyed by the caller (see `destroy`), after the context.
        unsafe {
            let device = set
                .create_device(&self.instance, self.pd, self.queue_family)
                .expect("device");
            let ctx = self.wrap(&device, set.clone(), self.queue_family);
            (device, ctx)
        }
    }

    /// illum's context on `device`, told that `enabled` was enabled on it.
    ///
    /// # Safety
    /// `device` must be valid and outlive the context.
    pub unsafe fn wrap(
        &self,
        device: &ash::Device,
        enabled: FeatureSet,
        queue_family: u32,
    ) -> illum::Result<Context> {
        let ctx = unsafe {
            Context::from_external(ExternalDevice {
                entry: self.entry.clone(),
                instance: self.instance.clone(),
                physical_device: self.pd,
                device: device.clone(),
                queue: device.get_device_queue(self.queue_family, 0),
                queue_family_index: queue_family,
                enabled,
            })
        };
        Ok(ctx?)
    }

    /// Fails the test if the validation layers said anything on this instance.
    pub fn assert_silent(&self) {
        let m = self.messages.lock().unwrap();
        assert!(
            m.is_empty(),
            "{} validation message(s):\n{}",
            m.len(),
            m.join("\n")
        );
    }
}

impl Drop for App {
    fn drop(&mut self) {
        // SAFETY: every device of the instance was destroyed by its test.
        unsafe {
            self.debug
                .0
                .destroy_debug_utils_messenger(self.debug.1, None);
            self.instance.destroy_instance(None);
        }
    }
}
