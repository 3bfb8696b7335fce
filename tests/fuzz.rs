//! A bounded byte-mutation fuzzer over every loader that reads untrusted files: scene JSON,
//! glTF (text with a data: buffer, and binary .glb), and the partial EXRs that `illum merge`
//! reads. Each mutated input must load or fail with an error: no panic, and no input may take
//! longer than a few seconds (a hang). Inputs that once found a defect are kept in
//! `tests/fuzz/` and replayed first.
//!
//! The budget is `ILLUM_FUZZ_SECONDS` per target (default 4; CI runs the default), and the
//! mutations are deterministic for a given `ILLUM_FUZZ_SEED` (default 1), so a failure names the
//! seed and iteration that reproduce it.

mod common;
use base64::Engine;
use common::Rng;
use illum::film::{FilmSums, Window};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::{Duration, Instant};

/// One to four mutations of `seed`: bit flips, bytes set to values parsers care about, numbers
/// spliced in, ranges deleted, duplicated or truncated.
fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    const SPECIAL: &[u8] = b"\0\xff\"{}[]:,-.0123456789eE+\\/\n";
    const NUMBERS: &[&str] = &[
        "1e39",
        "-1",
        "0",
        "4294967296",
        "1e308",
        "NaN",
        "-0",
        "65535",
        "2147483648",
        "1e-45",
    ];
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        if v.is_empty() {
            v.push(b'{');
        }
        let at = rng.below(v.len());
        match rng.below(7) {
            0 => v[at] ^= 1 << rng.below(8),
            1 => v[at] = SPECIAL[rng.below(SPECIAL.len())],
            2 => {
                let n = NUMBERS[rng.below(NUMBERS.len())];
                v.splice(at..at, n.bytes());
            }
            3 => {
                let end = (at + 1 + rng.below(16)).min(v.len());
                v.drain(at..end);
            }
            4 => {
                let end = (at + 1 + rng.below(64)).min(v.len());
                let piece = v[at..end].to_vec();
                v.splice(at..at, piece);
            }
            5 => v.truncate(at),
            _ => {
                // A little-endian integer field of a binary format, set to an extreme.
                let x = [0u32, 1, 0x7fff_ffff, 0xffff_ffff][rng.below(4)].to_le_bytes();
                for (k, b) in x.iter().enumerate() {
                    if at + k < v.len() {
                        v[at + k] = *b;
                    }
                }
            }
        }
    }
    v
}

fn budget() -> Duration {
    let s = std::env::var("ILLUM_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .unwrap_or(4.0);
    Duration::from_secs_f64(s)
}

fn fuzz_seed() -> u64 {
    std::env::var("ILLUM_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// Runs `load` on the kept regression inputs of `name`, then on mutations of `seeds` until the
/// budget is spent. Returns (inputs tried, inputs that loaded).
fn fuzz(name: &str, seeds: &[Vec<u8>], load: &dyn Fn(&[u8]) -> bool) -> (usize, usize) {
    let kept = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz")
        .join(name);
    let mut regressions: Vec<Vec<u8>> = std::fs::read_dir(&kept)
        .map(|d| {
            d.flatten()
                .map(|e| std::fs::read(e.path()).unwrap())
                .collect()
        })
        .unwrap_or_default();
    regressions.extend(seeds.iter().cloned());
    let mut rng = Rng::new(fuzz_seed());
    let (start, budget) = (Instant::now(), budget());
    let (mut tried, mut loaded) = (0, 0);
    // `what` names the input only when it fails: no string is built per input.
    let mut check = |input: &[u8], what: &dyn Fn() -> String| {
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| load(input)));
        let took = t.elapsed();
        match r {
            Ok(ok) => loaded += usize::from(ok),
            Err(_) => {
                let path = common::temp_path(&format!("fuzz-{name}-panic"));
                std::fs::write(&path, input).unwrap();
                panic!(
                    "{name}: {} panicked; input kept in {}",
                    what(),
                    path.display()
                );
            }
        }
        assert!(
            took < Duration::from_secs(5),
            "{name}: {} took {took:?} (a hang?)",
            what()
        );
        tried += 1;
    };
    for (k, r) in regressions.iter().enumerate() {
        check(r, &|| format!("kept input {k}"));
    }
    let mut i = 0u64;
    while start.elapsed() < budget {
        let seed = &seeds[rng.below(seeds.len())];
        let input = mutate(&mut rng, seed);
        check(&input, &|| format!("seed {} iteration {i}", fuzz_seed()));
        i += 1;
    }
    eprintln!(
        "fuzz {name}: {tried} inputs in {:.1?}, {loaded} loaded",
        start.elapsed()
    );
    (tried, loaded)
}

fn scene_seeds() -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut v: Vec<Vec<u8>> = [
        "scenes/default.json",
        "scenes/veach.json",
        "scenes/interior.json",
    ]
    .iter()
    .map(|p| std::fs::read(root.join(p)).unwrap())
    .collect();
    v.push(common::SMALL_SCENE.as_bytes().to_vec());
    v
}

#[test]
fn scene_json_never_panics() {
    let dir = std::env::temp_dir();
    let (tried, loaded) = fuzz("scene", &scene_seeds(), &|bytes| {
        let text = String::from_utf8_lossy(bytes);
        illum::scene::from_json_str(&text, "fuzz.json", &dir).is_ok()
    });
    assert!(tried > 100, "only {tried} inputs");
    // The seeds themselves load: the harness reaches the loader's checks, not only the parser.
    assert!(loaded >= scene_seeds().len(), "{loaded}");
}

/// A one-triangle glTF with its buffer in a data: URI, and the same as a .glb.
fn gltf_seeds() -> (Vec<u8>, Vec<u8>) {
    let mut bin = Vec::new();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let doc = |uri: Option<String>| {
        let buffer = match uri {
            Some(u) => format!(r#"{{"byteLength": {}, "uri": "{u}"}}"#, bin.len()),
            None => format!(r#"{{"byteLength": {}}}"#, bin.len()),
        };
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "translation": [0, 0.5, 0]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.2, 0.1, 1], "roughnessFactor": 0.4}}}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
  "buffers": [{buffer}]}}"#
        )
    };
    let text = doc(Some(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    )));
    let mut json = doc(None).into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut glb = Vec::new();
    let total = 12 + 8 + json.len() + 8 + bin.len();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    (text.into_bytes(), glb)
}

#[test]
fn gltf_never_panics() {
    let dir = common::temp_path("fuzz-gltf");
    std::fs::create_dir_all(&dir).unwrap();
    let (text, glb) = gltf_seeds();
    for (name, ext, seed) in [("gltf", "gltf", text), ("glb", "glb", glb)] {
        let asset = dir.join(format!("asset.{ext}"));
        let scene = format!(
            r#"{{"camera": {{"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_y": 40}},
                "shapes": {{"m": {{"gltf": {{"file": "asset.{ext}"}}}}}},
                "lights": {{"sky": {{"dome": {{}}}}}}}}"#
        );
        let (tried, loaded) = fuzz(name, std::slice::from_ref(&seed), &|bytes| {
            std::fs::write(&asset, bytes).unwrap();
            illum::scene::from_json_str(&scene, "fuzz.json", &dir).is_ok()
        });
        assert!(
            tried > 50 && loaded >= 1,
            "{name}: {tried} tried, {loaded} loaded"
        );
    }
}

#[test]
fn partial_exr_never_panics() {
    let dir = common::temp_path("fuzz-partial");
    std::fs::create_dir_all(&dir).unwrap();
    let window = Window {
        x0: 1,
        y0: 2,
        x1: 4,
        y1: 4,
    };
    let mut sums = FilmSums::new(window, vec!["Direct".into()]);
    for (k, s) in sums.sums.iter_mut().enumerate() {
        *s = (k as i128 * 0x1234_5678_9abc) << 20;
    }
    let info = illum::jobs::partial::PartInfo {
        samples: (0, 256),
        window,
        frame: (6, 5),
        spp: 512,
        seed: 3,
        witness: illum::film::Split::of_image(1024, 1024, 3).word(),
        scene_hash: "00ff".into(),
        settings: "integrator=full".into(),
        trace: "bvh".into(),
        version: "fuzz".into(),
        device: "none".into(),
        render_seconds: 1.0,
        setup_seconds: 0.5,
        aov_planes: vec!["Direct".into()],
    };
    let good = dir.join("good.exr");
    illum::jobs::partial::write_partial(&good, &info, &sums).unwrap();
    let (back_info, back) = illum::jobs::partial::read_partial(&good).unwrap();
    assert_eq!((back_info, back.sums), (info, sums.sums));
    // OpenEXR's windows: the data window is the crop in frame pixels, the display window the
    // frame (a crop was stored at (0, 0) with its place only in illum.crop).
    let meta = exr::meta::MetaData::read_from_file(&good, false).unwrap();
    let header = &meta.headers[0];
    assert_eq!(header.own_attributes.layer_position, exr::math::Vec2(1, 2));
    assert_eq!(header.layer_size, exr::math::Vec2(3, 2));
    assert_eq!(
        header.shared_attributes.display_window.size,
        exr::math::Vec2(6, 5)
    );
    let seed = std::fs::read(&good).unwrap();
    // A data window of 10^12 pixels: refused from the header, not allocated (the reader asked
    // for 240 GB and aborted the process).
    let tag = b"dataWindow\0box2i\0";
    let at = seed
        .windows(tag.len())
        .position(|w| w == tag)
        .expect("a data window")
        + tag.len()
        + 4;
    let mut huge = seed.clone();
    huge[at + 8..at + 16].copy_from_slice(
        &[
            &1_000_000i32.to_le_bytes()[..],
            &1_000_000i32.to_le_bytes()[..],
        ]
        .concat(),
    );
    let huge_path = dir.join("huge.exr");
    std::fs::write(&huge_path, &huge).unwrap();
    let e = illum::jobs::partial::read_partial(&huge_path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("huge.exr") && e.contains("declares"), "{e}");
    let input = dir.join("mutated.exr");
    let (tried, loaded) = fuzz("partial", &[seed], &|bytes| {
        std::fs::write(&input, bytes).unwrap();
        illum::jobs::partial::read_partial(&input).is_ok()
    });
    assert!(tried > 50 && loaded >= 1, "{tried} tried, {loaded} loaded");
}
