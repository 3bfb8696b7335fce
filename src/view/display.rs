//! What the window shows of a render in progress: one plane of the film (the beauty, an AOV, the
//! per-pixel sample count or its estimated error) as 8-bit sRGB, scaled into the window above the
//! status bar. The beauty and the integrator's layers are exposed by 2^EV and encoded as
//! `illum render`'s PNG (exact sRGB, rounded), so at EV 0 and scale 1 the window shows the
//! PNG's bytes.

use crate::film::FILM_CHANNELS;
use crate::layout::FilmPixel;
use crate::output::SrgbEncoder;
use crate::render::Peek;

/// A plane the window can show.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Plane {
    Beauty,
    Albedo,
    Normal,
    Depth,
    /// The integrator's AOV plane of this index (e.g. IndirectDiffuse).
    Aov(usize),
    /// Samples each pixel took, black 0 to white at the most any pixel took.
    Samples,
    /// The estimated relative standard error of each pixel's mean, black 0 to white at 10%.
    Error,
}

/// The planes in the order the A key steps through them.
pub fn planes(aovs: usize) -> Vec<Plane> {
    let mut p = vec![Plane::Beauty, Plane::Albedo, Plane::Normal, Plane::Depth];
    p.extend((0..aovs).map(Plane::Aov));
    p.extend([Plane::Samples, Plane::Error]);
    p
}

impl Plane {
    pub fn name(self, aovs: &[&str]) -> String {
        match self {
            Plane::Beauty => "beauty".into(),
            Plane::Albedo => "albedo".into(),
            Plane::Normal => "normal".into(),
            Plane::Depth => "depth".into(),
            Plane::Aov(k) => aovs.get(k).copied().unwrap_or("?").to_string(),
            Plane::Samples => "sample count".into(),
            Plane::Error => "relative error (white: 10%)".into(),
        }
    }

    /// Whether the plane is radiance, shown through the exposure.
    fn exposed(self) -> bool {
        matches!(self, Plane::Beauty | Plane::Aov(_))
    }
}

/// The plane's linear values, one RGB per pixel of the `pixels`-pixel image.
pub fn values(peek: &Peek, plane: Plane, pixels: usize) -> Vec<[f32; 3]> {
    let count = |i| peek.channel(i, FilmPixel::BEAUTY_ODD + 3).max(1.0);
    let mean = |i, at| mean(peek, i, at);
    match plane {
        Plane::Beauty => (0..pixels).map(|i| mean(i, FilmPixel::BEAUTY)).collect(),
        Plane::Albedo => (0..pixels).map(|i| mean(i, FilmPixel::ALBEDO)).collect(),
        Plane::Normal => (0..pixels)
            .map(|i| mean(i, FilmPixel::NORMAL).map(|v| 0.5 * v + 0.5))
            .collect(),
        Plane::Aov(k) => {
            let at = FILM_CHANNELS + crate::film::AOV_CHANNELS * k;
            (0..pixels).map(|i| mean(i, at)).collect()
        }
        Plane::Depth => {
            let depth: Vec<f64> = (0..pixels)
                .map(|i| {
                    let hits = peek.channel(i, FilmPixel::ALBEDO + 3);
                    if hits > 0.0 {
                        peek.channel(i, FilmPixel::NORMAL + 3) / hits
                    } else {
                        f64::INFINITY
                    }
                })
                .collect();
            let far = depth
                .iter()
                .copied()
                .filter(|d| d.is_finite())
                .fold(0.0, f64::max);
            // Near is bright; a miss is black.
            depth
                .iter()
                .map(|&d| {
                    let v = if d.is_finite() && far > 0.0 {
                        (1.0 - 0.9 * d / far) as f32
                    } else {
                        0.0
                    };
                    [v; 3]
                })
                .collect()
        }
        Plane::Samples => {
            let n: Vec<f64> = (0..pixels)
                .map(|i| peek.channel(i, FilmPixel::BEAUTY_ODD + 3))
                .collect();
            let most = n.iter().copied().fold(1.0, f64::max);
            n.iter().map(|&v| [(v / most) as f32; 3]).collect()
        }
        Plane::Error => (0..pixels)
            .map(|i| {
                let n = count(i);
                let lum = |at: usize| {
                    let c = |k| peek.channel(i, at + k);
                    0.2126 * c(0) + 0.7152 * c(1) + 0.0722 * c(2)
                };
                // The variance of the mean from the sums of squares of each channel, through the
                // luminance weights (channels taken as independent: a display, not a report).
                let mean = lum(FilmPixel::BEAUTY) / n;
                let w = [0.2126, 0.7152, 0.0722];
                let var: f64 = (0..3)
                    .map(|c| {
                        let m = peek.channel(i, FilmPixel::BEAUTY + c) / n;
                        let m2 = peek.channel(i, FilmPixel::BEAUTY_SQ + c) / n;
                        w[c] * w[c] * (m2 - m * m).max(0.0) / (n - 1.0).max(1.0)
                    })
                    .sum();
                let rel = if mean > 0.0 { var.sqrt() / mean } else { 0.0 };
                [(rel / 0.1).min(1.0) as f32; 3]
            })
            .collect(),
    }
}

/// Pixel `i`'s mean over its samples of the three channels from `at`, as the film's resolve
/// computes it (the f64 sum over the sample count, rounded to f32 once).
fn mean(peek: &Peek, i: usize, at: usize) -> [f32; 3] {
    let n = peek.channel(i, FilmPixel::BEAUTY_ODD + 3).max(1.0);
    std::array::from_fn(|c| (peek.channel(i, at + c) / n) as f32)
}

/// The planes the denoiser reads (beauty, albedo, normal, emission seen directly) as a film.
pub fn film(peek: &Peek, width: u32, height: u32) -> crate::film::Film {
    let mut f = crate::film::Film::new(width, height);
    for i in 0..f.pixel_count() {
        let mean = |at| mean(peek, i, at);
        f.beauty[i] = mean(FilmPixel::BEAUTY);
        f.albedo[i] = mean(FilmPixel::ALBEDO);
        f.normal[i] = mean(FilmPixel::NORMAL);
        f.emission[i] = mean(FilmPixel::EMISSION);
    }
    f
}

/// The image's relMSE estimated from its half-buffers (as `illum render` reports it), None
/// below 2 samples.
pub fn estimate(peek: &Peek, pixels: usize) -> Option<f64> {
    let (mut beauty, mut even, mut odd) = (Vec::new(), Vec::new(), Vec::new());
    let (mut counts, mut variance) = (Vec::with_capacity(pixels), Vec::with_capacity(pixels));
    for i in 0..pixels {
        let n = peek.channel(i, FilmPixel::BEAUTY_ODD + 3) as u32;
        let (n_all, n_even, n_odd) = (
            f64::from(n.max(1)),
            f64::from(n.div_ceil(2).max(1)),
            f64::from((n / 2).max(1)),
        );
        let sum: [f64; 3] = std::array::from_fn(|c| peek.channel(i, FilmPixel::BEAUTY + c));
        let o: [f64; 3] = std::array::from_fn(|c| peek.channel(i, FilmPixel::BEAUTY_ODD + c));
        // s² / n, as film::resolve gives it.
        variance.push(std::array::from_fn(|c| {
            let (mean, m2) = (
                sum[c] / n_all,
                peek.channel(i, FilmPixel::BEAUTY_SQ + c) / n_all,
            );
            ((m2 - mean * mean).max(0.0) / (n_all - 1.0).max(1.0)) as f32
        }));
        beauty.push(sum.map(|s| (s / n_all) as f32));
        even.push(std::array::from_fn(|c| ((sum[c] - o[c]) / n_even) as f32));
        odd.push(o.map(|v| (v / n_odd) as f32));
        counts.push(n);
    }
    let split = &peek.split[..pixels];
    crate::metrics::estimated_relmse(&beauty, &even, &odd, &counts, split, &variance)
}

/// The plane as 8-bit sRGB, radiance scaled by 2^`exposure` first.
pub fn encode(values: &[[f32; 3]], plane: Plane, exposure: f32, enc: &SrgbEncoder) -> Vec<[u8; 3]> {
    let scale = if plane.exposed() {
        exposure.exp2()
    } else {
        1.0
    };
    values
        .iter()
        .map(|v| v.map(|c| enc.encode(c * scale)))
        .collect()
}

/// Where the image lands in a frame of `frame` pixels above a bar of `bar` rows: the largest
/// integer (else fractional) scale of `image` that fits, centred.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub height: u32,
}

pub fn place(image: [u32; 2], frame: [u32; 2], bar: u32) -> Placement {
    let area = [frame[0], frame[1].saturating_sub(bar)];
    let fit =
        (f64::from(area[0]) / f64::from(image[0])).min(f64::from(area[1]) / f64::from(image[1]));
    let scale = if fit >= 1.0 { fit.floor() } else { fit };
    let (width, height) = (
        ((f64::from(image[0]) * scale) as u32).max(1),
        ((f64::from(image[1]) * scale) as u32).max(1),
    );
    Placement {
        x0: (area[0].saturating_sub(width)) / 2,
        y0: (area[1].saturating_sub(height)) / 2,
        width,
        height,
    }
}

/// Writes `image` (`size` pixels) into `frame` (RGBA8 rows of `frame_size` pixels) at `at`,
/// nearest-neighbour; the rest of the frame is left as it is.
pub fn blit(
    frame: &mut [u8],
    frame_size: [u32; 2],
    image: &[[u8; 3]],
    size: [u32; 2],
    at: Placement,
) {
    let fw = frame_size[0] as usize;
    for y in 0..at.height.min(frame_size[1].saturating_sub(at.y0)) {
        let sy = (u64::from(y) * u64::from(size[1]) / u64::from(at.height)) as usize;
        let row = (at.y0 + y) as usize * fw;
        for x in 0..at.width.min(frame_size[0].saturating_sub(at.x0)) {
            let sx = (u64::from(x) * u64::from(size[0]) / u64::from(at.width)) as usize;
            let p = image[sy * size[0] as usize + sx];
            let o = 4 * (row + (at.x0 + x) as usize);
            frame[o..o + 4].copy_from_slice(&[p[0], p[1], p[2], 255]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_image_takes_the_largest_integer_scale_that_fits_centred() {
        assert_eq!(
            place([64, 48], [64, 48 + 40], 40),
            Placement {
                x0: 0,
                y0: 0,
                width: 64,
                height: 48
            }
        );
        assert_eq!(
            place([64, 48], [200, 200], 40),
            Placement {
                x0: 4,
                y0: 8,
                width: 192,
                height: 144
            }
        );
        // Smaller than the image: a fractional scale.
        let p = place([400, 200], [200, 140], 40);
        assert_eq!((p.width, p.height), (200, 100));
    }

    #[test]
    fn a_blit_at_scale_one_copies_the_pixels() {
        let image: Vec<[u8; 3]> = (0..6).map(|i| [i as u8, 10, 20]).collect();
        let mut frame = vec![0u8; 4 * 3 * 3];
        let at = place([3, 2], [3, 3], 1);
        blit(&mut frame, [3, 3], &image, [3, 2], at);
        assert_eq!(&frame[..4], &[0, 10, 20, 255]);
        assert_eq!(&frame[4 * 5..4 * 6], &[5, 10, 20, 255]);
        assert_eq!(&frame[4 * 6..], &[0; 12]);
    }
}
