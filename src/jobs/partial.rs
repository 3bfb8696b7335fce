//! Partial EXRs: one job of a split render (a sample range and/or a pixel window), holding its
//! exact film sums so that `illum merge` can rebuild the image bit for bit (src/film/mod.rs).
//!
//! The data window is the job's pixel window. Channels (all sorted by name, as EXR wants):
//! - `sum.<plane>.w0` … `w3`: the job's fixed-point sums (i128; units in src/film/mod.rs) of each
//!   film channel ([`channel_names`]: the 24 of [`PLANES`], then `<Name>.r`, `.g`, `.b`, `.unused`
//!   for each AOV plane the integrator declares), as four little-endian 32-bit words (UINT
//!   channels, w0 lowest);
//! - `block<k>.<plane>` (k = 0, 1): float32 sums of a whole film block that the job owns only
//!   partly, with its sample range in the header attribute `illum.block<k>` = "start..end".
//!
//! Header attributes (text): `illum.partial` = "1", `illum.samples` = "A..B", `illum.crop` =
//! "x0,y0,x1,y1", `illum.frame` = "WxH", `illum.spp` (of the whole image), `illum.seed`,
//! `illum.sceneHash`, `illum.settings`, `illum.trace`, `illum.version`, `illum.device`,
//! `illum.renderSeconds`, `illum.setupSeconds`, and `illum.aovPlanes` = the AOV planes' names,
//! comma-separated, in channel order (absent when the integrator declares none).

use crate::film::{self, BoundaryBlock, FILM_CHANNELS, FilmSums, Window};
use crate::output::OutputError;
use exr::prelude::*;
use std::path::Path;

/// Names of the 24 film channels (FilmPixel, glsl/shared/layout.glsl), in order.
pub const PLANES: [&str; FILM_CHANNELS] = [
    "beauty.r",
    "beauty.g",
    "beauty.b",
    "clamped",
    "beauty_sq.r",
    "beauty_sq.g",
    "beauty_sq.b",
    "rays",
    "albedo.r",
    "albedo.g",
    "albedo.b",
    "hits",
    "normal.x",
    "normal.y",
    "normal.z",
    "depth",
    "emission.r",
    "emission.g",
    "emission.b",
    "non_finite",
    "odd.r",
    "odd.g",
    "odd.b",
    "odd.unused",
];

/// Suffixes of an AOV plane's four channels (its vec4 on the device; the fourth is unused).
pub const AOV_COMPONENTS: [&str; film::AOV_CHANNELS] = ["r", "g", "b", "unused"];

/// Names of every film channel of a film with the AOV planes `aov_planes`, in order: [`PLANES`],
/// then `<Name>.r`, `<Name>.g`, `<Name>.b`, `<Name>.unused` per plane.
pub fn channel_names<S: AsRef<str>>(aov_planes: &[S]) -> Vec<String> {
    let mut names: Vec<String> = PLANES.iter().map(|p| p.to_string()).collect();
    for plane in aov_planes {
        for c in AOV_COMPONENTS {
            names.push(format!("{}.{c}", plane.as_ref()));
        }
    }
    names
}

/// Header attribute naming the AOV planes.
const AOV_PLANES: &str = "illum.aovPlanes";

/// What a partial EXR says about its job, besides the sums.
#[derive(Clone, Debug, PartialEq)]
pub struct PartInfo {
    pub samples: (u32, u32),
    pub window: Window,
    pub frame: (u32, u32),
    pub spp: u32,
    pub seed: u64,
    /// Hash of the validated scene (src/scene: `Scene::content_hash`), hex.
    pub scene_hash: String,
    /// Every setting that changes the samples (integrator, clamp), as text.
    pub settings: String,
    pub trace: String,
    pub version: String,
    pub device: String,
    pub render_seconds: f64,
    pub setup_seconds: f64,
    /// The AOV planes of the integrator that rendered it, in channel order.
    pub aov_planes: Vec<String>,
}

/// Writes a job's sums and description to `path`.
pub fn write_partial(
    path: &Path,
    info: &PartInfo,
    sums: &FilmSums,
) -> std::result::Result<(), OutputError> {
    let write_err = |cause| OutputError::ExrWrite {
        path: path.to_path_buf(),
        cause,
    };
    let w = sums.window;
    let n = w.pixels();
    if info.aov_planes != sums.aov_planes {
        return Err(OutputError::Attribute {
            path: path.to_path_buf(),
            name: AOV_PLANES.into(),
            reason: format!(
                "the job names the planes {:?}, its sums hold {:?}",
                info.aov_planes, sums.aov_planes
            ),
        });
    }
    if let Err(reason) = film::check_aov_names(&sums.aov_planes) {
        return Err(OutputError::AovName {
            path: path.to_path_buf(),
            reason,
        });
    }
    let names = channel_names(&sums.aov_planes);
    let stride = names.len();
    let mut channels = Vec::new();
    for (c, plane) in names.iter().enumerate() {
        for word in 0..4 {
            let data: Vec<u32> = sums.sums[c..]
                .iter()
                .step_by(stride)
                .map(|&x| (x as u128 >> (32 * word)) as u32)
                .collect();
            channels.push(AnyChannel::new(
                Text::from(format!("sum.{plane}.w{word}").as_str()),
                FlatSamples::U32(data),
            ));
        }
    }
    let mut attributes = LayerAttributes::named(Text::from("partial"));
    let mut put = |name: &str, value: String| {
        attributes.other.insert(
            Text::from(name),
            AttributeValue::Text(Text::from(value.as_str())),
        );
    };
    for (k, b) in sums.boundary.iter().enumerate() {
        for (c, plane) in names.iter().enumerate() {
            let data: Vec<f32> = b.sums[c..].iter().step_by(stride).copied().collect();
            channels.push(AnyChannel::new(
                Text::from(format!("block{k}.{plane}").as_str()),
                FlatSamples::F32(data),
            ));
        }
        put(
            &format!("illum.block{k}"),
            format!("{}..{}", b.start, b.end),
        );
    }
    put("illum.partial", "1".into());
    put(
        "illum.samples",
        format!("{}..{}", info.samples.0, info.samples.1),
    );
    put("illum.crop", info.window.to_string());
    put("illum.frame", format!("{}x{}", info.frame.0, info.frame.1));
    put("illum.spp", info.spp.to_string());
    put("illum.seed", info.seed.to_string());
    put("illum.sceneHash", info.scene_hash.clone());
    put("illum.settings", info.settings.clone());
    put("illum.trace", info.trace.clone());
    put("illum.version", info.version.clone());
    put("illum.device", info.device.clone());
    put("illum.renderSeconds", info.render_seconds.to_string());
    put("illum.setupSeconds", info.setup_seconds.to_string());
    if !info.aov_planes.is_empty() {
        put(AOV_PLANES, info.aov_planes.join(","));
    }
    debug_assert!(channels.iter().all(|c| c.sample_data.len() == n));
    let layer = Layer::new(
        (w.width() as usize, w.height() as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut image = Image::from_layer(layer);
    // OpenEXR's meaning, as Nuke and exrinfo read it: the data window is the crop in the
    // frame's pixel coordinates, the display window the whole frame.
    image.layer_data.attributes.layer_position = Vec2(w.x0 as i32, w.y0 as i32);
    image.attributes.display_window =
        IntegerBounds::from_dimensions((info.frame.0 as usize, info.frame.1 as usize));
    crate::output::write_atomically(path, |tmp| image.write().to_file(tmp).map_err(write_err))
}

type Res<T> = std::result::Result<T, OutputError>;

/// "A..B" as (A, B).
fn range_text(v: &str) -> Option<(u32, u32)> {
    let (a, b) = v.split_once("..")?;
    Some((a.parse().ok()?, b.parse().ok()?))
}

fn unsupported(path: &Path, reason: String) -> OutputError {
    OutputError::ExrUnsupported {
        path: path.to_path_buf(),
        reason,
    }
}

/// The job description in a partial EXR's header, checked against its data window `size`.
fn parse_info(path: &Path, attributes: &LayerAttributes, size: Vec2<usize>) -> Res<PartInfo> {
    let bad = |reason: String| unsupported(path, reason);
    let attr = |name: &str| -> Res<String> {
        match attributes.other.get(&Text::from(name)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(bad(format!(
                "not a partial render of illum (no text attribute {name}; write one with illum render --samples, --crop or --part)"
            ))),
        }
    };
    if attr("illum.partial")? != "1" {
        return Err(bad("illum.partial is not 1".into()));
    }
    let parse_range = |name: &str| -> Res<(u32, u32)> {
        let v = attr(name)?;
        range_text(&v).ok_or_else(|| bad(format!("{name} = {v:?} is not A..B")))
    };
    let num = |name: &str| -> Res<f64> {
        let v = attr(name)?;
        v.parse()
            .map_err(|_| bad(format!("{name} = {v:?} is not a number")))
    };
    let crop = attr("illum.crop")?;
    let c: Vec<u32> = crop.split(',').filter_map(|x| x.parse().ok()).collect();
    let [x0, y0, x1, y1] = c[..] else {
        return Err(bad(format!("illum.crop = {crop:?} is not x0,y0,x1,y1")));
    };
    let window = Window { x0, y0, x1, y1 };
    // Absent: the integrator declares no AOV planes.
    let aov_planes: Vec<String> = match attributes.other.get(&Text::from(AOV_PLANES)) {
        Some(AttributeValue::Text(t)) => t.to_string().split(',').map(String::from).collect(),
        Some(_) => return Err(bad(format!("{AOV_PLANES} is not text"))),
        None => Vec::new(),
    };
    film::check_aov_names(&aov_planes).map_err(|e| bad(format!("{AOV_PLANES}: {e}")))?;
    let frame_text = attr("illum.frame")?;
    let frame = frame_text
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .ok_or_else(|| bad(format!("illum.frame = {frame_text:?} is not WxH")))?;
    let info = PartInfo {
        samples: parse_range("illum.samples")?,
        window,
        frame,
        spp: num("illum.spp")? as u32,
        seed: attr("illum.seed")?
            .parse()
            .map_err(|_| bad("illum.seed is not a number".into()))?,
        scene_hash: attr("illum.sceneHash")?,
        settings: attr("illum.settings")?,
        trace: attr("illum.trace")?,
        version: attr("illum.version")?,
        device: attr("illum.device")?,
        render_seconds: num("illum.renderSeconds")?,
        setup_seconds: num("illum.setupSeconds")?,
        aov_planes,
    };
    let position = attributes.layer_position;
    if size != Vec2(window.width() as usize, window.height() as usize)
        || position != Vec2(window.x0 as i32, window.y0 as i32)
    {
        return Err(bad(format!(
            "data window {}x{} at ({}, {}) does not match illum.crop {window}",
            size.0, size.1, position.0, position.1
        )));
    }
    Ok(info)
}

/// Reads only the job description of a partial EXR (its header), without its data.
pub fn read_partial_info(path: &Path) -> Res<PartInfo> {
    let meta = MetaData::read_from_file(path, false).map_err(|cause| OutputError::ExrRead {
        path: path.to_path_buf(),
        cause,
    })?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| unsupported(path, "no parts".into()))?;
    parse_info(path, &header.own_attributes, header.layer_size)
}

/// Deflate expands data at most 1032 times: the most pixel bytes a compressed file can hold.
const MAX_EXPANSION: u64 = 1032;

/// Refuses a file whose header declares more pixel data than its size can hold, before the
/// reader allocates it (a flipped size field asked for 240 GB).
fn check_declared_size(path: &Path) -> Res<()> {
    let meta = MetaData::read_from_file(path, false).map_err(|cause| OutputError::ExrRead {
        path: path.to_path_buf(),
        cause,
    })?;
    let len = std::fs::metadata(path)
        .map_err(|cause| OutputError::ExrRead {
            path: path.to_path_buf(),
            cause: exr::error::Error::from(cause),
        })?
        .len();
    let mut declared: u64 = 0;
    for h in &meta.headers {
        let pixels = h.layer_size.0 as u64 * h.layer_size.1 as u64;
        for c in &h.channels.list {
            let bytes = pixels.saturating_mul(c.sample_type.bytes_per_sample() as u64);
            declared = declared.saturating_add(bytes);
        }
    }
    if declared > len.saturating_mul(MAX_EXPANSION) {
        return Err(unsupported(
            path,
            format!(
                "its header declares {declared} bytes of pixels, more than a {len}-byte file \
                 can hold"
            ),
        ));
    }
    Ok(())
}

/// Reads a partial EXR written by [`write_partial`].
pub fn read_partial(path: &Path) -> Res<(PartInfo, FilmSums)> {
    let bad = |reason: String| unsupported(path, reason);
    check_declared_size(path)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|cause| OutputError::ExrRead {
            path: path.to_path_buf(),
            cause,
        })?;
    let layer = image
        .layer_data
        .into_iter()
        .next()
        .ok_or_else(|| bad("no parts".into()))?;
    let info = parse_info(path, &layer.attributes, layer.size)?;
    let window = info.window;
    let attr = |name: &str| -> Option<String> {
        match layer.attributes.other.get(&Text::from(name)) {
            Some(AttributeValue::Text(t)) => Some(t.to_string()),
            _ => None,
        }
    };
    let n = window.pixels();
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .map(|c| &c.sample_data)
    };
    let names = channel_names(&info.aov_planes);
    let stride = names.len();
    let mut sums = FilmSums::new(window, info.aov_planes.clone());
    for (c, plane) in names.iter().enumerate() {
        let word = |k: usize| {
            let name = format!("sum.{plane}.w{k}");
            match channel(&name) {
                Some(FlatSamples::U32(v)) if v.len() == n => Ok(v),
                _ => Err(bad(format!("missing UINT channel {name}"))),
            }
        };
        let (w0, w1, w2, w3) = (word(0)?, word(1)?, word(2)?, word(3)?);
        // One pass per channel: the sums are strided, the words are not.
        for (i, p) in sums.sums[c..].iter_mut().step_by(stride).enumerate() {
            *p = (u128::from(w0[i])
                | u128::from(w1[i]) << 32
                | u128::from(w2[i]) << 64
                | u128::from(w3[i]) << 96) as i128;
        }
    }
    for k in 0..2 {
        // No attribute: the job has no such block; a malformed one is an error, not a skip.
        let name = format!("illum.block{k}");
        let Some(v) = attr(&name) else {
            continue;
        };
        let range = range_text(&v).ok_or_else(|| bad(format!("{name} = {v:?} is not A..B")))?;
        let mut block = BoundaryBlock {
            start: range.0,
            end: range.1,
            sums: vec![0.0; n * stride],
        };
        for (c, plane) in names.iter().enumerate() {
            let name = format!("block{k}.{plane}");
            let Some(FlatSamples::F32(v)) = channel(&name) else {
                return Err(bad(format!("missing FLOAT channel {name}")));
            };
            for (p, &x) in block.sums[c..].iter_mut().step_by(stride).zip(v) {
                *p = x;
            }
        }
        sums.boundary.push(block);
    }
    Ok((info, sums))
}
