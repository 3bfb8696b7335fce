//! The C API (include/illum.h, generated from this file by scripts/gen-header.sh): opaque
//! handles, a status code per call and the message of the calling thread's last error. No Rust
//! panic crosses the boundary: each call runs under `catch_unwind`, and a panic becomes
//! `ILLUM_ERROR_PANIC` with its message.
//!
//! Vulkan handles are the host's own (`VkInstance`, `VkDevice`, …, with Vulkan's C types);
//! illum loads the functions it needs through the host's `vkGetInstanceProcAddr` (or the system
//! loader when that is NULL), and destroys nothing it did not create.

#![allow(clippy::missing_safety_doc)] // the safety rules are in include/illum.h, for C readers

use crate::error::{Error, GpuError};
use crate::render::{PreparedScene, RenderSession, Renderer};
use crate::scene::Scene;
use crate::vk::{Context, ExternalDevice};
use ash::vk::{self, Handle};

/// The host's `vkGetInstanceProcAddr`, or NULL for the system loader's.
pub type IllumGetInstanceProcAddr =
    Option<unsafe extern "system" fn(vk::Instance, *const c_char) -> vk::PFN_vkVoidFunction>;
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

mod builder;
mod scene;
pub use builder::*;
pub use scene::*;

/// What a call returned.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IllumStatus {
    Ok = 0,
    /// A NULL handle or pointer where one was required.
    ErrorNull = 1,
    /// Bad input: a value out of range, a malformed scene, an update that changes geometry.
    ErrorInvalid = 2,
    /// The device lacks something illum needs (the message names it).
    ErrorUnsupported = 3,
    /// A Vulkan call failed (device lost, out of memory, …).
    ErrorVulkan = 4,
    /// An internal error (a bug): illum caught a panic.
    ErrorPanic = 5,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_error(msg: String) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

fn status_of(e: &Error) -> IllumStatus {
    match e {
        Error::Invalid(m) if m.ends_with(NULL_SUFFIX) => IllumStatus::ErrorNull,
        Error::Gpu(
            GpuError::Unsupported { .. } | GpuError::NoDevice(_) | GpuError::MissingLayer(_),
        ) => IllumStatus::ErrorUnsupported,
        Error::Gpu(_) => IllumStatus::ErrorVulkan,
        _ => IllumStatus::ErrorInvalid,
    }
}

/// Runs `f`, turning its error or panic into a status and the thread's last error message.
fn guard(f: impl FnOnce() -> Result<(), Error>) -> IllumStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            set_error(String::new());
            IllumStatus::Ok
        }
        Ok(Err(e)) => {
            set_error(e.to_string());
            status_of(&e)
        }
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            set_error(format!("internal error (panic): {msg}"));
            IllumStatus::ErrorPanic
        }
    }
}

const NULL_SUFFIX: &str = " is NULL";

fn null(what: &str) -> Error {
    Error::Invalid(format!("{what}{NULL_SUFFIX}"))
}

unsafe fn str_arg<'a>(p: *const c_char, what: &str) -> Result<&'a str, Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: the caller passes a NUL-terminated string.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Error::Invalid(format!("{what} is not UTF-8")))
}

unsafe fn handle<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Error> {
    // SAFETY: the caller passes a live handle from this API, or NULL.
    unsafe { p.as_mut() }.ok_or_else(|| null(what))
}

fn out<T>(dst: *mut *mut T, v: T) -> Result<(), Error> {
    if dst.is_null() {
        return Err(null("the output pointer"));
    }
    // SAFETY: checked non-NULL; the caller passes a writable pointer.
    unsafe { *dst = Box::into_raw(Box::new(v)) };
    Ok(())
}

/// The message of the calling thread's last failed call ("" after a successful one). Valid until
/// the thread's next call into illum.
#[unsafe(no_mangle)]
pub extern "C" fn illum_last_error() -> *const c_char {
    // The thread-local is gone only while the thread exits: then "".
    catch_unwind(|| LAST_ERROR.try_with(|e| e.borrow().as_ptr()).ok())
        .ok()
        .flatten()
        .unwrap_or(c"".as_ptr())
}

/// What illum needs of a device (see illum::vk::requirements): the host enables these when it
/// creates its device.
#[repr(C)]
pub struct IllumRequirements {
    /// Lowest Vulkan API version (VK_MAKE_API_VERSION).
    pub api_version: u32,
    /// Device extensions to enable: `extension_count` static NUL-terminated names.
    pub extension_count: u32,
    pub extensions: [*const c_char; 4],
    /// Features to enable (VkBool32): VkPhysicalDeviceFeatures::shaderInt64,
    /// VkPhysicalDeviceVulkan12Features::bufferDeviceAddress and ::scalarBlockLayout, and with ray
    /// queries VkPhysicalDeviceAccelerationStructureFeaturesKHR::accelerationStructure and
    /// VkPhysicalDeviceRayQueryFeaturesKHR::rayQuery.
    pub shader_int64: u32,
    pub buffer_device_address: u32,
    pub scalar_block_layout: u32,
    pub acceleration_structure: u32,
    pub ray_query: u32,
    /// VkQueueFlags the queue needs, and the first family that has them.
    pub queue_flags: u32,
    pub queue_family: u32,
    /// Whether the device offers ray queries (1) or not (0).
    pub ray_query_available: u32,
}

struct Loaded {
    entry: ash::Entry,
    instance: ash::Instance,
}

unsafe fn load_instance(
    get_instance_proc_addr: IllumGetInstanceProcAddr,
    instance: vk::Instance,
) -> Result<Loaded, Error> {
    if instance == vk::Instance::null() {
        return Err(null("the VkInstance"));
    }
    // SAFETY: the host's loader entry point (or the system loader), with its own instance.
    unsafe {
        let entry = match get_instance_proc_addr {
            None => ash::Entry::load().map_err(|e| GpuError::Loader(e.to_string()))?,
            Some(get_instance_proc_addr) => ash::Entry::from_static_fn(ash::StaticFn {
                get_instance_proc_addr,
            }),
        };
        let instance = ash::Instance::load(entry.static_fn(), instance);
        Ok(Loaded { entry, instance })
    }
}

/// Fills `out` with what illum needs of `physical_device`; with `ray_query` non-zero, the set
/// with ray queries (an error if the device lacks them). `get_instance_proc_addr` may be NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_requirements(
    get_instance_proc_addr: IllumGetInstanceProcAddr,
    instance: vk::Instance,
    physical_device: vk::PhysicalDevice,
    ray_query: u32,
    out: *mut IllumRequirements,
) -> IllumStatus {
    guard(|| unsafe {
        let l = load_instance(get_instance_proc_addr, instance)?;
        let out = out.as_mut().ok_or_else(|| null("out"))?;
        let req = crate::vk::requirements(&l.instance, physical_device)?;
        let set = if ray_query != 0 {
            req.ray_query.as_ref().ok_or_else(|| {
                Error::Gpu(GpuError::Unsupported {
                    device: "the physical device".into(),
                    what: "it has no ray queries".into(),
                })
            })?
        } else {
            &req.base
        };
        let mut extensions = [std::ptr::null(); 4];
        for (slot, e) in extensions.iter_mut().zip(&set.extensions) {
            *slot = static_name(e);
        }
        *out = IllumRequirements {
            api_version: set.api_version,
            extension_count: set.extensions.len() as u32,
            extensions,
            shader_int64: set.features.shader_int64,
            buffer_device_address: set.vulkan12.buffer_device_address,
            scalar_block_layout: set.vulkan12.scalar_block_layout,
            acceleration_structure: set.acceleration_structure.acceleration_structure,
            ray_query: set.ray_query.ray_query,
            queue_flags: req.queue_flags.as_raw(),
            queue_family: req.queue_family.unwrap_or(u32::MAX),
            ray_query_available: u32::from(req.ray_query.is_some()),
        };
        if !req.missing.is_empty() {
            return Err(Error::Gpu(GpuError::Unsupported {
                device: "the physical device".into(),
                what: format!("it lacks {}", req.missing.join(", ")),
            }));
        }
        Ok(())
    })
}

/// The static name of an extension illum asks for (the C caller keeps the pointer).
fn static_name(e: &CStr) -> *const c_char {
    const NAMES: [&CStr; 3] = [
        ash::khr::acceleration_structure::NAME,
        ash::khr::ray_query::NAME,
        ash::khr::deferred_host_operations::NAME,
    ];
    NAMES
        .iter()
        .find(|n| **n == e)
        .map_or(std::ptr::null(), |n| n.as_ptr())
}

/// The host's device, as `illum_context_from_external` takes it.
#[repr(C)]
pub struct IllumExternalDevice {
    /// The host's vkGetInstanceProcAddr, or NULL for the system loader's.
    pub get_instance_proc_addr: IllumGetInstanceProcAddr,
    pub instance: vk::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: vk::Device,
    pub queue: vk::Queue,
    pub queue_family_index: u32,
    /// Non-zero when the device was created with the ray-query set of `illum_requirements`
    /// (else with the base set).
    pub ray_query_enabled: u32,
}

/// illum on the host's device.
pub struct IllumContext {
    ctx: Context,
    renderer: Renderer,
}

/// A validated scene (host memory).
pub struct IllumScene(Scene);

/// A scene prepared on a context: uploaded, its trace structure built.
pub struct IllumPrepared {
    prepared: PreparedScene,
    ctx: Context,
}

/// A progressive render recorded into the host's command buffers.
pub struct IllumSession {
    session: RenderSession<'static>,
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_context_from_external(
    ext: *const IllumExternalDevice,
    out_context: *mut *mut IllumContext,
) -> IllumStatus {
    guard(|| unsafe {
        let ext = ext.as_ref().ok_or_else(|| null("ext"))?;
        let l = load_instance(ext.get_instance_proc_addr, ext.instance)?;
        if ext.device.is_null() || ext.queue.is_null() || ext.physical_device.is_null() {
            return Err(null("the VkPhysicalDevice, VkDevice or VkQueue"));
        }
        let pd = ext.physical_device;
        let device = ash::Device::load(l.instance.fp_v1_0(), ext.device);
        let req = crate::vk::requirements(&l.instance, pd)?;
        let enabled = if ext.ray_query_enabled != 0 {
            req.ray_query.clone().ok_or_else(|| {
                Error::Gpu(GpuError::Unsupported {
                    device: "the physical device".into(),
                    what: "ray queries were enabled, but the device does not offer them".into(),
                })
            })?
        } else {
            req.base.clone()
        };
        let ctx = Context::from_external(ExternalDevice {
            entry: l.entry,
            instance: l.instance,
            physical_device: pd,
            device,
            queue: ext.queue,
            queue_family_index: ext.queue_family_index,
            enabled,
        })?;
        let renderer = Renderer::new(ctx.clone());
        out(out_context, IllumContext { ctx, renderer })
    })
}

/// Waits for illum's work and frees the context (the host's device stays).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_context_destroy(context: *mut IllumContext) {
    if !context.is_null() {
        // SAFETY: a handle from illum_context_from_external, destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(context) })));
    }
}

/// Panics inside illum with `message` (NULL: a fixed one) under the same guard as every other
/// call: for hosts' and illum's tests that a panic comes back as ILLUM_STATUS_ERROR_PANIC with
/// its message and the process goes on. Nothing else happens.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_debug_panic(message: *const c_char) -> IllumStatus {
    guard(|| unsafe {
        let m = if message.is_null() {
            "illum_debug_panic"
        } else {
            str_arg(message, "message")?
        };
        panic!("{m}")
    })
}
