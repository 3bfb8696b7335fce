//! glTF loading: small .gltf / .glb files written by the test (base64 data URIs, an external
//! .bin, the GLB binary chunk), checked for counts, composed transforms, the material
//! mapping, the camera form, and rejections.

use super::{approx_mat, temp_dir};
use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use illum::scene::*;
use serde_json::{Value, json};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

/// Binary payload: attribute data followed by a PNG; views are 4-byte aligned.
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    fn push(&mut self, bytes: &[u8]) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views
            .push(json!({ "buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len() }));
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }
    fn f32s(&mut self, v: &[f32]) -> usize {
        self.push(&v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>())
    }
    fn u16s(&mut self, v: &[u16]) -> usize {
        self.push(&v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>())
    }
}

fn png_2x1() -> Vec<u8> {
    let img = image::RgbaImage::from_raw(2, 1, vec![255, 128, 0, 255, 0, 0, 255, 255]).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// How the buffer and the image are stored.
#[derive(Clone, Copy)]
enum Storage {
    DataUris,
    ExternalBin,
    Glb,
}

/// The test asset: mesh 0 has a quad (u16 indices, normals, uvs, material "paint") and a
/// triangle (no material). Node "parent" (T·R·S) has children "child" (mesh, translated) and
/// "cam" (camera 0); root node "copy" instances mesh 0 again with a matrix.
fn asset(storage: Storage) -> (Value, Vec<u8>) {
    let mut bin = Bin {
        data: Vec::new(),
        views: Vec::new(),
    };
    let quad_pos = bin.f32s(&[-1., -1., 0., 1., -1., 0., 1., 1., 0., -1., 1., 0.]);
    let quad_nrm = bin.f32s(&[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.]);
    let quad_uv = bin.f32s(&[0., 1., 1., 1., 1., 0., 0., 0.]);
    let quad_idx = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    let tri_pos = bin.f32s(&[0., 0., 0., 1., 0., 0., 0., 1., 0.]);
    let tri_idx = bin.u16s(&[0, 1, 2]);
    let png = png_2x1();
    let image = match storage {
        Storage::Glb => json!({ "bufferView": bin.push(&png), "mimeType": "image/png" }),
        _ => json!({ "uri": format!("data:image/png;base64,{}", b64(&png)) }),
    };
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    let buffer = match storage {
        Storage::DataUris => json!({
            "byteLength": bin.data.len(),
            "uri": format!("data:application/octet-stream;base64,{}", b64(&bin.data)) }),
        Storage::ExternalBin => json!({ "byteLength": bin.data.len(), "uri": "mesh%20data.bin" }),
        Storage::Glb => json!({ "byteLength": bin.data.len() }),
    };
    let vec3 = |view, count, min: [f32; 3], max: [f32; 3]| json!({ "bufferView": view, "componentType": 5126, "count": count, "type": "VEC3", "min": min, "max": max });
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "extensionsRequired": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{ "nodes": [0, 3] }],
        "nodes": [
            { "name": "parent", "translation": [1, 2, 3],
              "rotation": [0, (FRAC_PI_2 / 2.0).sin(), 0, (FRAC_PI_2 / 2.0).cos()],
              "scale": [2, 2, 2], "children": [1, 2] },
            { "name": "child", "mesh": 0, "translation": [0, 1, 0] },
            { "name": "cam", "camera": 0, "translation": [0, 0, 5] },
            { "name": "copy", "mesh": 0,
              "matrix": [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  -4, 0, 0, 1] }
        ],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }],
        "meshes": [{ "name": "thing", "primitives": [
            { "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0 },
            { "attributes": { "POSITION": 4 }, "indices": 5 }
        ] }],
        "materials": [{
            "name": "paint",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.2, 0.1, 1.0], "metallicFactor": 0.25, "roughnessFactor": 0.5,
                "baseColorTexture": { "index": 0 }
            },
            "emissiveFactor": [1.0, 0.5, 0.25],
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } },
            "doubleSided": true
        }],
        "textures": [{ "source": 0 }],
        "images": [image],
        "accessors": [
            vec3(quad_pos, 4, [-1., -1., 0.], [1., 1., 0.]),
            vec3(quad_nrm, 4, [0., 0., 1.], [0., 0., 1.]),
            { "bufferView": quad_uv, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": quad_idx, "componentType": 5123, "count": 6, "type": "SCALAR" },
            vec3(tri_pos, 3, [0., 0., 0.], [1., 1., 0.]),
            { "bufferView": tri_idx, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ],
        "bufferViews": bin.views,
        "buffers": [buffer]
    });
    (doc, bin.data)
}

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

/// Writes the asset into `dir` and returns its file name.
fn write_asset(dir: &Path, storage: Storage, doc: &Value, bin: &[u8]) -> &'static str {
    match storage {
        Storage::Glb => {
            std::fs::write(dir.join("car.glb"), glb(doc, bin)).unwrap();
            "car.glb"
        }
        Storage::ExternalBin | Storage::DataUris => {
            if let Storage::ExternalBin = storage {
                std::fs::write(dir.join("mesh data.bin"), bin).unwrap();
            }
            std::fs::write(
                dir.join("car.gltf"),
                serde_json::to_vec_pretty(doc).unwrap(),
            )
            .unwrap();
            "car.gltf"
        }
    }
}

const SHAPE_TRANSFORM: &str = r#"{ "translate": [10, 0, 0] }"#;

fn scene_with(file: &str, camera: &str) -> String {
    format!(
        r#"{{ "camera": {camera},
             "shapes": {{ "car": {{ "gltf": {{ "file": "{file}" }}, "transform": {SHAPE_TRANSFORM} }} }} }}"#
    )
}

fn check_asset(s: &Scene) {
    // One Mesh per (mesh, primitive), instanced by both nodes that use the mesh.
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.instances.len(), 4);
    let triangles: usize = s
        .instances
        .iter()
        .map(|i| s.meshes[i.mesh as usize].indices.len() / 3)
        .sum();
    assert_eq!(triangles, 6);
    let quad = &s.meshes[0];
    assert_eq!(quad.name, "car/thing/0");
    assert_eq!(quad.indices, [0, 1, 2, 0, 2, 3]);
    assert_eq!(quad.normals.as_ref().unwrap(), &vec![Vec3::Z; 4]);
    assert_eq!(quad.uvs.as_ref().unwrap()[1], Vec2::new(1.0, 1.0));
    assert!(quad.tangents.is_none());
    assert_eq!(s.meshes[1].positions.len(), 3);
    assert!(s.meshes[1].normals.is_none());

    // Composed transforms: shape × parent × child, and shape × copy.
    let shape = DMat4::from_translation(DVec3::new(10.0, 0.0, 0.0));
    let parent = DMat4::from_scale_rotation_translation(
        DVec3::splat(2.0),
        DQuat::from_rotation_y(FRAC_PI_2),
        DVec3::new(1.0, 2.0, 3.0),
    );
    let child = shape * parent * DMat4::from_translation(DVec3::Y);
    let copy = shape * DMat4::from_translation(DVec3::new(-4.0, 0.0, 0.0));
    let names: Vec<&str> = s.instances.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(names, ["car/child", "car/child", "car/copy", "car/copy"]);
    assert_eq!(
        s.instances.iter().map(|i| i.mesh).collect::<Vec<_>>(),
        [0, 1, 0, 1]
    );
    assert!(
        approx_mat(&s.instances[0].transform, &child, 1e-6),
        "{}",
        s.instances[0].transform
    );
    assert!(approx_mat(&s.instances[1].transform, &child, 1e-6));
    assert!(approx_mat(&s.instances[2].transform, &copy, 1e-12));

    // Material mapping: diffuse = base (1 - m), GGX alpha = r², f0 = mix(0.04, base, m).
    assert_eq!(s.materials.len(), 2);
    let paint = &s.materials[0];
    assert_eq!(paint.name, "car/paint");
    assert!(
        paint.diffuse.abs_diff_eq(Vec3::new(0.6, 0.15, 0.075), 1e-6),
        "{}",
        paint.diffuse
    );
    assert_eq!(paint.specular.len(), 1);
    let lobe = paint.specular[0];
    assert_eq!(lobe.distribution, Distribution::GgxSmith);
    assert_eq!(lobe.alpha, Vec2::splat(0.25));
    let Fresnel::Schlick { f0 } = lobe.fresnel else {
        panic!("{:?}", lobe.fresnel)
    };
    assert!(f0.abs_diff_eq(Vec3::new(0.23, 0.08, 0.055), 1e-6), "{f0}");
    assert_eq!(paint.emission, Vec3::new(4.0, 2.0, 1.0));
    assert!(paint.two_sided);
    assert_eq!(paint.diffuse_texture, Some(0));
    let default = &s.materials[1];
    assert_eq!(
        (default.name.as_str(), default.diffuse),
        ("car/default", Vec3::splat(0.5))
    );
    assert_eq!(s.meshes[1].material, 1);

    // The base colour texture, decoded from sRGB.
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width, t.height), (2, 1));
    assert_eq!(t.texels[0].x, 1.0);
    assert!((t.texels[0].y - 0.2158605).abs() < 1e-5);
}

#[test]
fn gltf_loads_from_data_uris_external_bin_and_glb() {
    for storage in [Storage::DataUris, Storage::ExternalBin, Storage::Glb] {
        let dir = temp_dir("gltf");
        let (doc, bin) = asset(storage);
        let file = write_asset(&dir, storage, &doc, &bin);
        let camera = r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 }"#;
        let s = from_json_str(&scene_with(file, camera), "cars.json", &dir).unwrap();
        check_asset(&s);
    }
}

#[test]
fn gltf_camera_form() {
    let dir = temp_dir("gltf-camera");
    let (doc, bin) = asset(Storage::Glb);
    write_asset(&dir, Storage::Glb, &doc, &bin);
    std::fs::write(
        dir.join("s.json"),
        scene_with("car.glb", r#"{ "gltf": "car", "resolution": [64, 32] }"#),
    )
    .unwrap();
    let s = load(&dir.join("s.json")).unwrap();
    let c = &s.camera;
    // cam node: shape × parent × T(0, 0, 5): position (10, 0, 0) + (1, 2, 3) + R_y(90°)·(0, 0, 10).
    assert!(
        c.position.abs_diff_eq(DVec3::new(21.0, 2.0, 3.0), 1e-5),
        "{}",
        c.position
    );
    let forward = c.look_at - c.position;
    assert!(forward.abs_diff_eq(DVec3::NEG_X, 1e-6), "{forward}");
    assert!(c.up.abs_diff_eq(DVec3::Y, 1e-6), "{}", c.up);
    assert!((c.fov_y_deg - 0.8f64.to_degrees()).abs() < 1e-5);
    assert_eq!((c.width, c.height), (64, 32));

    let err = |camera: &str| {
        let text = scene_with("car.glb", camera);
        from_json_str(&text, "s.json", &dir)
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        err(r#"{ "gltf": "car", "index": 1 }"#),
        "s.json: camera.index: out of range (shape \"car\" has 1 cameras), got 1"
    );
    assert_eq!(
        err(r#"{ "gltf": "truck" }"#),
        "s.json: camera.gltf: no such gltf shape (known: \"car\"), got \"truck\""
    );
    assert_eq!(
        err(r#"{ "gltf": "car", "fov_y": 30 }"#),
        "s.json: camera.fov_y: not allowed with camera.gltf (the glTF camera defines it)"
    );
}

#[test]
fn gltf_material_override() {
    let dir = temp_dir("gltf-override");
    let (doc, bin) = asset(Storage::Glb);
    write_asset(&dir, Storage::Glb, &doc, &bin);
    let text = r#"{ "camera": { "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 },
        "materials": { "chrome": { "specular": [{ "model": "ggx", "roughness": 0.1 }] } },
        "shapes": { "car": { "gltf": { "file": "car.glb" }, "material": "chrome" } } }"#;
    let s = from_json_str(text, "s.json", &dir).unwrap();
    assert_eq!(
        s.materials.len(),
        1,
        "glTF materials are not loaded when overridden"
    );
    assert!(s.textures.is_empty());
    assert!(s.meshes.iter().all(|m| m.material == 0));
}

/// Loads the asset after `edit`, as a .gltf, and returns the error message.
fn gltf_error(edit: impl FnOnce(&mut Value)) -> (String, String) {
    let dir = temp_dir("gltf-bad");
    let (mut doc, bin) = asset(Storage::DataUris);
    edit(&mut doc);
    write_asset(&dir, Storage::DataUris, &doc, &bin);
    let camera = r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 }"#;
    let msg = from_json_str(&scene_with("car.gltf", camera), "s.json", &dir)
        .unwrap_err()
        .to_string();
    (msg, dir.join("car.gltf").display().to_string())
}

#[test]
fn gltf_rejections() {
    let (msg, file) = gltf_error(|d| {
        d["extensionsRequired"] = json!([
            "KHR_materials_emissive_strength",
            "KHR_draco_mesh_compression"
        ])
    });
    assert_eq!(
        msg,
        format!(
            "{file}: extensionsRequired: unsupported required extension \
             \"KHR_draco_mesh_compression\" (illum supports: KHR_materials_emissive_strength)"
        )
    );
    let (msg, file) = gltf_error(|d| d["extensionsRequired"] = json!(["KHR_texture_transform"]));
    assert!(
        msg.starts_with(&format!(
            "{file}: extensionsRequired: unsupported required extension \"KHR_texture_transform\""
        )),
        "{msg}"
    );

    let (msg, file) = gltf_error(|d| d["meshes"][0]["primitives"][1]["mode"] = json!(1));
    assert_eq!(
        msg,
        format!("{file}: meshes[0].primitives[1].mode: only TRIANGLES is supported, got LINES")
    );

    let (msg, file) = gltf_error(|d| d["accessors"][5]["componentType"] = json!(5126));
    assert_eq!(
        msg,
        format!(
            "{file}: meshes[0].primitives[1].indices (accessors[5]): must be UNSIGNED_BYTE, \
             UNSIGNED_SHORT or UNSIGNED_INT SCALAR, got FLOAT SCALAR"
        )
    );
    let (msg, file) = gltf_error(|d| d["accessors"][4]["count"] = json!(1000));
    assert!(msg.starts_with(&format!("{file}: meshes[0].primitives[1].attributes.POSITION (accessors[4]): data runs past the end of bufferViews[4]")), "{msg}");

    let (msg, file) = gltf_error(|d| d["accessors"][2]["count"] = json!(3));
    assert!(msg.starts_with(&format!("{file}: meshes[0].primitives[0].attributes.TEXCOORD_0 (accessors[2]): must have as many elements as POSITION (4), got count 3")), "{msg}");

    let (msg, file) =
        gltf_error(|d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(17));
    assert_eq!(
        msg,
        format!(
            "{file}: meshes[0].primitives[0].attributes.POSITION: accessor index out of range (6 accessors), got 17"
        )
    );
    let (msg, file) =
        gltf_error(|d| d["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(17));
    assert!(
        msg.starts_with(&format!(
            "{file}: meshes[0].primitives[0].attributes[\"NORMAL\"]: invalid glTF"
        )),
        "{msg}"
    );
    let (msg, file) = gltf_error(|d| d["images"][0] = json!({ "bufferView": 0 }));
    assert_eq!(
        msg,
        format!("{file}: images[0]: an image in a bufferView needs a mimeType")
    );
    let (msg, file) = gltf_error(|d| d["images"][0] = json!({}));
    assert_eq!(
        msg,
        format!("{file}: images[0]: needs exactly one of uri and bufferView")
    );
    let (msg, file) = gltf_error(|d| d["cameras"][0]["type"] = json!("orthographic"));
    assert_eq!(
        msg,
        format!("{file}: cameras[0]: the object named by \"type\" is missing")
    );

    let (msg, file) = gltf_error(|d| d["nodes"][1]["children"] = json!([0]));
    assert_eq!(
        msg,
        format!("{file}: nodes[1].children: the node hierarchy has a cycle (back to nodes[0])")
    );

    let (msg, file) = gltf_error(|d| d["buffers"][0]["uri"] = json!("missing.bin"));
    assert_eq!(
        msg,
        format!("{file}: buffers[0].uri: cannot read \"missing.bin\": No such file or directory")
    );

    let (msg, file) = gltf_error(|d| {
        d["nodes"][3]["matrix"] = json!([0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
    });
    assert_eq!(
        msg,
        format!(
            "{file}: nodes[3] (world transform): must be invertible (no zero scale or collapsed axes), got determinant 0"
        )
    );

    let (msg, file) = gltf_error(|d| d["meshes"][0]["primitives"][1]["indices"] = json!(1));
    assert!(
        msg.starts_with(&format!(
            "{file}: meshes[0].primitives[1].indices (accessors[1]): must be"
        )),
        "{msg}"
    );

    let (msg, file) = gltf_error(|d| d["asset"]["version"] = json!(2));
    assert!(
        msg.starts_with(&format!("{file}: line ")) && msg.contains("asset.version"),
        "{msg}"
    );
}

/// Every leaf of the asset's JSON replaced by odd values, and bytes of the binary chunk
/// corrupted: loading may fail, but must never panic.
#[test]
fn gltf_mutations_never_panic() {
    fn leaves(v: &Value, path: &mut Vec<Value>, out: &mut Vec<Vec<Value>>) {
        match v {
            Value::Object(m) => m.iter().for_each(|(k, c)| {
                path.push(json!(k));
                leaves(c, path, out);
                path.pop();
            }),
            Value::Array(a) => a.iter().enumerate().for_each(|(i, c)| {
                path.push(json!(i));
                leaves(c, path, out);
                path.pop();
            }),
            _ => {}
        }
        out.push(path.clone());
    }
    fn at<'a>(v: &'a mut Value, path: &[Value]) -> &'a mut Value {
        path.iter().fold(v, |v, k| match k {
            Value::String(k) => &mut v[k.as_str()],
            k => &mut v[k.as_u64().unwrap() as usize],
        })
    }
    let dir = temp_dir("gltf-mutations");
    let (doc, bin) = asset(Storage::Glb);
    let mut paths = Vec::new();
    leaves(&doc, &mut Vec::new(), &mut paths);
    let scene = scene_with("car.glb", r#"{ "gltf": "car" }"#);
    let replacements = [
        json!(0),
        json!(-1),
        json!(3),
        json!(1e10),
        json!(0.5),
        json!("x"),
        json!({}),
        json!([]),
    ];
    let mut tried = 0;
    let mut attempt = |doc: &Value, bin: &[u8]| {
        std::fs::write(dir.join("car.glb"), glb(doc, bin)).unwrap();
        let r = std::panic::catch_unwind(|| from_json_str(&scene, "s.json", &dir));
        assert!(
            r.is_ok(),
            "panicked on {}",
            serde_json::to_string(doc).unwrap()
        );
        tried += 1;
    };
    for path in &paths {
        for r in &replacements {
            let mut d = doc.clone();
            *at(&mut d, path) = r.clone();
            attempt(&d, &bin);
        }
    }
    // Corrupt 4-byte words of the binary chunk (floats become NaN / huge, indices out of range).
    for i in (0..bin.len()).step_by(4) {
        for word in [u32::MAX, 0x7fc0_0000, 0x0000_ffff] {
            let mut b = bin.clone();
            b[i..i + 4].copy_from_slice(&word.to_le_bytes());
            attempt(&doc, &b);
        }
    }
    assert!(tried > 1000, "{tried}");
}

#[test]
fn truncated_glb_is_an_error() {
    let dir = temp_dir("glb-truncated");
    let camera = r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 }"#;
    for bytes in [
        &b"glTF"[..],
        b"glTF\x02\0\0\0\x04\0\0\0",
        b"glTF\x02\0\0\0\xff\0\0\0JSON",
    ] {
        std::fs::write(dir.join("car.glb"), bytes).unwrap();
        let msg = from_json_str(&scene_with("car.glb", camera), "s.json", &dir)
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("s.json: shapes.car.gltf.file: cannot decode \"car.glb\": invalid GLB"),
            "{msg}"
        );
    }
}

/// A sparse POSITION accessor (moves vertex 2 of the triangle) and normalized UNSIGNED_SHORT
/// texture coordinates, added to the GLB asset.
#[test]
fn gltf_sparse_and_normalized_accessors() {
    let (mut doc, data) = asset(Storage::Glb);
    let mut bin = Bin {
        data,
        views: serde_json::from_value(doc["bufferViews"].clone()).unwrap(),
    };
    let idx_view = bin.u16s(&[2]);
    let val_view = bin.f32s(&[0.0, 2.0, 0.0]);
    let uv_view = bin.u16s(&[0, 65535, 65535, 65535, 65535, 0, 0, 32768]);
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    doc["accessors"][4]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": idx_view, "componentType": 5123 },
        "values": { "bufferView": val_view }
    });
    doc["accessors"][4]["max"] = json!([1.0, 2.0, 0.0]);
    doc["accessors"][2] = json!({ "bufferView": uv_view, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC2" });
    doc["bufferViews"] = json!(bin.views);
    doc["buffers"][0]["byteLength"] = json!(bin.data.len());

    let dir = temp_dir("gltf-sparse");
    write_asset(&dir, Storage::Glb, &doc, &bin.data);
    let camera = r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40 }"#;
    let s = from_json_str(&scene_with("car.glb", camera), "s.json", &dir).unwrap();
    assert_eq!(
        s.meshes[1].positions,
        [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)]
    );
    let uvs = s.meshes[0].uvs.as_ref().unwrap();
    assert_eq!(uvs[0], Vec2::new(0.0, 1.0));
    assert!((uvs[3].y - 32768.0 / 65535.0).abs() < 1e-6, "{}", uvs[3]);
}
