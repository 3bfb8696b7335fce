//! Image decoding into linear RGBA `Texture`s: PNG/JPEG/HDR through the image crate, OpenEXR
//! through the exr crate.

use super::types::Texture;
use glam::Vec4;
use std::io::Cursor;

/// Container formats illum reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ImageKind {
    Png,
    Jpeg,
    Exr,
    Hdr,
}

impl ImageKind {
    /// From a file name's extension (case-insensitive).
    pub fn from_path(path: &str) -> Option<Self> {
        let ext = path.rsplit_once('.')?.1.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageKind::Png),
            "jpg" | "jpeg" => Some(ImageKind::Jpeg),
            "exr" => Some(ImageKind::Exr),
            "hdr" => Some(ImageKind::Hdr),
            _ => None,
        }
    }

    /// From the first bytes of the data (glTF images may have no usable name or MIME type).
    pub fn sniff(bytes: &[u8]) -> Option<Self> {
        if bytes.starts_with(b"\x89PNG") {
            Some(ImageKind::Png)
        } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            Some(ImageKind::Jpeg)
        } else if bytes.starts_with(&[0x76, 0x2F, 0x31, 0x01]) {
            Some(ImageKind::Exr)
        } else if bytes.starts_with(b"#?") {
            Some(ImageKind::Hdr)
        } else {
            None
        }
    }

    /// Whether files of this kind hold sRGB-encoded values unless told otherwise.
    pub fn srgb_by_default(self) -> bool {
        matches!(self, ImageKind::Png | ImageKind::Jpeg)
    }
}

/// Decodes `bytes` into linear RGBA; `srgb` decodes the RGB channels from sRGB (alpha is
/// always linear). Errors are plain messages; the caller adds file and field.
pub(crate) fn decode(
    name: &str,
    bytes: &[u8],
    kind: ImageKind,
    srgb: bool,
) -> Result<Texture, String> {
    let (width, height, mut texels) = match kind {
        ImageKind::Exr => decode_exr(bytes)?,
        ImageKind::Png | ImageKind::Jpeg | ImageKind::Hdr => {
            let format = match kind {
                ImageKind::Png => image::ImageFormat::Png,
                ImageKind::Jpeg => image::ImageFormat::Jpeg,
                _ => image::ImageFormat::Hdr,
            };
            let img =
                image::load_from_memory_with_format(bytes, format).map_err(|e| e.to_string())?;
            let (w, h) = (img.width(), img.height());
            // Float images straight to RGBA texels: through `into_rgba32f` an 8192 x 4096 HDR
            // map took another 537 MB and its page faults.
            let texels = match img {
                image::DynamicImage::ImageRgb32F(b) => b
                    .pixels()
                    .map(|p| Vec4::new(p.0[0], p.0[1], p.0[2], 1.0))
                    .collect::<Vec<_>>(),
                other => other
                    .into_rgba32f()
                    .pixels()
                    .map(|p| Vec4::from_array(p.0))
                    .collect(),
            };
            (w, h, texels)
        }
    };
    if width == 0 || height == 0 {
        return Err("image is empty".into());
    }
    if let Some(bad) = texels.iter().position(|t| !t.is_finite()) {
        return Err(format!(
            "pixel ({}, {}) is not finite",
            bad % width as usize,
            bad / width as usize
        ));
    }
    if srgb {
        for t in &mut texels {
            *t = Vec4::new(
                srgb_to_linear(t.x),
                srgb_to_linear(t.y),
                srgb_to_linear(t.z),
                t.w,
            );
        }
    }
    Ok(Texture::new(name, width, height, texels))
}

fn decode_exr(bytes: &[u8]) -> Result<(u32, u32, Vec<Vec4>), String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| (size.width(), vec![glam::Vec4::ONE; size.area()]),
            |(w, px): &mut (usize, Vec<glam::Vec4>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = glam::Vec4::new(r, g, b, a);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    let w = u32::try_from(size.width()).map_err(|_| "image too large".to_string())?;
    let h = u32::try_from(size.height()).map_err(|_| "image too large".to_string())?;
    Ok((w, h, texels))
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-9);
    }

    #[test]
    fn kinds_from_names_and_bytes() {
        assert_eq!(ImageKind::from_path("a/b.JPG"), Some(ImageKind::Jpeg));
        assert_eq!(ImageKind::from_path("sky.hdr"), Some(ImageKind::Hdr));
        assert_eq!(ImageKind::from_path("noext"), None);
        assert_eq!(ImageKind::sniff(b"\x89PNG\r\n"), Some(ImageKind::Png));
        assert_eq!(ImageKind::sniff(b"#?RADIANCE"), Some(ImageKind::Hdr));
        assert!(ImageKind::Png.srgb_by_default() && !ImageKind::Exr.srgb_by_default());
    }

    #[test]
    fn corrupt_images_are_errors_not_panics() {
        assert!(decode("x", b"\x89PNG garbage", ImageKind::Png, true).is_err());
        assert!(decode("x", b"v/1\x01 garbage", ImageKind::Exr, false).is_err());
        assert!(decode("x", b"", ImageKind::Jpeg, true).is_err());
    }
}
