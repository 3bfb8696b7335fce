//! 8-bit sRGB PNG of the beauty.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use image::ImageEncoder;
use image::codecs::png::PngEncoder;

use super::{Film, OutputError};

/// Writes the beauty as 8-bit RGB: clamped to [0,1], encoded with the exact piecewise sRGB
/// OETF, rounded to nearest; NaN and ±inf become 0.
pub fn write_png(path: &Path, film: &Film) -> Result<(), OutputError> {
    super::validate_film(film, path)?;
    let encoder = SrgbEncoder::new();
    let mut bytes = Vec::with_capacity(film.pixel_count() * 3);
    bytes.extend(film.beauty.iter().flatten().map(|&v| encoder.encode(v)));
    write_rgb8_png(path, &bytes, film.width, film.height)
}

/// Writes `width` x `height` 8-bit RGB pixels (row-major) as a PNG, through a temporary file.
pub fn write_rgb8_png(
    path: &Path,
    bytes: &[u8],
    width: u32,
    height: u32,
) -> Result<(), OutputError> {
    let io_err = |cause| OutputError::Io {
        path: path.to_path_buf(),
        cause,
    };
    super::write_atomically(path, |tmp| {
        let mut out = BufWriter::new(File::create(tmp).map_err(io_err)?);
        PngEncoder::new(&mut out)
            .write_image(bytes, width, height, image::ExtendedColorType::Rgb8)
            .map_err(|cause| OutputError::Png {
                path: path.to_path_buf(),
                cause,
            })?;
        // BufWriter's drop would swallow a failing final flush.
        out.flush().map_err(io_err)
    })
}

/// Inverse of the sRGB OETF (`12.92 v` up to v = 0.0031308, else `1.055 v^(1/2.4) - 0.055`),
/// split at the encoded image of 0.0031308 so it inverts exactly that piecewise function.
fn srgb_eotf(e: f64) -> f64 {
    if e <= 12.92 * 0.003_130_8 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

/// Quantises linear values to 8-bit sRGB without a `powf` per sample: byte k+1 starts at the
/// linear value whose encoding is (k + 0.5) / 255, so the byte is the number of such
/// thresholds at or below the value (round-half-up of `255 * oetf(v)`).
pub struct SrgbEncoder {
    thresholds: [f64; 255],
}

impl Default for SrgbEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl SrgbEncoder {
    pub fn new() -> Self {
        Self {
            thresholds: std::array::from_fn(|k| srgb_eotf((k as f64 + 0.5) / 255.0)),
        }
    }

    pub fn encode(&self, v: f32) -> u8 {
        if !v.is_finite() {
            return 0;
        }
        let v = f64::from(v);
        // At most 255, so the cast is lossless.
        self.thresholds.partition_point(|&t| t <= v) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srgb_oetf(v: f64) -> f64 {
        if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
    }

    fn reference(v: f32) -> u8 {
        if !v.is_finite() {
            return 0;
        }
        (srgb_oetf(f64::from(v).clamp(0.0, 1.0)) * 255.0).round() as u8
    }

    #[test]
    fn known_values() {
        let e = SrgbEncoder::new();
        for (v, b) in [
            (0.0, 0),
            (-1.0, 0),
            (1.0, 255),
            (7.5, 255),
            (0.5, 188),
            (0.18, 118),
            (0.003_130_8, 10),
            (f32::NAN, 0),
            (f32::INFINITY, 0),
            (f32::NEG_INFINITY, 0),
        ] {
            assert_eq!(e.encode(v), b, "{v}");
        }
    }

    #[test]
    fn matches_double_precision_formula() {
        let e = SrgbEncoder::new();
        // Dense sweep of [0, 1.1] plus every f32 bit pattern step through the low range.
        for i in 0..=1_100_000 {
            let v = i as f32 / 1_000_000.0;
            assert_eq!(e.encode(v), reference(v), "{v}");
        }
        for bits in (0..0x3f80_0000u32).step_by(997) {
            let v = f32::from_bits(bits);
            assert_eq!(e.encode(v), reference(v), "{v}");
        }
    }

    #[test]
    fn inverse_is_inverse() {
        for i in 0..=1000 {
            let e = i as f64 / 1000.0;
            assert!((srgb_oetf(srgb_eotf(e)) - e).abs() < 1e-12, "{e}");
        }
    }
}
