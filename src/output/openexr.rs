//! EXR writing (all film planes in one part) and reading (any scanline/tiled float EXR).

use std::path::{Path, PathBuf};

use exr::block::{BlockIndex, UncompressedBlock};
use exr::image::write::channels::{ChannelsWriter, WritableChannels};
use exr::image::{Blocks, Encoding, FlatSamples, Image, Layer};
use exr::math::RoundingMode;
use exr::meta::MetaData;
use exr::meta::attribute::{
    AttributeValue, ChannelDescription, ChannelList, Compression, LevelMode, LineOrder, SampleType,
    Text,
};
use exr::meta::header::{Header, LayerAttributes, standard_names};
use exr::prelude::{ReadChannels, ReadLayers, WritableImage};

use super::{Film, ImageMetadata, OutputError};

/// Custom attributes written from [`ImageMetadata`]'s fixed fields.
const SPP: &str = "illum.spp";
const RENDER_SECONDS: &str = "illum.renderSeconds";
const SETUP_SECONDS: &str = "illum.setupSeconds";
const DEVICE: &str = "illum.device";
const SEED: &str = "illum.seed";

/// Writes every plane of `film` as 32-bit float channels of a single-part, ZIP-compressed
/// scanline EXR, with `meta` as header attributes.
pub fn write_exr(path: &Path, film: &Film, meta: &ImageMetadata) -> Result<(), OutputError> {
    super::validate_film(film, path)?;
    let attributes = layer_attributes(path, meta)?;
    let channels = FilmChannels::new(film);
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let size = (film.width as usize, film.height as usize);
    let image = Image::from_layer(Layer::new(size, attributes, encoding, channels));
    super::write_atomically(path, |tmp| {
        image
            .write()
            .to_file(tmp)
            .map_err(|cause| OutputError::ExrWrite {
                path: path.to_path_buf(),
                cause,
            })
    })
}

/// Reads the beauty of a reference image (any EXR with R/G/B or `<layer>`.R/G/B) and checks that
/// it has the render's resolution.
pub fn read_reference(path: &Path, width: u32, height: u32) -> Result<Vec<[f32; 3]>, OutputError> {
    let img = read_exr(path)?;
    if (img.width, img.height) != (width, height) {
        return Err(OutputError::ReferenceSize {
            path: path.to_path_buf(),
            width: img.width,
            height: img.height,
            expected_width: width,
            expected_height: height,
        });
    }
    img.rgb()
}

fn text(s: &str) -> Text {
    // EXR strings are bytes; UTF-8 is what OpenEXR-based tools store and expect.
    Text::from_slice_unchecked(s.as_bytes())
}

fn layer_attributes(path: &Path, meta: &ImageMetadata) -> Result<LayerAttributes, OutputError> {
    let mut attributes = LayerAttributes {
        software_name: Some(text(concat!("illum ", env!("CARGO_PKG_VERSION")))),
        ..LayerAttributes::default()
    };
    let spp = match i32::try_from(meta.spp) {
        Ok(spp) => AttributeValue::I32(spp),
        Err(_) => AttributeValue::Text(text(&meta.spp.to_string())),
    };
    let fixed = [
        (SPP, spp),
        (RENDER_SECONDS, AttributeValue::F64(meta.render_seconds)),
        (SETUP_SECONDS, AttributeValue::F64(meta.setup_seconds)),
        (DEVICE, AttributeValue::Text(text(&meta.device))),
        // EXR ints are i32, so the u64 seed goes as its decimal string.
        (SEED, AttributeValue::Text(text(&meta.seed.to_string()))),
    ];
    for (name, value) in fixed {
        attributes.other.insert(text(name), value);
    }
    for (name, value) in &meta.extra {
        let reason = if name.is_empty() || name.len() > 255 || name.contains('\0') {
            Some("names must be 1 to 255 bytes without NUL")
        } else if [SPP, RENDER_SECONDS, SETUP_SECONDS, DEVICE, SEED].contains(&name.as_str())
            || standard_names::ALL.contains(&name.as_bytes())
        {
            Some("the name is reserved for a standard or illum attribute")
        } else if attributes.other.contains_key(&text(name)) {
            Some("the name is given twice")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(OutputError::Attribute {
                path: path.to_path_buf(),
                name: name.clone(),
                reason: reason.into(),
            });
        }
        attributes
            .other
            .insert(text(name), AttributeValue::Text(text(value)));
    }
    Ok(attributes)
}

use crate::film::FILM_LAYERS;

/// Where one EXR channel's samples live in the film.
#[derive(Clone, Copy)]
enum Source<'a> {
    Component(&'a [[f32; 3]], usize),
    Scalar(&'a [f32]),
}

/// Streams film planes straight into EXR blocks, so writing needs no per-channel copies of
/// the film (a 4096² film is 1 GiB of planes).
#[derive(Clone)]
struct FilmChannels<'a> {
    width: usize,
    /// Sorted by name, as the EXR channel list must be.
    channels: Vec<(String, Source<'a>)>,
}

impl<'a> FilmChannels<'a> {
    fn new(film: &'a Film) -> Self {
        let mut channels = vec![("Z".to_string(), Source::Scalar(&film.depth))];
        if let Some(samples) = &film.samples {
            channels.push(("SampleCount".to_string(), Source::Scalar(samples)));
        }
        let mut add = |layer: &str, components: [&str; 3], plane: &'a [[f32; 3]]| {
            for (c, component) in components.into_iter().enumerate() {
                let name = if layer.is_empty() {
                    component.to_string()
                } else {
                    format!("{layer}.{component}")
                };
                channels.push((name, Source::Component(plane, c)));
            }
        };
        const RGB: [&str; 3] = ["R", "G", "B"];
        let [albedo, normal, emission, variance_layer] = FILM_LAYERS;
        add("", RGB, &film.beauty);
        add(albedo, RGB, &film.albedo);
        add(normal, ["X", "Y", "Z"], &film.normal);
        add(emission, RGB, &film.emission);
        if let Some(variance) = &film.variance {
            add(variance_layer, RGB, variance);
        }
        for aov in &film.aovs {
            add(&aov.name, RGB, &aov.rgb);
        }
        channels.sort_unstable_by(|a, b| a.0.cmp(&b.0));
        Self {
            width: film.width as usize,
            channels,
        }
    }
}

impl<'slf> WritableChannels<'slf> for FilmChannels<'_> {
    type Writer = Self;

    fn infer_channel_list(&self) -> ChannelList {
        ChannelList::new(
            self.channels
                .iter()
                .map(|(name, _)| ChannelDescription::named(text(name), SampleType::F32))
                .collect(),
        )
    }

    fn infer_level_modes(&self) -> (LevelMode, RoundingMode) {
        (LevelMode::Singular, RoundingMode::Down)
    }

    fn create_writer(&'slf self, _header: &Header) -> Self::Writer {
        self.clone()
    }
}

impl ChannelsWriter for FilmChannels<'_> {
    fn extract_uncompressed_block(&self, header: &Header, block: BlockIndex) -> Vec<u8> {
        UncompressedBlock::collect_block_data_from_lines(&header.channels, block, |line| {
            let at = line.location;
            let start = at.position.y() * self.width + at.position.x();
            let range = start..start + at.sample_count;
            // Uncompressed blocks are native-endian; exr converts when compressing.
            let out = line.value.chunks_exact_mut(4);
            match self.channels[at.channel].1 {
                Source::Component(plane, c) => {
                    for (o, px) in out.zip(&plane[range]) {
                        o.copy_from_slice(&px[c].to_ne_bytes());
                    }
                }
                Source::Scalar(plane) => {
                    for (o, v) in out.zip(&plane[range]) {
                        o.copy_from_slice(&v.to_ne_bytes());
                    }
                }
            }
        })
    }
}

/// An EXR read back as float channels.
#[derive(Debug, Clone, PartialEq)]
pub struct ExrImage {
    /// The file this was read from (for error messages).
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Full channel names (`"R"`, `"Albedo.G"`, ...) with width*height samples each, row-major,
    /// top row first. In multi-part files a part's name prefixes its channels unless they
    /// already carry it.
    pub channels: Vec<(String, Vec<f32>)>,
    /// Every attribute of the first part's header, stringified (numbers in Rust's shortest
    /// round-trip form, strings as stored).
    pub attributes: Vec<(String, String)>,
}

/// Layer names, lower-cased, that other renderers use for the beauty.
const BEAUTY_LAYERS: &[&str] = &[
    "beauty", "default", "rgba", "rgb", "combined", "ci", "color",
];

impl ExrImage {
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// The value of the attribute `name`, stringified.
    pub fn attribute(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// The beauty as RGB: channels "R","G","B", else the `<layer>.R/G/B` of a layer named like a
    /// beauty (`beauty`, `default`, `rgba`, `combined`, ...), else the first layer with
    /// `.R/.G/.B`; else an error naming the file and its channels.
    pub fn rgb(&self) -> Result<Vec<[f32; 3]>, OutputError> {
        let layer_rgb = |prefix: &str| {
            let get = |c: &str| self.channel(&format!("{prefix}{c}"));
            Some([get("R")?, get("G")?, get("B")?])
        };
        let candidates = || {
            self.channels
                .iter()
                .filter_map(|(name, _)| name.strip_suffix(".R"))
                .filter_map(|layer| Some((layer, layer_rgb(&format!("{layer}."))?)))
        };
        let is_beauty = |layer: &str| {
            let last = layer
                .rsplit('.')
                .next()
                .unwrap_or(layer)
                .to_ascii_lowercase();
            BEAUTY_LAYERS.contains(&last.as_str())
        };
        let found = layer_rgb("")
            .or_else(|| {
                candidates()
                    .find(|(layer, _)| is_beauty(layer))
                    .map(|c| c.1)
            })
            .or_else(|| candidates().next().map(|c| c.1));
        let [r, g, b] = found.ok_or_else(|| OutputError::NoBeauty {
            path: self.path.clone(),
            channels: self.channels.iter().map(|(n, _)| n.clone()).collect(),
        })?;
        Ok(r.iter()
            .zip(g)
            .zip(b)
            .map(|((&r, &g), &b)| [r, g, b])
            .collect())
    }
}

/// Reads all channels of the largest resolution level of every part with the first part's
/// size (as f32), and the first part's attributes.
pub fn read_exr(path: &Path) -> Result<ExrImage, OutputError> {
    let read_err = |cause| OutputError::ExrRead {
        path: path.to_path_buf(),
        cause,
    };
    let unsupported = |reason: String| OutputError::ExrUnsupported {
        path: path.to_path_buf(),
        reason,
    };
    // The header pass is cheap, fails fast on non-EXR files and keeps every attribute exact.
    let meta = MetaData::read_from_file(path, false).map_err(read_err)?;
    let attributes = meta
        .headers
        .first()
        .map(|h| {
            h.all_named_attributes()
                .map(|(n, v)| (text_string(n), value_string(&v)))
                .collect()
        })
        .unwrap_or_default();

    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(read_err)?;
    let multi_part = image.layer_data.len() > 1;
    let size = image
        .layer_data
        .first()
        .map(|l| l.size)
        .ok_or_else(|| unsupported("no parts".into()))?;
    let (width, height) = (
        u32::try_from(size.0).map_err(|_| unsupported("too wide".into()))?,
        u32::try_from(size.1).map_err(|_| unsupported("too tall".into()))?,
    );

    let mut channels = Vec::new();
    // Parts of another size (e.g. a cropped data window) cannot be indexed like the first.
    for layer in image.layer_data.into_iter().filter(|l| l.size == size) {
        let part = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| text_string(n.as_slice()));
        for channel in layer.channel_data.list {
            let mut name = text_string(channel.name.as_slice());
            if let Some(part) = part.as_deref().filter(|_| multi_part) {
                if !name.starts_with(&format!("{part}.")) {
                    name = format!("{part}.{name}");
                }
            }
            let samples: Vec<f32> = match channel.sample_data {
                FlatSamples::F32(v) => v,
                FlatSamples::F16(v) => v.into_iter().map(f32::from).collect(),
                FlatSamples::U32(v) => v.into_iter().map(|x| x as f32).collect(),
            };
            if samples.len() != size.0 * size.1 {
                return Err(unsupported(format!("channel `{name}` is subsampled")));
            }
            channels.push((name, samples));
        }
    }
    Ok(ExrImage {
        path: path.to_path_buf(),
        width,
        height,
        channels,
        attributes,
    })
}

/// EXR text as a String: UTF-8 where valid (what we and OpenEXR write), else Latin-1.
fn text_string(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

fn value_string(value: &AttributeValue) -> String {
    match value {
        AttributeValue::Text(t) => text_string(t.as_slice()),
        AttributeValue::TextVector(v) => v
            .iter()
            .map(|t| text_string(t.as_slice()))
            .collect::<Vec<_>>()
            .join(", "),
        AttributeValue::I32(v) => v.to_string(),
        AttributeValue::F32(v) => v.to_string(),
        AttributeValue::F64(v) => v.to_string(),
        AttributeValue::ChannelList(list) => list
            .list
            .iter()
            .map(|c| format!("{} ({:?})", text_string(c.name.as_slice()), c.sample_type))
            .collect::<Vec<_>>()
            .join(", "),
        AttributeValue::Preview(p) => format!("preview {}x{}", p.size.0, p.size.1),
        AttributeValue::Bytes { type_hint, bytes } => {
            format!(
                "{} bytes ({})",
                bytes.len(),
                text_string(type_hint.as_slice())
            )
        }
        AttributeValue::Custom { kind, bytes } => {
            format!(
                "{} bytes of type {}",
                bytes.len(),
                text_string(kind.as_slice())
            )
        }
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_list_is_sorted_and_complete() {
        let mut film = Film::new(2, 2);
        let names = |f: &Film| -> Vec<String> {
            FilmChannels::new(f)
                .channels
                .iter()
                .map(|c| c.0.clone())
                .collect()
        };
        let without = names(&film);
        assert_eq!(without.len(), 13);
        assert!(without.is_sorted());
        film.variance = Some(vec![[0.0; 3]; 4]);
        let with = names(&film);
        assert_eq!(with.len(), 16);
        assert!(with.is_sorted() && with.contains(&"Variance.G".to_string()));
        for name in ["Direct", "IndirectDiffuse", "Reflection"] {
            film.aovs.push(crate::output::AovPlane {
                name: name.into(),
                rgb: vec![[0.0; 3]; 4],
            });
        }
        let aovs = names(&film);
        assert_eq!(aovs.len(), 25);
        assert!(aovs.is_sorted() && aovs.contains(&"IndirectDiffuse.B".to_string()));
    }

    #[test]
    fn reserved_extra_names_are_rejected() {
        for name in ["software", "illum.spp", "channels", "", "a\0b"] {
            let meta = ImageMetadata {
                extra: vec![(name.into(), "x".into())],
                ..Default::default()
            };
            let err = layer_attributes(Path::new("r.exr"), &meta)
                .unwrap_err()
                .to_string();
            assert!(err.contains("r.exr"), "{err}");
        }
        let meta = ImageMetadata {
            extra: vec![("a".into(), "1".into()), ("a".into(), "2".into())],
            ..Default::default()
        };
        assert!(layer_attributes(Path::new("r.exr"), &meta).is_err());
    }
}
