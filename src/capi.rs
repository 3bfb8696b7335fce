//! The C API (include/illum.h, generated from this file by scripts/gen-header.sh): opaque
//! handles, a status code per call and the message of the calling thread's last error. No Rust
//! panic crosses the boundary: each call runs under `catch_unwind`, and a panic becomes
//! `ILLUM_ERROR_PANIC` with its message.
//!
//! Vulkan handles are the host's own (`VkInstance`, `VkDevice`, …, with Vulkan's C types);
//! illum loads the functions it needs through the host's `vkGetInstanceProcAddr` (or the system
//! loader when that is NULL), and destroys nothing it did not create.

#![allow(clippy::missing_safety_doc)] // the safety rules are in include/illum.h, for C readers

use crate::error::Error;
use crate::render::{ImageState, Pass, PreparedScene, RenderSession, RenderSettings, Renderer};
use crate::scene::Scene;
use crate::vk::{Context, ExternalDevice};
use ash::vk::{self, Handle};

/// The host's `vkGetInstanceProcAddr`, or NULL for the system loader's.
pub type IllumGetInstanceProcAddr =
    Option<unsafe extern "system" fn(vk::Instance, *const c_char) -> vk::PFN_vkVoidFunction>;
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

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
        Error::Unsupported { .. } | Error::NoDevice(_) | Error::MissingLayer(_) => {
            IllumStatus::ErrorUnsupported
        }
        Error::Vulkan { .. }
        | Error::DeviceLost { .. }
        | Error::OutOfMemory { .. }
        | Error::Allocation { .. }
        | Error::Loader(_) => IllumStatus::ErrorVulkan,
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
    LAST_ERROR.with(|e| e.borrow().as_ptr())
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
            None => ash::Entry::load().map_err(|e| Error::Loader(e.to_string()))?,
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
            req.ray_query.as_ref().ok_or_else(|| Error::Unsupported {
                device: "the physical device".into(),
                what: "it has no ray queries".into(),
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
            return Err(Error::Unsupported {
                device: "the physical device".into(),
                what: format!("it lacks {}", req.missing.join(", ")),
            });
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
            req.ray_query.clone().ok_or_else(|| Error::Unsupported {
                device: "the physical device".into(),
                what: "ray queries were enabled, but the device does not offer them".into(),
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

/// A scene from scene JSON (docs/scene-format.md); relative paths resolve against `base_dir`
/// (NULL: the working directory). Errors name the field and value.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_from_json(
    json: *const c_char,
    base_dir: *const c_char,
    out_scene: *mut *mut IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let text = str_arg(json, "json")?;
        let dir = if base_dir.is_null() {
            "."
        } else {
            str_arg(base_dir, "base_dir")?
        };
        let s = crate::scene::from_json_str(text, "<json>", std::path::Path::new(dir))?;
        out(out_scene, IllumScene(s))
    })
}

/// A scene from a scene file.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_load(
    path: *const c_char,
    out_scene: *mut *mut IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let p = str_arg(path, "path")?;
        let s = crate::scene::load(std::path::Path::new(p))?;
        out(out_scene, IllumScene(s))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_destroy(scene: *mut IllumScene) {
    if !scene.is_null() {
        // SAFETY: a handle from illum_scene_*, destroyed once.
        drop(unsafe { Box::from_raw(scene) });
    }
}

/// Moves the camera (resolution unchanged).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_set_camera(
    scene: *mut IllumScene,
    position: *const f64,
    look_at: *const f64,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(scene, "scene")?;
        if position.is_null() || look_at.is_null() {
            return Err(null("position or look_at"));
        }
        let p = glam::DVec3::from_slice(std::slice::from_raw_parts(position, 3));
        let l = glam::DVec3::from_slice(std::slice::from_raw_parts(look_at, 3));
        if !p.is_finite() || !l.is_finite() || p == l {
            return Err(Error::Invalid(format!(
                "camera position {p} and look_at {l} must be finite and differ"
            )));
        }
        (s.0.camera.position, s.0.camera.look_at) = (p, l);
        Ok(())
    })
}

/// Sets material `name`'s diffuse albedo (each in [0, 1]).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_set_diffuse(
    scene: *mut IllumScene,
    name: *const c_char,
    r: f32,
    g: f32,
    b: f32,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(scene, "scene")?;
        let n = str_arg(name, "name")?;
        let m =
            s.0.materials
                .iter_mut()
                .find(|m| m.name == n)
                .ok_or_else(|| Error::Invalid(format!("materials.{n}: no such material")))?;
        let v = glam::Vec3::new(r, g, b);
        if !(v.cmpge(glam::Vec3::ZERO).all() && v.cmple(glam::Vec3::ONE).all()) {
            return Err(Error::Invalid(format!(
                "materials.{n}.diffuse: each must be in [0, 1], got {v}"
            )));
        }
        m.diffuse = v;
        Ok(())
    })
}

/// Sets the object-to-world transform (16 numbers, row-major) of mesh instance `name`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_set_transform(
    scene: *mut IllumScene,
    name: *const c_char,
    matrix: *const f64,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(scene, "scene")?;
        let n = str_arg(name, "name")?;
        if matrix.is_null() {
            return Err(null("matrix"));
        }
        let m = glam::DMat4::from_cols_slice(std::slice::from_raw_parts(matrix, 16)).transpose();
        if !m.is_finite() {
            return Err(Error::Invalid(format!(
                "shapes.{n}.transform: must be finite"
            )));
        }
        let i =
            s.0.instances
                .iter_mut()
                .find(|i| i.name == n)
                .ok_or_else(|| Error::Invalid(format!("shapes.{n}: no such mesh instance")))?;
        i.transform = m;
        Ok(())
    })
}

/// Uploads `scene` and builds its trace structure on `context`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_prepare(
    context: *mut IllumContext,
    scene: *const IllumScene,
    out_prepared: *mut *mut IllumPrepared,
) -> IllumStatus {
    guard(|| unsafe {
        let c = handle(context, "context")?;
        let s = scene.as_ref().ok_or_else(|| null("scene"))?;
        let prepared = c.renderer.prepare(&s.0, Default::default())?;
        out(
            out_prepared,
            IllumPrepared {
                prepared,
                ctx: c.ctx.clone(),
            },
        )
    })
}

/// Brings `prepared` to the edited `scene` (materials, lights, instance transforms).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_prepared_update(
    prepared: *mut IllumPrepared,
    scene: *const IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let p = handle(prepared, "prepared")?;
        let s = scene.as_ref().ok_or_else(|| null("scene"))?;
        p.prepared.update(&p.ctx, &s.0).map(|_| ())
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_prepared_destroy(prepared: *mut IllumPrepared) {
    if !prepared.is_null() {
        // SAFETY: a handle from illum_prepare, destroyed once, with no session on it.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(prepared) })
        }));
    }
}

/// Renders `prepared` through `scene`'s camera, blocking, and writes the beauty (linear RGB,
/// width × height × 3 floats, row-major) to `rgb`, which holds `capacity` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_render(
    context: *mut IllumContext,
    prepared: *const IllumPrepared,
    scene: *const IllumScene,
    spp: u32,
    seed: u64,
    rgb: *mut f32,
    capacity: usize,
) -> IllumStatus {
    guard(|| unsafe {
        let c = handle(context, "context")?;
        let p = prepared.as_ref().ok_or_else(|| null("prepared"))?;
        let s = scene.as_ref().ok_or_else(|| null("scene"))?;
        let cam = &s.0.camera;
        let n = cam.width as usize * cam.height as usize * 3;
        if rgb.is_null() || capacity < n {
            return Err(Error::Invalid(format!(
                "rgb must hold {n} floats ({}x{} RGB), capacity is {capacity}",
                cam.width, cam.height
            )));
        }
        let settings = RenderSettings {
            spp,
            seed,
            ..Default::default()
        };
        let outputs =
            c.renderer
                .render_prepared(&p.prepared, cam, &settings, &[seed], &mut |_, _| {})?;
        let dst = std::slice::from_raw_parts_mut(rgb, n);
        for (d, p) in dst.chunks_exact_mut(3).zip(&outputs[0].film.beauty) {
            d.copy_from_slice(p);
        }
        Ok(())
    })
}

/// The host's storage image (see RenderSession in the Rust docs for the contract): VkImage and
/// VkImageView of format R32G32B32A32_SFLOAT, the layout/stage/access it is in before each pass
/// and the one it must be in after.
#[repr(C)]
pub struct IllumTarget {
    pub image: vk::Image,
    pub view: vk::ImageView,
    pub width: u32,
    pub height: u32,
    pub before_layout: vk::ImageLayout,
    pub before_stage: vk::PipelineStageFlags,
    pub before_access: vk::AccessFlags,
    pub after_layout: vk::ImageLayout,
    pub after_stage: vk::PipelineStageFlags,
    pub after_access: vk::AccessFlags,
}

/// A progressive render of `prepared` through `scene`'s camera into `target`. `prepared` must not
/// be used or destroyed until the session is.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_create(
    context: *mut IllumContext,
    prepared: *mut IllumPrepared,
    scene: *const IllumScene,
    seed: u64,
    target: *const IllumTarget,
    out_session: *mut *mut IllumSession,
) -> IllumStatus {
    guard(|| unsafe {
        let c = handle(context, "context")?;
        let p: &'static mut IllumPrepared = handle(prepared, "prepared")?;
        let s = scene.as_ref().ok_or_else(|| null("scene"))?;
        let t = target.as_ref().ok_or_else(|| null("target"))?;
        let target = crate::render::TargetImage {
            image: t.image,
            view: t.view,
            extent: [t.width, t.height],
            before: ImageState {
                layout: t.before_layout,
                stage: t.before_stage,
                access: t.before_access,
            },
            after: ImageState {
                layout: t.after_layout,
                stage: t.after_stage,
                access: t.after_access,
            },
        };
        let settings = RenderSettings {
            seed,
            ..Default::default()
        };
        let session = c
            .renderer
            .session(&mut p.prepared, &s.0.camera, &settings, target)?;
        out(out_session, IllumSession { session })
    })
}

/// Moves the session's camera to `scene`'s; the next pass should start at sample 0.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_set_camera(
    session: *mut IllumSession,
    scene: *const IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(session, "session")?;
        let scene = scene.as_ref().ok_or_else(|| null("scene"))?;
        s.session.set_camera(&scene.0.camera)
    })
}

/// Records samples [first_sample, first_sample + sample_count) into the host's command buffer
/// `cmd` (recording, outside a render pass) and resolves them into the target.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_record_pass(
    session: *mut IllumSession,
    cmd: vk::CommandBuffer,
    first_sample: u32,
    sample_count: u32,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(session, "session")?;
        if cmd.is_null() {
            return Err(null("the VkCommandBuffer"));
        }
        s.session.record_pass(
            cmd,
            &Pass {
                first_sample,
                sample_count,
            },
        )
    })
}

/// Frees the session (the host's passes must have completed).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_destroy(session: *mut IllumSession) {
    if !session.is_null() {
        // SAFETY: a handle from illum_session_create, destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(session) })));
    }
}
