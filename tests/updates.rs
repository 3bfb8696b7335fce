//! Updates of a prepared scene without preparing it again: a moved camera uploads
//! nothing but its frame constants, edited materials and lights write their own tables only, a
//! moved instance rebuilds the top level of the trace structure and no bottom level; each gives
//! the image of the edited scene prepared from scratch, bit for bit.

mod common;
use common::*;
use illum::render::{PreparedScene, RenderSettings, Renderer};
use illum::scene::Scene;
use illum::vk::Context;

/// SMALL_SCENE with a mesh instance (a tilted card) in it.
const SCENE: &str = r#"{"camera": {"position": [0, 1.2, 3], "look_at": [0, 0.3, 0], "fov_y": 40, "resolution": [13, 9]},
    "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6], "specular": [{"model": "ggx", "roughness": 0.2}]},
                  "ball": {"diffuse": [0.7, 0.3, 0.2]}, "card": {"diffuse": [0.2, 0.5, 0.7]}},
    "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
               "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "ball"},
               "card": {"mesh": {"positions": [[-0.4, 0, 0], [0.4, 0, 0], [0.4, 0.8, 0], [-0.4, 0.8, 0]], "indices": [0, 1, 2, 0, 2, 3]},
                        "material": "card", "transform": {"translate": [-0.9, 0, 0.2], "rotate": [0, 30, 0]}}},
    "lights": {"key": {"rect": {"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]}, "intensity": 6},
               "sky": {"dome": {}, "color": [0.2, 0.3, 0.4]}}}"#;

fn settings() -> RenderSettings {
    RenderSettings {
        spp: 4,
        seed: 5,
        trace: trace_mode(),
        ..Default::default()
    }
}

fn render_prepared(r: &Renderer, p: &PreparedScene, scene: &Scene) -> illum::output::Film {
    r.render_prepared(p, &scene.camera, &settings(), &[5], &mut |_, _| {})
        .unwrap()
        .remove(0)
        .film
}

/// Counters of the context around `f`: (uploads, bytes, bottom-level builds, top-level builds).
fn counted<R>(ctx: &Context, f: impl FnOnce() -> R) -> (R, [u64; 4]) {
    let (u0, b0) = ctx.upload_counts();
    let (bl0, tl0) = ctx.build_counts();
    let r = f();
    let (u1, b1) = ctx.upload_counts();
    let (bl1, tl1) = ctx.build_counts();
    (r, [u1 - u0, b1 - b0, bl1 - bl0, tl1 - tl0])
}

/// Applies `edit` to the scene, updates the prepared scene, and checks the update's counts and
/// that it renders as the edited scene prepared afresh (and unlike the scene before the edit).
fn check_update(
    ctx: &Context,
    r: &Renderer,
    prepared: &mut PreparedScene,
    scene: &mut Scene,
    edit: impl FnOnce(&mut Scene),
    tables: &[&str],
    builds: [u64; 2],
) {
    let before = render_prepared(r, prepared, scene);
    edit(scene);
    let (u, n) = counted(ctx, || prepared.update(ctx, scene).unwrap());
    eprintln!("update {tables:?}: {:.3} ms, counts {n:?}", u.seconds * 1e3);
    assert_eq!(u.tables, tables, "tables written");
    assert_eq!(n[0], tables.len() as u64, "uploads");
    assert_eq!([n[2], n[3]], builds, "bottom and top levels built");
    let updated = render_prepared(r, prepared, scene);
    let fresh = r.render(scene, &settings(), &mut |_, _| {}).unwrap().film;
    assert!(
        updated == fresh,
        "the updated scene renders otherwise than the edited one"
    );
    assert!(updated != before, "the edit changed nothing in the image");
}

#[test]
fn updates_write_only_what_changed_and_render_the_edited_scene() {
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let mut scene = scene(SCENE);
    let mut prepared = r.prepare(&scene, trace_mode()).unwrap();
    r.loop_limited().unwrap();
    // A moved camera: nothing is written, nothing built; a render uploads its frame only.
    let mut moved = scene.clone();
    moved.camera.position = glam::DVec3::new(0.4, 1.3, 2.8);
    let (u, n) = counted(&ctx, || prepared.update(&ctx, &moved).unwrap());
    assert!(u.tables.is_empty() && !u.instances_moved, "{u:?}");
    assert_eq!(n, [0; 4]);
    let (_, n) = counted(&ctx, || render_prepared(&r, &prepared, &moved));
    let frame = std::mem::size_of::<illum::layout::Frame>() as u64;
    assert_eq!(n, [1, frame, 0, 0], "a render after a camera move");

    let m = scene
        .materials
        .iter()
        .position(|m| m.name == "ball")
        .unwrap();
    check_update(
        &ctx,
        &r,
        &mut prepared,
        &mut scene,
        |s| s.materials[m].diffuse = glam::Vec3::new(0.2, 0.7, 0.3),
        &["materials"],
        [0, 0],
    );
    let l = scene.lights.iter().position(|l| l.name == "key").unwrap();
    check_update(
        &ctx,
        &r,
        &mut prepared,
        &mut scene,
        |s| s.lights[l].intensity *= 0.5,
        &["lights"],
        [0, 0],
    );
    // The instance's transform: its table, then the top level (instance records, nodes and
    // header on the compute BVH; the instance buffer on ray queries), no bottom level.
    let expected_top_uploads = if prepared.trace_name() == "bvh" { 3 } else { 1 };
    let before = render_prepared(&r, &prepared, &scene);
    scene.instances[0].transform = glam::DMat4::from_translation(glam::DVec3::new(0.6, 0.0, 0.9))
        * scene.instances[0].transform;
    let (u, n) = counted(&ctx, || prepared.update(&ctx, &scene).unwrap());
    eprintln!("instance moved: {:.3} ms, counts {n:?}", u.seconds * 1e3);
    assert_eq!(u.tables, ["instances"]);
    assert!(u.instances_moved);
    assert_eq!(n[0], 1 + expected_top_uploads, "uploads");
    assert_eq!([n[2], n[3]], [0, 1], "bottom and top levels built");
    let updated = render_prepared(&r, &prepared, &scene);
    let fresh = r.render(&scene, &settings(), &mut |_, _| {}).unwrap().film;
    assert!(
        updated == fresh,
        "the moved instance renders otherwise than a fresh scene"
    );
    assert!(updated != before, "moving the instance changed nothing");
    assert_no_validation_messages(&ctx);
}

#[test]
fn an_update_cannot_change_geometry() {
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let scene = scene(SCENE);
    let mut prepared = r.prepare(&scene, trace_mode()).unwrap();
    let mut edited = scene.clone();
    if let illum::scene::ShapeGeometry::Sphere { radius, .. } = &mut edited.shapes[1].geometry {
        *radius = 0.6;
    }
    let e = prepared.update(&ctx, &edited).unwrap_err().to_string();
    assert!(
        e.contains("analytic shapes") && e.contains("prepare the scene again"),
        "{e}"
    );
    let mut edited = scene.clone();
    edited.meshes[0].positions[0].x += 0.1;
    let e = prepared.update(&ctx, &edited).unwrap_err().to_string();
    assert!(e.contains("mesh geometry"), "{e}");
    let mut edited = scene.clone();
    let l = edited.lights.iter().position(|l| l.name == "key").unwrap();
    edited.lights[l].intensity = 0.0;
    let e = prepared.update(&ctx, &edited).unwrap_err().to_string();
    assert!(e.contains("prepare the scene again"), "{e}");
    assert_no_validation_messages(&ctx);
}

/// What an update cannot bring is refused, naming it, never silently left as it was: texture
/// pixels and mesh normals (also uvs and tangents), as geometry is (above).
#[test]
fn an_update_refuses_what_it_cannot_upload() {
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let json = SCENE
        .replace(
            r#""ball": {"diffuse": [0.7, 0.3, 0.2]}"#,
            r#""ball": {"diffuse": [1, 1, 1], "diffuse_texture": "t"}"#,
        )
        .replace(
            r#""materials""#,
            r#""textures": {"t": {"file": "t.png"}}, "materials""#,
        );
    let dir = temp_path("update-refusals");
    std::fs::create_dir_all(&dir).unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 50, 50]))
        .save(dir.join("t.png"))
        .unwrap();
    let scene = illum::scene::from_json_str(&json, "<scene>", &dir).unwrap();
    let mut prepared = r.prepare(&scene, trace_mode()).unwrap();
    let refused = |prepared: &mut PreparedScene, edited: &Scene, what: &str| {
        let e = prepared.update(&ctx, edited).unwrap_err().to_string();
        assert!(e.contains(what), "{e}");
    };
    let mut pixels = scene.clone();
    pixels.textures[0].texels[0].x = 0.1;
    refused(&mut prepared, &pixels, "texture pixels");
    let mut normals = scene.clone();
    let card = normals
        .meshes
        .iter_mut()
        .find(|m| m.name.contains("card"))
        .unwrap();
    card.normals = Some(vec![glam::Vec3::Z; card.positions.len()]);
    refused(&mut prepared, &normals, "mesh normals");
    // The prepared scene is as it was: an unchanged scene updates with nothing written.
    assert!(prepared.update(&ctx, &scene).unwrap().tables.is_empty());
    assert_no_validation_messages(&ctx);
}
