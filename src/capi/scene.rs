//! The C API's scenes, prepared scenes, blocking renders and sessions (see the parent module).

use super::{
    IllumContext, IllumPrepared, IllumScene, IllumSession, IllumStatus, guard, handle, null, out,
    str_arg,
};
use crate::error::Error;
use crate::render::{ImageState, Integrator, Params, Pass, RenderSettings};
use ash::vk::{self, Handle};
use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

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

thread_local! {
    static WARNINGS: std::cell::RefCell<std::ffi::CString> =
        std::cell::RefCell::new(std::ffi::CString::default());
}

/// What the scene file holds that illum does not render (a USD stage's prims and attributes):
/// `*out_count` warnings, one per line in `*out_text` ("" when there are none), valid until
/// the thread's next call of this function.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_warnings(
    scene: *mut IllumScene,
    out_text: *mut *const c_char,
    out_count: *mut u32,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(scene, "scene")?;
        if out_text.is_null() || out_count.is_null() {
            return Err(null("out_text or out_count"));
        }
        let text =
            std::ffi::CString::new(s.0.warnings.join("\n").replace('\0', " ")).unwrap_or_default();
        *out_count = s.0.warnings.len() as u32;
        WARNINGS.with(|w| {
            *w.borrow_mut() = text;
            *out_text = w.borrow().as_ptr();
        });
        Ok(())
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_destroy(scene: *mut IllumScene) {
    if !scene.is_null() {
        // SAFETY: a handle from illum_scene_*, destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(scene) })));
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

fn target_image(t: &IllumTarget) -> crate::render::TargetImage {
    crate::render::TargetImage {
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
    }
}

/// The integrator named `name` (any of the integrators' table; NULL: the default, "direct"),
/// with its default parameters.
unsafe fn integrator_arg(name: *const c_char) -> Result<Arc<dyn Integrator>, Error> {
    if name.is_null() {
        return Ok(crate::integrators::default_integrator());
    }
    // SAFETY: the caller's NUL-terminated string.
    let n = unsafe { str_arg(name, "integrator")? };
    crate::integrators::create(n, &Params::new()).map_err(Error::Invalid)
}

/// A progressive render of `prepared` through `scene`'s camera into `target`, with `integrator`
/// ("direct", "path" or "full"; NULL: "direct"). `prepared` must not be used or destroyed until
/// the session is. Creation compiles the integrator's kernels (blocking), and with "full" warms
/// the radiosity cache up; the cache then stays fixed during passes (see RenderSession in the
/// Rust docs). illum_render renders with "direct", whose session images equal it bit for bit.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_create(
    context: *mut IllumContext,
    prepared: *mut IllumPrepared,
    scene: *const IllumScene,
    integrator: *const c_char,
    seed: u64,
    target: *const IllumTarget,
    out_session: *mut *mut IllumSession,
) -> IllumStatus {
    guard(|| unsafe {
        let c = handle(context, "context")?;
        let p: &'static mut IllumPrepared = handle(prepared, "prepared")?;
        let s = scene.as_ref().ok_or_else(|| null("scene"))?;
        let t = target.as_ref().ok_or_else(|| null("target"))?;
        let settings = RenderSettings {
            seed,
            ..RenderSettings::with_integrator(integrator_arg(integrator)?)
        };
        let session =
            c.renderer
                .session(&mut p.prepared, &s.0.camera, &settings, target_image(t))?;
        out(out_session, IllumSession { session })
    })
}

/// Also resolves AOV plane `plane` (e.g. "Direct", "IndirectDiffuse", "Reflection" for the path
/// and full integrators) into the host's `target` from the next pass on; an unknown plane is
/// ILLUM_STATUS_ERROR_INVALID with the integrator's planes in the message. The host's passes must
/// have completed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_add_aov_target(
    session: *mut IllumSession,
    plane: *const c_char,
    target: *const IllumTarget,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(session, "session")?;
        let plane = str_arg(plane, "plane")?;
        let t = target.as_ref().ok_or_else(|| null("target"))?;
        s.session.add_aov_target(plane, target_image(t))
    })
}

/// Brings the session's prepared scene to the edited `scene` (materials, lights, instance
/// transforms; its camera is ignored: illum_session_set_camera) and warms a radiosity cache up
/// again (blocking). The host's passes must have completed; the next pass should start at 0.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_update_scene(
    session: *mut IllumSession,
    scene: *const IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let s = handle(session, "session")?;
        let scene = scene.as_ref().ok_or_else(|| null("scene"))?;
        s.session.update_scene(&scene.0).map(|_| ())
    })
}

/// Warms the radiosity cache ("full") up again for the current camera, blocking (e.g. after a
/// large camera move). The host's passes must have completed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_session_refresh_cache(session: *mut IllumSession) -> IllumStatus {
    guard(|| unsafe { handle(session, "session")?.session.refresh_cache() })
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
