//! Scene loading through the public API: good files load with the right values, each kind of
//! bad input gives its specific message (file, field path, value), glTF files written here
//! load with the documented mapping.

#[path = "scene_load/gltf_files.rs"]
mod gltf_files;
#[path = "scene_load/invalid.rs"]
mod invalid;
#[path = "common/scratch.rs"]
mod scratch;

use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use illum::scene::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// A fresh, empty directory in this process's scratch folder (tests/common/scratch.rs).
pub fn temp_dir(tag: &str) -> PathBuf {
    static N: AtomicU32 = AtomicU32::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    scratch::scratch_dir(&format!("scene-{tag}-{n}"))
}

pub const CAMERA: &str =
    r#""camera": { "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 }"#;

/// Loads `body` (the scene's top-level members after the camera) as "bad.json" in `dir`.
pub fn load_in(dir: &Path, body: &str) -> Result<Scene, SceneError> {
    let text = format!("{{ {CAMERA}, {body} }}");
    from_json_str(&text, "bad.json", dir)
}

/// The error message of loading `text` (a whole file), which must fail.
pub fn error_of_file(text: &str) -> String {
    match from_json_str(text, "bad.json", Path::new(".")) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Asserts that loading fails with a message containing every piece of `expected`.
#[track_caller]
pub fn assert_error(text: &str, expected: &[&str]) {
    let msg = error_of_file(text);
    for piece in expected {
        assert!(
            msg.contains(piece),
            "error message\n  {msg}\nshould contain\n  {piece}"
        );
    }
}

pub fn approx_mat(a: &DMat4, b: &DMat4, eps: f64) -> bool {
    a.to_cols_array()
        .iter()
        .zip(b.to_cols_array())
        .all(|(x, y)| (x - y).abs() <= eps)
}

#[test]
fn default_scene_loads() {
    let s = default_scene();
    assert_eq!((s.camera.width, s.camera.height), (768, 384));
    assert_eq!(s.shapes.len(), 7, "ground + 6 spheres");
    assert_eq!(s.lights.len(), 2);
    assert!(s.source.is_none());
    let rough: Vec<f32> = s.materials[1..6]
        .iter()
        .map(|m| m.specular[0].alpha.x)
        .collect();
    assert_eq!(rough, [0.6, 0.3, 0.15, 0.05, 0.01]);
    let aniso = s
        .materials
        .iter()
        .find(|m| m.name == "brushed_aluminium")
        .unwrap();
    assert_eq!(aniso.specular[0].alpha, Vec2::new(0.05, 0.4));
    assert_eq!(aniso.specular[0].distribution, Distribution::DBrdf);
    assert!(matches!(s.lights[1].kind, LightKind::Dome { .. }));
    let sky = s.lights[1].radiance();
    assert!(
        sky.min_element() >= 0.3 && sky.max_element() <= 0.5,
        "{sky}"
    );
}

fn write_test_images(dir: &Path) {
    let png = image::RgbaImage::from_raw(2, 1, vec![128, 0, 255, 255, 0, 0, 0, 128]).unwrap();
    png.save(dir.join("albedo.png")).unwrap();
    let pixels = [[0.5f32, 2.0, 4.0, 1.0], [8.0, 0.25, 0.0, 1.0]];
    exr::prelude::write_rgba_file(dir.join("sky.exr"), 2, 1, |x, _| {
        let p = pixels[x];
        (p[0], p[1], p[2], p[3])
    })
    .unwrap();
}

const EVERY_FORM: &str = r#"{
  "$schema": "../docs/scene.schema.json",
  "camera": { "position": [0, 1, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0], "fov_y": 40, "resolution": [320, 200] },
  "textures": {
    "albedo": { "file": "albedo.png" },
    "sky": { "file": "sky.exr" },
    "albedo_linear": { "file": "albedo.png", "srgb": false }
  },
  "materials": {
    "grey": {},
    "plastic": {
      "diffuse": [0.8, 0.1, 0.1], "diffuse_texture": "albedo",
      "specular": [
        { "model": "dbrdf", "roughness": 0.3, "fresnel": { "constant": [0.04, 0.04, 0.04] } },
        { "model": "ggx", "roughness": [0.1, 0.5] }
      ],
      "tangent": [1, 0, 0]
    },
    "metal": { "diffuse": [0, 0, 0], "specular": [{ "model": "beckmann", "roughness": 1,
      "fresnel": { "conductor": { "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2] } } }] },
    "schlick": { "specular": [{ "model": "ggx", "roughness": 0.2, "fresnel": { "schlick": [0.9, 0.8, 0.5] } }] },
    "glow": { "emission": [4, 3, 2], "emission_texture": "albedo_linear", "two_sided": true }
  },
  "shapes": {
    "ball": { "sphere": { "center": [0, 1, 0], "radius": 1 }, "material": "plastic" },
    "floor": { "rect": { "center": [0, 0, 0], "normal": [0, 1, 0], "size": [10, 4] }, "material": "grey" },
    "wall": { "rect": { "center": [0, 0, -2], "normal": [0, 0, 2], "size": [2, 3], "up": [0, 5, 0] }, "material": "grey" },
    "coin": { "disk": { "center": [1, 0, 0], "normal": [0, 3, 0], "radius": 0.5 }, "material": "metal" },
    "tri": {
      "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], "indices": [0, 1, 2, 2, 1, 3],
                "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 2]], "uvs": [[0, 0], [1, 0], [0, 1], [1, 1]] },
      "material": "glow",
      "transform": { "translate": [1, 2, 3], "rotate": [90, 0, 30], "scale": 2 }
    },
    "soup": {
      "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] },
      "material": "schlick",
      "transform": { "matrix": [1, 0, 0, 5,  0, 2, 0, 6,  0, 0, 3, 7,  0, 0, 0, 1] }
    },
    "stretched": {
      "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] },
      "material": "grey",
      "transform": { "scale": [1, 2, 3] }
    }
  },
  "lights": {
    "key": { "rect": { "center": [0, 4, 0], "normal": [0, -1, 0], "size": [1, 2], "up": [1, 0, 0] },
             "color": [1, 0.5, 0.25], "intensity": 10, "exposure": 1, "two_sided": true, "texture": "albedo", "visible": false },
    "fill": { "disk": { "center": [2, 2, 2], "normal": [-1, -1, -1], "radius": 0.5 } },
    "bulb": { "sphere": { "center": [0, 3, 0], "radius": 0.1 }, "intensity": 100 },
    "env": { "dome": { "rotation": 90 }, "color": [0.2, 0.3, 0.5], "texture": "sky" },
    "sun": { "sun": { "direction": [0, 2, 0] }, "intensity": 100000, "exposure": -2 }
  }
}"#;

#[test]
fn every_form_loads() {
    let dir = temp_dir("every-form");
    write_test_images(&dir);
    std::fs::write(dir.join("every.json"), EVERY_FORM).unwrap();
    let s = load(&dir.join("every.json")).unwrap();
    assert_eq!(s.source.as_deref(), Some(dir.join("every.json").as_path()));

    let c = &s.camera;
    assert_eq!((c.width, c.height, c.fov_y_deg), (320, 200, 40.0));
    assert_eq!(c.look_at, DVec3::new(0.0, 0.5, 0.0));

    // Textures in file order; PNG decoded from sRGB unless srgb: false; EXR linear.
    assert_eq!(s.textures.len(), 3);
    let t = &s.textures[0];
    assert_eq!((t.name.as_str(), t.width, t.height), ("albedo", 2, 1));
    assert!((t.texels[0].x - 0.2158605).abs() < 1e-5, "{}", t.texels[0]);
    assert_eq!(t.texels[0].z, 1.0);
    assert!(
        (t.texels[1].w - 128.0 / 255.0).abs() < 1e-6,
        "alpha stays linear"
    );
    assert_eq!(s.textures[1].texels[0], Vec4::new(0.5, 2.0, 4.0, 1.0));
    assert_eq!(s.textures[1].texels[1], Vec4::new(8.0, 0.25, 0.0, 1.0));
    assert!((s.textures[2].texels[0].x - 128.0 / 255.0).abs() < 1e-6);

    // Materials.
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["grey", "plastic", "metal", "schlick", "glow"]);
    let grey = &s.materials[0];
    assert_eq!(grey.diffuse, Vec3::splat(0.5));
    assert!(grey.specular.is_empty() && grey.emission == Vec3::ZERO && !grey.two_sided);
    let plastic = &s.materials[1];
    assert_eq!(plastic.diffuse_texture, Some(0));
    assert_eq!(plastic.tangent_direction, Some(Vec3::X));
    assert_eq!(plastic.specular.len(), 2);
    assert_eq!(plastic.specular[0].distribution, Distribution::DBrdf);
    assert_eq!(plastic.specular[0].alpha, Vec2::splat(0.3));
    assert_eq!(
        plastic.specular[0].fresnel,
        Fresnel::Constant(Vec3::splat(0.04))
    );
    assert_eq!(plastic.specular[1].distribution, Distribution::GgxSmith);
    assert_eq!(plastic.specular[1].alpha, Vec2::new(0.1, 0.5));
    let default_f0 = Fresnel::Schlick {
        f0: Vec3::splat(0.04),
    };
    assert_eq!(plastic.specular[1].fresnel, default_f0);
    let metal = &s.materials[2].specular[0];
    assert_eq!(metal.distribution, Distribution::BeckmannSmith);
    assert_eq!(
        metal.fresnel,
        Fresnel::Conductor {
            eta: Vec3::new(0.2, 0.9, 1.1),
            k: Vec3::new(3.9, 2.4, 2.2)
        }
    );
    let glow = &s.materials[4];
    assert_eq!(
        (glow.emission, glow.emission_texture, glow.two_sided),
        (Vec3::new(4.0, 3.0, 2.0), Some(2), true)
    );

    // Analytic shapes in file order; rect edges follow the documented convention.
    assert_eq!(s.shapes.len(), 4);
    assert_eq!(
        s.shapes[0].geometry,
        ShapeGeometry::Sphere {
            center: DVec3::Y,
            radius: 1.0
        }
    );
    assert_eq!(s.shapes[0].material, 1);
    let ShapeGeometry::Rect { u, v, .. } = s.shapes[1].geometry else {
        panic!()
    };
    assert_eq!(
        (u, v),
        (DVec3::new(10.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -4.0))
    );
    assert_eq!(u.cross(v).normalize(), DVec3::Y);
    let ShapeGeometry::Rect { center, u, v } = s.shapes[2].geometry else {
        panic!()
    };
    assert_eq!(center, DVec3::new(0.0, 0.0, -2.0));
    assert!(u.abs_diff_eq(DVec3::new(2.0, 0.0, 0.0), 1e-12), "{u}");
    assert!(v.abs_diff_eq(DVec3::new(0.0, 3.0, 0.0), 1e-12), "{v}");
    let disk = ShapeGeometry::Disk {
        center: DVec3::X,
        normal: DVec3::Y,
        radius: 0.5,
    };
    assert_eq!(s.shapes[3].geometry, disk);

    // Meshes and their transforms.
    assert_eq!((s.meshes.len(), s.instances.len()), (3, 3));
    let tri = &s.meshes[0];
    assert_eq!(tri.indices, [0, 1, 2, 2, 1, 3]);
    assert_eq!(
        tri.normals.as_ref().unwrap()[3],
        Vec3::Z,
        "normals are normalized"
    );
    assert_eq!(tri.uvs.as_ref().unwrap()[3], Vec2::ONE);
    assert_eq!(tri.material, 4);
    assert_eq!(s.meshes[1].indices, [0, 1, 2], "sequential by default");
    assert!(s.meshes[1].normals.is_none() && s.meshes[1].uvs.is_none());
    let expected = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0))
        * DMat4::from_rotation_z(30f64.to_radians())
        * DMat4::from_rotation_x(90f64.to_radians())
        * DMat4::from_scale(DVec3::splat(2.0));
    assert!(approx_mat(&s.instances[0].transform, &expected, 1e-12));
    assert_eq!(s.instances[0].name, "tri");
    let m = s.instances[1].transform;
    assert_eq!(
        m.transform_point3(DVec3::ONE),
        DVec3::new(6.0, 8.0, 10.0),
        "row-major matrix"
    );
    assert_eq!(
        s.instances[2].transform,
        DMat4::from_scale(DVec3::new(1.0, 2.0, 3.0))
    );

    // Lights.
    assert_eq!(s.lights.len(), 5);
    let key = &s.lights[0];
    let LightKind::Rect { u, v, .. } = key.kind else {
        panic!()
    };
    assert!(v.abs_diff_eq(DVec3::new(2.0, 0.0, 0.0), 1e-12), "{v}");
    assert!(u.abs_diff_eq(DVec3::new(0.0, 0.0, -1.0), 1e-12), "{u}");
    assert!(u.cross(v).normalize().abs_diff_eq(DVec3::NEG_Y, 1e-12));
    assert_eq!(key.radiance(), Vec3::new(20.0, 10.0, 5.0));
    assert!(key.two_sided && !key.visible && key.texture == Some(0));
    let fill = &s.lights[1];
    let LightKind::Disk { normal, radius, .. } = fill.kind else {
        panic!()
    };
    assert!(normal.abs_diff_eq(DVec3::splat(-1.0 / 3f64.sqrt()), 1e-12) && radius == 0.5);
    assert_eq!(
        (fill.color, fill.intensity, fill.exposure),
        (Vec3::ONE, 1.0, 0.0)
    );
    assert!(fill.visible && !fill.two_sided && fill.texture.is_none());
    assert_eq!(
        s.lights[2].kind,
        LightKind::Sphere {
            center: DVec3::new(0.0, 3.0, 0.0),
            radius: 0.1
        }
    );
    assert_eq!(
        s.lights[3].kind,
        LightKind::Dome {
            rotation_deg: 90.0,
            convention: illum::scene::DomeConvention::Illum
        }
    );
    assert_eq!(s.lights[3].texture, Some(1));
    let sun = LightKind::Sun {
        direction: DVec3::Y,
        angular_diameter_deg: 0.53,
    };
    assert_eq!(s.lights[4].kind, sun);
    assert_eq!(s.lights[4].radiance(), Vec3::splat(25000.0));
}

#[test]
fn load_reports_missing_scene_file() {
    let dir = temp_dir("missing");
    let path = dir.join("nope.json");
    let msg = load(&path).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!("{}: cannot read: No such file or directory", path.display())
    );
}

#[test]
fn committed_schema_is_current() {
    let generated = serde_json::to_string_pretty(&json_schema()).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene.schema.json");
    if std::env::var_os("ILLUM_WRITE_SCHEMA").is_some() {
        std::fs::write(&path, format!("{generated}\n")).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed.trim_end() == generated,
        "docs/scene.schema.json is stale; regenerate it with\n  \
         cargo run --release -- schema > docs/scene.schema.json\n\
         or\n  ILLUM_WRITE_SCHEMA=1 cargo test --release --test scene_load committed_schema_is_current"
    );
}

#[test]
fn rotate_applies_x_then_y_then_z() {
    let body = r#""materials": { "m": {} }, "shapes": { "t": {
        "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }, "material": "m",
        "transform": { "rotate": [90, 90, 0] } } }"#;
    let s = load_in(Path::new("."), body).unwrap();
    // +Y → (X by 90°) +Z → (Y by 90°) +X.
    let y = s.instances[0].transform.transform_vector3(DVec3::Y);
    assert!(y.abs_diff_eq(DVec3::X, 1e-12), "{y}");
}

/// A texture's first bytes are checked before the file is read: a 1 GiB sparse file named .png
/// was read whole (1.05 GB resident) before its decoder refused it; a PNG named .jpg is named.
#[test]
fn texture_files_are_sniffed_before_they_are_read() {
    let dir = temp_dir("sniff");
    let big = std::fs::File::create(dir.join("huge.png")).unwrap();
    big.set_len((1 << 30) - 1).unwrap();
    let png = dir.join("img.png");
    image::RgbImage::new(2, 2).save(&png).unwrap();
    std::fs::copy(&png, dir.join("png.jpg")).unwrap();
    for (file, needle) in [
        ("huge.png", "no image file of a known kind"),
        ("png.jpg", "Png data, not what its name says"),
    ] {
        let body = format!(
            r#""textures": {{"t": {{"file": "{file}"}}}}, "lights": {{"sky": {{"dome": {{}}}}}}"#
        );
        let e = load_in(&dir, &body).expect_err(file).to_string();
        assert!(e.contains("textures.t.file") && e.contains(file), "{e}");
        assert!(e.contains(needle), "{e}");
    }
    let ok = r#""textures": {"t": {"file": "img.png"}}, "lights": {"sky": {"dome": {}}}"#;
    load_in(&dir, ok).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A stage's inputs (what `illum view` watches) are every layer it composed — sublayers,
/// references — besides the root layer and the images it names.
#[test]
fn a_stage_s_inputs_are_its_layers() {
    let dir = temp_dir("usd-inputs");
    std::fs::write(
        dir.join("root.usda"),
        "#usda 1.0\n(\n    subLayers = [@lights.usda@]\n)\n\
         def Camera \"Cam\" {}\n\
         def Xform \"World\" (\n    prepend references = @ball.usda@\n) {}\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("lights.usda"),
        "#usda 1.0\ndef DomeLight \"Sky\" {}\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("ball.usda"),
        "#usda 1.0\n(\n    defaultPrim = \"Ball\"\n)\ndef Sphere \"Ball\" {}\n",
    )
    .unwrap();
    let scene = load(&dir.join("root.usda")).unwrap();
    let names: Vec<String> = scene
        .inputs
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names[0], "root.usda", "{names:?}");
    for layer in ["lights.usda", "ball.usda"] {
        assert_eq!(names.iter().filter(|n| *n == layer).count(), 1, "{names:?}");
    }
    assert_eq!(names.len(), 3, "{names:?}");
}

/// A metallic-roughness material's maps: one texture's G and B are used as they are; other
/// channels are packed into a texture of their own (G roughness, B metallic, 1 where no map
/// says); maps of two sizes are refused naming the field.
#[test]
fn metallic_roughness_maps_are_packed_or_refused() {
    let dir = temp_dir("mr-maps");
    write_test_images(&dir);
    exr::prelude::write_rgba_file(dir.join("one.exr"), 1, 1, |_, _| (0.5, 0.5, 0.5, 1.0)).unwrap();
    let scene = |materials: &str| {
        std::fs::write(
            dir.join("mr.json"),
            format!(
                r#"{{ {CAMERA}, "textures": {{ "sky": {{ "file": "sky.exr" }}, "one": {{ "file": "one.exr" }} }},
                "materials": {{ {materials} }},
                "shapes": {{ "ball": {{ "sphere": {{ "center": [0, 1, 0], "radius": 1 }}, "material": "m" }} }} }}"#
            ),
        )
        .unwrap();
        load(&dir.join("mr.json"))
    };
    let glb = scene(
        r#""m": { "metallic_roughness": { "roughness_texture": { "texture": "sky" }, "metallic_texture": { "texture": "sky" } } }"#,
    )
    .unwrap();
    assert_eq!(
        glb.textures.len(),
        2,
        "G and B of one texture are used as they are"
    );
    assert_eq!(glb.materials[0].metallic_roughness_texture, Some(0));
    let packed = scene(
        r#""m": { "metallic_roughness": { "metallic_texture": { "texture": "sky", "channel": "r" } } }"#,
    )
    .unwrap();
    assert_eq!(packed.textures.len(), 3);
    assert_eq!(packed.materials[0].metallic_roughness_texture, Some(2));
    let (src, p) = (&packed.textures[0], &packed.textures[2]);
    assert_eq!(
        (p.width, p.height, p.wrap, p.filter),
        (src.width, src.height, src.wrap, src.filter)
    );
    for (t, s) in p.texels.iter().zip(&src.texels) {
        assert_eq!(
            (t.y, t.z),
            (1.0, s.x),
            "roughness 1, metallic the R channel"
        );
    }
    let err = scene(
        r#""m": { "metallic_roughness": { "roughness_texture": { "texture": "sky" }, "metallic_texture": { "texture": "one", "channel": "r" } } }"#,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("materials.m.metallic_roughness.metallic_texture.texture")
            && err.contains("must have one size"),
        "{err}"
    );
}
