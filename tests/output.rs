//! Round trips of src/output: EXR planes and attributes, beauty lookup, PNG encoding, errors.

mod common;

use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};

use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, Image, WritableImage};
use illum::output::{ExrImage, Film, ImageMetadata, read_exr, write_exr, write_png};

/// A fresh path in the process's scratch folder, removed on drop.
struct TempFile(PathBuf);

impl TempFile {
    fn new(tag: &str, ext: &str) -> TempFile {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        TempFile(common::scratch_root().join(format!("output-{n}-{tag}.{ext}")))
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

const W: u32 = 7;
const H: u32 = 5;

/// Distinct values per plane and pixel, plus edge cases that must survive bit-exactly.
fn film(with_variance: bool) -> Film {
    let mut film = Film::new(W, H);
    for i in 0..(W * H) as usize {
        let f = i as f32;
        film.beauty[i] = [f + 0.25, 100.0 + f, 1.0e4 * f];
        film.albedo[i] = [0.01 * f, 0.02 * f, 0.03 * f];
        film.normal[i] = [(f * 0.1).sin(), (f * 0.1).cos(), -0.5];
        film.depth[i] = 3.0 + f * 0.125;
        film.emission[i] = [f * 7.0, 0.0, 1.0 / (1.0 + f)];
    }
    film.depth[3] = f32::INFINITY;
    film.beauty[4] = [-0.0, f32::MIN_POSITIVE / 4.0, f32::MAX];
    film.emission[6] = [f32::from_bits(0x7fc0_1234), 0.0, 0.0]; // NaN payload
    if with_variance {
        film.variance = Some(
            (0..(W * H) as usize)
                .map(|i| [i as f32 * 1e-3, i as f32 * 2e-3, i as f32 * 3e-3])
                .collect(),
        );
    }
    film
}

fn meta() -> ImageMetadata {
    ImageMetadata {
        spp: 64,
        render_seconds: 12.5,
        setup_seconds: 3.25,
        device: "NVIDIA Test GPU (ünïcode)".into(),
        seed: u64::MAX - 1,
        extra: vec![
            ("illum.technique".into(), "mis".into()),
            ("illum.scene".into(), "scenes/cornell.json".into()),
        ],
    }
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn assert_plane(img: &ExrImage, names: [&str; 3], plane: &[[f32; 3]]) {
    for (c, name) in names.into_iter().enumerate() {
        let expected: Vec<f32> = plane.iter().map(|p| p[c]).collect();
        let got = img
            .channel(name)
            .unwrap_or_else(|| panic!("missing channel {name}"));
        assert_eq!(bits(got), bits(&expected), "channel {name}");
    }
}

fn attr<'a>(img: &'a ExrImage, name: &str) -> &'a str {
    img.attributes
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v.as_str())
        .unwrap_or_else(|| panic!("missing attribute {name}: {:?}", img.attributes))
}

#[test]
fn exr_round_trip_with_variance() {
    let film = film(true);
    let file = TempFile::new("var", "exr");
    write_exr(&file.0, &film, &meta()).unwrap();
    let img = read_exr(&file.0).unwrap();

    assert_eq!((img.width, img.height), (W, H));
    assert_eq!(img.path, file.0);
    let mut names: Vec<&str> = img.channels.iter().map(|(n, _)| n.as_str()).collect();
    names.sort_unstable();
    let mut expected = common::EXR_CHANNELS.to_vec();
    expected.sort_unstable();
    assert_eq!(names, expected);
    assert!(
        img.channels
            .iter()
            .all(|(_, v)| v.len() == (W * H) as usize)
    );

    assert_plane(&img, ["R", "G", "B"], &film.beauty);
    assert_plane(&img, ["Albedo.R", "Albedo.G", "Albedo.B"], &film.albedo);
    assert_plane(&img, ["N.X", "N.Y", "N.Z"], &film.normal);
    assert_plane(
        &img,
        ["Emission.R", "Emission.G", "Emission.B"],
        &film.emission,
    );
    let variance = film.variance.as_ref().unwrap();
    assert_plane(&img, ["Variance.R", "Variance.G", "Variance.B"], variance);
    assert_eq!(bits(img.channel("Z").unwrap()), bits(&film.depth));
    assert_eq!(img.channel("Z").unwrap()[3], f32::INFINITY);

    let rgb = img.rgb().unwrap();
    let flat = |v: &[[f32; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(flat(&rgb), flat(&film.beauty));

    assert_eq!(attr(&img, "illum.spp"), "64");
    assert_eq!(attr(&img, "illum.renderSeconds"), "12.5");
    assert_eq!(attr(&img, "illum.setupSeconds"), "3.25");
    assert_eq!(attr(&img, "illum.device"), "NVIDIA Test GPU (ünïcode)");
    assert_eq!(attr(&img, "illum.seed"), (u64::MAX - 1).to_string());
    assert_eq!(attr(&img, "illum.technique"), "mis");
    assert_eq!(attr(&img, "illum.scene"), "scenes/cornell.json");
    assert_eq!(
        attr(&img, "software"),
        format!("illum {}", env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(img.attribute("illum.spp"), Some("64"));
    assert!(attr(&img, "compression").contains("ZIP"));

    // Typed where natural: check with the exr crate's own reader.
    let meta = exr::meta::MetaData::read_from_file(&file.0, true).unwrap();
    assert_eq!(meta.headers.len(), 1, "one part");
    let other = &meta.headers[0].own_attributes.other;
    let get = |n: &str| other.get(&exr::prelude::Text::from(n)).cloned();
    assert_eq!(
        get("illum.spp"),
        Some(exr::prelude::AttributeValue::I32(64))
    );
    assert_eq!(
        get("illum.renderSeconds"),
        Some(exr::prelude::AttributeValue::F64(12.5))
    );
    assert!(
        meta.headers[0]
            .channels
            .list
            .iter()
            .all(|c| c.sample_type == exr::prelude::SampleType::F32)
    );
}

#[test]
fn exr_round_trip_without_variance() {
    let film = film(false);
    let file = TempFile::new("novar", "exr");
    write_exr(&file.0, &film, &ImageMetadata::default()).unwrap();
    let img = read_exr(&file.0).unwrap();
    assert_eq!(img.channels.len(), 13);
    assert!(img.channels.iter().all(|(n, _)| !n.starts_with("Variance")));
    assert_plane(&img, ["R", "G", "B"], &film.beauty);
    assert_eq!(bits(img.channel("Z").unwrap()), bits(&film.depth));
    assert_eq!(attr(&img, "illum.seed"), "0");
    assert_eq!(attr(&img, "illum.device"), "");
}

#[test]
fn exr_larger_than_one_block() {
    // Several ZIP blocks of 16 lines, a partial last block, and a non-square width.
    let mut film = Film::new(131, 37);
    for (i, p) in film.beauty.iter_mut().enumerate() {
        *p = [i as f32, -(i as f32), 0.5 * i as f32];
    }
    film.depth
        .iter_mut()
        .enumerate()
        .for_each(|(i, d)| *d = i as f32 * 0.25);
    let file = TempFile::new("big", "exr");
    write_exr(&file.0, &film, &meta()).unwrap();
    let img = read_exr(&file.0).unwrap();
    assert_eq!((img.width, img.height), (131, 37));
    assert_plane(&img, ["R", "G", "B"], &film.beauty);
    assert_eq!(bits(img.channel("Z").unwrap()), bits(&film.depth));
}

fn write_foreign(path: &PathBuf, names: &[&str]) -> Vec<Vec<f32>> {
    let n = (W * H) as usize;
    let data: Vec<Vec<f32>> = (0..names.len())
        .map(|c| (0..n).map(|i| (c * 1000 + i) as f32).collect())
        .collect();
    let channels = names
        .iter()
        .zip(&data)
        .map(|(name, v)| AnyChannel::new(*name, FlatSamples::F32(v.clone())))
        .collect();
    let image = Image::from_channels((W as usize, H as usize), AnyChannels::sort(channels));
    image.write().to_file(path).unwrap();
    data
}

#[test]
fn rgb_finds_foreign_beauty_layer() {
    let file = TempFile::new("foreign", "exr");
    // "albedo" sorts before "beauty" but is not a beauty layer.
    let names = [
        "albedo.R", "albedo.G", "albedo.B", "beauty.R", "beauty.G", "beauty.B",
    ];
    let data = write_foreign(&file.0, &names);
    let rgb = read_exr(&file.0).unwrap().rgb().unwrap();
    assert_eq!(rgb[0], [data[3][0], data[4][0], data[5][0]]);
    assert_eq!(rgb[9], [data[3][9], data[4][9], data[5][9]]);

    let file = TempFile::new("default", "exr");
    let data = write_foreign(
        &file.0,
        &["default.R", "default.G", "default.B", "default.A"],
    );
    let rgb = read_exr(&file.0).unwrap().rgb().unwrap();
    assert_eq!(rgb[2], [data[0][2], data[1][2], data[2][2]]);

    // No beauty-like name: the first layer with R/G/B.
    let file = TempFile::new("first", "exr");
    let data = write_foreign(&file.0, &["diffuse.R", "diffuse.G", "diffuse.B", "x.Y"]);
    let rgb = read_exr(&file.0).unwrap().rgb().unwrap();
    assert_eq!(rgb[1], [data[0][1], data[1][1], data[2][1]]);
}

#[test]
fn rgb_error_names_file_and_channels() {
    let file = TempFile::new("nobeauty", "exr");
    write_foreign(&file.0, &["Y", "depth.Z", "beauty.R", "beauty.G"]);
    let err = read_exr(&file.0).unwrap().rgb().unwrap_err().to_string();
    assert!(err.contains(&file.0.display().to_string()), "{err}");
    for name in ["Y", "depth.Z", "beauty.R", "beauty.G"] {
        assert!(err.contains(name), "{err}");
    }
}

#[test]
fn multi_part_channels_get_part_prefix() {
    use exr::prelude::{Encoding, Layer, LayerAttributes, Text};
    let n = (W * H) as usize;
    let part = |name: &str, channels: &[&str], base: f32| {
        let list = channels
            .iter()
            .enumerate()
            .map(|(c, ch)| {
                let v = (0..n).map(|i| base + (c * 100 + i) as f32).collect();
                AnyChannel::new(*ch, FlatSamples::F32(v))
            })
            .collect();
        let attributes = LayerAttributes::named(Text::from(name));
        Layer::new(
            (W as usize, H as usize),
            attributes,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(list),
        )
    };
    let image = Image::from_layers(
        exr::prelude::ImageAttributes::new(exr::prelude::IntegerBounds::from_dimensions((
            W as usize, H as usize,
        ))),
        vec![
            part("normal", &["X", "Y", "Z"], 0.0),
            part("beauty", &["R", "G", "B"], 5000.0),
        ],
    );
    let file = TempFile::new("multipart", "exr");
    image.write().to_file(&file.0).unwrap();
    let img = read_exr(&file.0).unwrap();
    assert!(img.channel("normal.X").is_some() && img.channel("beauty.B").is_some());
    let rgb = img.rgb().unwrap();
    assert_eq!(rgb[0], [5000.0, 5100.0, 5200.0]);
}

fn srgb_reference(v: f32) -> u8 {
    if !v.is_finite() {
        return 0;
    }
    let v = f64::from(v).clamp(0.0, 1.0);
    let e = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0).round() as u8
}

#[test]
fn png_encodes_exact_srgb_bytes() {
    let values: Vec<(f32, u8)> = vec![
        (0.0, 0),
        (1.0, 255),
        (0.5, 188),
        (0.18, 118),
        (0.0031308, 10), // boundary of the linear segment
        (0.0031307, 10), // just below
        (0.0031309, 10), // just above
        (0.001, 3),      // linear segment: 12.92 * 0.001 * 255 = 3.29
        (0.0002, 1),     // 0.66 -> 1
        (0.0001, 0),     // 0.33 -> 0
        (1.5, 255),      // clamped
        (1e30, 255),
        (-0.25, 0),
        (f32::NAN, 0),
        (f32::INFINITY, 0),
        (f32::NEG_INFINITY, 0),
        (0.2140, 127), // around mid-grey byte
        (0.2159, 128),
        (0.9911, 254),
    ];
    for &(v, b) in &values {
        assert_eq!(srgb_reference(v), b, "reference for {v}");
    }
    // One pixel per value triple; pad with a dense sweep to exercise many bytes.
    let mut samples: Vec<f32> = values.iter().map(|&(v, _)| v).collect();
    samples.extend((0..=1000).map(|i| i as f32 / 1000.0));
    while samples.len() % 3 != 0 {
        samples.push(0.75);
    }
    let pixels = samples.len() / 3;
    let mut film = Film::new(pixels as u32, 1);
    for (p, c) in film.beauty.iter_mut().zip(samples.chunks_exact(3)) {
        *p = [c[0], c[1], c[2]];
    }
    let file = TempFile::new("srgb", "png");
    write_png(&file.0, &film).unwrap();

    let img = image::open(&file.0).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    let bytes = img.into_rgb8().into_raw();
    let expected: Vec<u8> = samples.iter().map(|&v| srgb_reference(v)).collect();
    assert_eq!(bytes, expected);
    assert_eq!(
        &bytes[..values.len()],
        values.iter().map(|v| v.1).collect::<Vec<_>>()
    );
}

#[test]
fn png_keeps_row_order() {
    let mut film = Film::new(2, 3);
    for (i, p) in film.beauty.iter_mut().enumerate() {
        *p = [i as f32 / 5.0, 0.0, 1.0];
    }
    let file = TempFile::new("rows", "png");
    write_png(&file.0, &film).unwrap();
    let img = image::open(&file.0).unwrap().into_rgb8();
    assert_eq!(img.dimensions(), (2, 3));
    for y in 0..3 {
        for x in 0..2 {
            let v = (y * 2 + x) as f32 / 5.0;
            assert_eq!(img.get_pixel(x, y).0, [srgb_reference(v), 0, 255]);
        }
    }
}

#[test]
fn errors_name_the_file() {
    let dir = common::scratch_root().join("missing-dir");
    let exr_path = dir.join("out.exr");
    let png_path = dir.join("out.png");
    let film = film(true);
    let contains_path = |msg: String, path: &PathBuf| {
        assert!(msg.contains(&path.display().to_string()), "{msg}");
    };

    contains_path(
        write_exr(&exr_path, &film, &meta())
            .unwrap_err()
            .to_string(),
        &exr_path,
    );
    contains_path(
        write_png(&png_path, &film).unwrap_err().to_string(),
        &png_path,
    );
    contains_path(read_exr(&exr_path).unwrap_err().to_string(), &exr_path);

    let text = TempFile::new("notexr", "exr");
    std::fs::write(&text.0, b"this is not an OpenEXR file, just some text\n").unwrap();
    contains_path(read_exr(&text.0).unwrap_err().to_string(), &text.0);

    let empty = TempFile::new("empty", "exr");
    std::fs::write(&empty.0, b"").unwrap();
    contains_path(read_exr(&empty.0).unwrap_err().to_string(), &empty.0);

    let mut bad = film.clone();
    bad.albedo.pop();
    let target = TempFile::new("badplane", "exr");
    let msg = write_exr(&target.0, &bad, &meta()).unwrap_err().to_string();
    assert!(msg.contains("albedo"), "{msg}");
    contains_path(msg, &target.0);
    contains_path(
        write_png(&target.0, &Film::new(0, 3))
            .unwrap_err()
            .to_string(),
        &target.0,
    );

    let mut reserved = meta();
    reserved.extra.push(("software".into(), "other".into()));
    let msg = write_exr(&target.0, &film, &reserved)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("software"), "{msg}");
    contains_path(msg, &target.0);
    assert!(!target.0.exists());
}
