//! The C API's scene builder: scenes built in code (scene::SceneBuilder), with meshes and
//! textures from host memory. Materials, analytic shapes and lights are given as the scene
//! format's JSON objects (docs/scene-format.md), so every field of the format is reachable from
//! C; `illum_scene_builder_build` validates it all as the loader does, with the same errors.

use super::{IllumScene, IllumStatus, guard, handle, null, out, str_arg};
use crate::error::Error;
use crate::scene::SceneBuilder;
use crate::scene::format::{CameraDef, MeshDef, ShapeDef, TransformDef};
use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A scene being built (see illum_scene_builder_create).
pub struct IllumSceneBuilder(SceneBuilder);

/// `n` values at `p`, or an error naming `field` when `p` is NULL.
unsafe fn slice<'a, T>(p: *const T, n: usize, field: &str) -> Result<&'a [T], Error> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(null(field));
    }
    // SAFETY: the caller passes `n` readable values.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// `n` values at `p` if `p` is not NULL.
unsafe fn optional<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    // SAFETY: as `slice`.
    (!p.is_null()).then(|| unsafe { std::slice::from_raw_parts(p, n) })
}

/// A builder whose look-at camera is at `position` (3 doubles) looking at `look_at`, with a
/// vertical field of view of `fov_y` degrees and `width` × `height` pixels.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_create(
    position: *const f64,
    look_at: *const f64,
    fov_y: f64,
    width: u32,
    height: u32,
    out_builder: *mut *mut IllumSceneBuilder,
) -> IllumStatus {
    guard(|| unsafe {
        let p = slice(position, 3, "position")?;
        let l = slice(look_at, 3, "look_at")?;
        let camera = CameraDef::look_at(
            [p[0], p[1], p[2]],
            [l[0], l[1], l[2]],
            fov_y,
            [width, height],
        );
        out(out_builder, IllumSceneBuilder(SceneBuilder::new(camera)))
    })
}

/// Adds the object `json` of the scene format's `section` as `name`, through `add`: the body of
/// the material, shape and light entries.
unsafe fn add_def<T: serde::de::DeserializeOwned>(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    json: *const c_char,
    section: &str,
    add: impl FnOnce(&mut SceneBuilder, &str, T),
) -> IllumStatus {
    guard(|| unsafe {
        let b = handle(builder, "builder")?;
        let n = str_arg(name, "name")?;
        let json = str_arg(json, "json")?;
        let def = serde_json::from_str(json)
            .map_err(|e| Error::Invalid(format!("{section}.{n}: {e} (in {json:?})")))?;
        add(&mut b.0, n, def);
        Ok(())
    })
}

/// Adds material `name`: a JSON object of the scene format's "materials" section, e.g.
/// `{"diffuse": [0.8, 0.2, 0.2], "diffuse_texture": "checker"}`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_material(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    json: *const c_char,
) -> IllumStatus {
    unsafe {
        add_def(builder, name, json, "materials", |b, n, d| {
            b.material(n, d);
        })
    }
}

/// Adds shape `name`: a JSON object of the scene format's "shapes" section (sphere, rect, disk;
/// meshes from host memory through illum_scene_builder_mesh).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_shape(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    json: *const c_char,
) -> IllumStatus {
    unsafe {
        add_def(builder, name, json, "shapes", |b, n, d: ShapeDef| {
            b.shape(n, d);
        })
    }
}

/// Adds light `name`: a JSON object of the scene format's "lights" section.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_light(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    json: *const c_char,
) -> IllumStatus {
    unsafe {
        add_def(builder, name, json, "lights", |b, n, d| {
            b.light(n, d);
        })
    }
}

/// Adds triangle mesh `name` of material `material` from host arrays (copied): `vertex_count`
/// positions (3 floats each), optional normals (3 floats each) and uvs (2 floats each) per vertex
/// (NULL: none), `index_count` indices (3 per triangle, counter-clockwise = front), and an
/// optional object-to-world matrix (16 doubles, row-major; NULL: identity).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_mesh(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    material: *const c_char,
    positions: *const f32,
    normals: *const f32,
    uvs: *const f32,
    vertex_count: usize,
    indices: *const u32,
    index_count: usize,
    matrix: *const f64,
) -> IllumStatus {
    guard(|| unsafe {
        let b = handle(builder, "builder")?;
        let n = str_arg(name, "name")?;
        let field = |f: &str| format!("shapes.{n}.mesh.{f}");
        let count = vertex_count.checked_mul(3).ok_or_else(|| {
            Error::Invalid(format!("{}: {vertex_count} vertices", field("positions")))
        })?;
        let triples = |v: &[f32]| -> Vec<[f64; 3]> {
            v.chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]].map(f64::from))
                .collect()
        };
        let mesh = MeshDef {
            positions: triples(slice(positions, count, &field("positions"))?),
            indices: Some(slice(indices, index_count, &field("indices"))?.to_vec()),
            normals: optional(normals, count).map(triples),
            uvs: optional(uvs, 2 * vertex_count).map(|v| {
                v.chunks_exact(2)
                    .map(|t| [f64::from(t[0]), f64::from(t[1])])
                    .collect()
            }),
            tangents: None,
        };
        let transform = optional(matrix, 16).map(|m| TransformDef {
            matrix: Some(m.try_into().expect("16 values")),
            ..Default::default()
        });
        b.0.shape(
            n,
            ShapeDef {
                mesh: Some(mesh),
                material: Some(str_arg(material, "material")?.to_owned()),
                transform,
                ..Default::default()
            },
        );
        Ok(())
    })
}

/// Adds texture `name` from host pixels (copied): `width` × `height` texels, row-major, top row
/// first, `channels` floats each (3: RGB, alpha 1; 4: RGBA), linear, or sRGB-encoded in RGB when
/// `srgb` is non-zero.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_texture(
    builder: *mut IllumSceneBuilder,
    name: *const c_char,
    width: u32,
    height: u32,
    channels: u32,
    pixels: *const f32,
    srgb: u32,
) -> IllumStatus {
    guard(|| unsafe {
        let b = handle(builder, "builder")?;
        let n = str_arg(name, "name")?;
        let field = format!("textures.{n}.pixels");
        if channels != 3 && channels != 4 {
            return Err(Error::Invalid(format!(
                "{field}: {channels} channels (must be 3, RGB, or 4, RGBA)"
            )));
        }
        let count = (width as usize)
            .checked_mul(height as usize)
            .and_then(|t| t.checked_mul(channels as usize))
            .ok_or_else(|| Error::Invalid(format!("{field}: {width}x{height} is too large")))?;
        let v = slice(pixels, count, &field)?;
        let rgba: Vec<f32> = if channels == 4 {
            v.to_vec()
        } else {
            v.chunks_exact(3)
                .flat_map(|t| [t[0], t[1], t[2], 1.0])
                .collect()
        };
        b.0.texture_pixels(n, width, height, &rgba, srgb != 0);
        Ok(())
    })
}

/// Validates what was added (errors name the object and field, as the loader's do) and returns
/// the scene; the builder stays usable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_build(
    builder: *const IllumSceneBuilder,
    out_scene: *mut *mut IllumScene,
) -> IllumStatus {
    guard(|| unsafe {
        let b = builder.as_ref().ok_or_else(|| null("builder"))?;
        let scene = b.0.build()?;
        out(out_scene, IllumScene(scene))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn illum_scene_builder_destroy(builder: *mut IllumSceneBuilder) {
    if !builder.is_null() {
        // SAFETY: a handle from illum_scene_builder_create, destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(builder) })));
    }
}
