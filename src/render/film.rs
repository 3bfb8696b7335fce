//! The film: per-pixel sums of every plane (FilmPixel's 24 floats), moved off the device on a
//! fixed grid of sample blocks and accumulated exactly, so that a render split into jobs (sample
//! ranges, pixel windows) and merged is bit-identical to the render in one piece.
//!
//! - The device sums the samples of one block in float32: block k holds samples
//!   [256 k, min(256 (k + 1), N)) of an N-sample render, counted from sample 0 whatever the job,
//!   each dispatch taking them in index order. float32 sums of a block never depend on how the
//!   render was split, so long as the whole block was rendered.
//! - At each block's end its sums leave the device and are added here in fixed point (i128):
//!   integer addition is associative, so the total does not depend on the order in which blocks
//!   or jobs are added. The unit is 2^-64 (every float32 from 5e-13 up is exact in it; the range
//!   reaches 9e18, radiance 1e8 over 2^36 samples), and 2^-24 for the sums of squares (range
//!   1e31: squared radiance 1e8 over 2^46 samples). Each block sum is rounded to it once,
//!   deterministically; sums saturate rather than wrap.
//! - A job whose sample range starts or ends inside a block renders that whole block (so that its
//!   float32 sums are the ones a render in one piece makes) and keeps it apart as a
//!   [`BoundaryBlock`]; merging takes each boundary block once, from whichever job has it.

use crate::error::Result;
use crate::layout::FilmPixel;
use crate::output::Film;
use crate::vk::{Buffer, Context};

/// Samples per block of the film grid (and the most one invocation takes per dispatch).
pub const FILM_BLOCK: u32 = 256;
/// Floats per pixel in the device film (FilmPixel).
pub const FILM_CHANNELS: usize = 24;
/// Fixed-point unit of channel c's exact sums: 2^-fixed_bits(c) (the squares, FilmPixel's
/// beauty_sq.rgb, get a coarser unit for their range).
pub fn fixed_bits(c: usize) -> i32 {
    if (4..7).contains(&c) { 24 } else { 64 }
}

/// A float32 block sum of channel `c` in fixed point (NaN reads 0; out of range saturates).
pub fn to_fixed(v: f32, c: usize) -> i128 {
    let x = (f64::from(v) * 2f64.powi(fixed_bits(c))).round();
    if x.is_nan() { 0 } else { x as i128 }
}

/// A fixed-point sum of channel `c` as f64.
pub fn from_fixed(s: i128, c: usize) -> f64 {
    s as f64 * 2f64.powi(-fixed_bits(c))
}

/// The block of sample `s` in an `n`-sample render: [start, end).
pub fn block_of(s: u32, n: u32) -> (u32, u32) {
    let start = s - s % FILM_BLOCK;
    (start, (start + FILM_BLOCK).min(n))
}

/// A rectangle of pixels [x0, x1) x [y0, y1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Window {
    pub fn full(width: u32, height: u32) -> Window {
        Window {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }
    pub fn pixels(&self) -> usize {
        self.width() as usize * self.height() as usize
    }
    pub fn overlaps(&self, o: &Window) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
}

impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// The float32 sums of one whole block [start, end) of which a job owns only part.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryBlock {
    pub start: u32,
    pub end: u32,
    /// Window pixels, row-major.
    pub sums: Vec<[f32; FILM_CHANNELS]>,
}

/// Exact sums of a job: its pixel window, the blocks it owns wholly (fixed point), and the blocks
/// it owns partly (float32, whole).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSums {
    pub window: Window,
    pub sums: Vec<[i128; FILM_CHANNELS]>,
    pub boundary: Vec<BoundaryBlock>,
}

impl FilmSums {
    pub fn new(window: Window) -> FilmSums {
        FilmSums {
            window,
            sums: vec![[0; FILM_CHANNELS]; window.pixels()],
            boundary: Vec::new(),
        }
    }

    /// Adds float32 block sums (window pixels) exactly.
    pub fn add_block(&mut self, block: &[[f32; FILM_CHANNELS]]) {
        for (acc, p) in self.sums.iter_mut().zip(block) {
            for (c, (a, x)) in acc.iter_mut().zip(p).enumerate() {
                *a = a.saturating_add(to_fixed(*x, c));
            }
        }
    }

    /// Adds another job's fixed-point sums of the same window.
    pub fn add_sums(&mut self, other: &[[i128; FILM_CHANNELS]]) {
        for (acc, p) in self.sums.iter_mut().zip(other) {
            for (a, x) in acc.iter_mut().zip(p) {
                *a = a.saturating_add(*x);
            }
        }
    }

    /// The sums with the boundary blocks added: every sample this job rendered.
    pub fn with_boundary(&self) -> FilmSums {
        let mut all = FilmSums {
            window: self.window,
            sums: self.sums.clone(),
            boundary: Vec::new(),
        };
        for b in &self.boundary {
            all.add_block(&b.sums);
        }
        all
    }
}

/// Reads the device film's pixels inside `window` (the device film covers the whole frame of
/// `width` pixels a row).
pub fn download_window(
    ctx: &Context,
    film: &Buffer,
    width: u32,
    window: Window,
) -> Result<Vec<[f32; FILM_CHANNELS]>> {
    let rows = window.y1 as usize * width as usize;
    let raw: Vec<FilmPixel> = ctx.download(film, rows)?;
    let mut out = Vec::with_capacity(window.pixels());
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            let p = &raw[(y * width + x) as usize];
            out.push(*bytemuck::cast_ref::<FilmPixel, [f32; FILM_CHANNELS]>(p));
        }
    }
    Ok(out)
}

/// Clears the device film for the next block.
pub fn clear(ctx: &Context, film: &Buffer) -> Result<()> {
    ctx.one_shot(|cmd| {
        // SAFETY: the film buffer is alive until the wait.
        unsafe {
            ctx.device
                .cmd_fill_buffer(cmd, film.buffer, 0, ash::vk::WHOLE_SIZE, 0)
        }
    })
}

/// A film resolved from its sums after `spp` samples per pixel.
pub struct Resolved {
    pub film: Film,
    pub spp: u32,
    /// Means of the even- and odd-numbered samples (the half-buffers).
    pub even: Vec<[f32; 3]>,
    pub odd: Vec<[f32; 3]>,
    pub non_finite_samples: u64,
    /// Camera samples whose direct lighting the firefly clamp reduced.
    pub clamped_samples: u64,
    /// Rays traced (camera and shadow rays).
    pub rays: u64,
}

/// Beauty, emission, albedo and normal are averaged over all samples (misses count as 0, as
/// denoisers expect); Z over the samples that hit (+inf where none did); Variance is the variance
/// of the pixel mean, s² / n. `sums` are the window's pixels, `width` x `height`.
pub fn resolve(sums: &[[i128; FILM_CHANNELS]], width: u32, height: u32, spp: u32) -> Resolved {
    let mut film = Film::new(width, height);
    let n = f64::from(spp);
    let n_even = f64::from(spp.div_ceil(2));
    let n_odd = f64::from(spp / 2);
    let mut variance = vec![[0.0f32; 3]; sums.len()];
    let mut even = vec![[0.0f32; 3]; sums.len()];
    let mut odd = vec![[0.0f32; 3]; sums.len()];
    let (mut non_finite, mut clamped, mut rays) = (0u64, 0u64, 0u64);
    // Offsets of the FilmPixel members in the flattened sums.
    const BEAUTY: usize = 0;
    const BEAUTY_SQ: usize = 4;
    const ALBEDO: usize = 8;
    const NORMAL: usize = 12;
    const EMISSION: usize = 16;
    const BEAUTY_ODD: usize = 20;
    for (i, s) in sums.iter().enumerate() {
        let p: [f64; FILM_CHANNELS] = std::array::from_fn(|k| from_fixed(s[k], k));
        for c in 0..3 {
            let sum = p[BEAUTY + c];
            let mean = sum / n;
            film.beauty[i][c] = mean as f32;
            film.albedo[i][c] = (p[ALBEDO + c] / n) as f32;
            film.normal[i][c] = (p[NORMAL + c] / n) as f32;
            film.emission[i][c] = (p[EMISSION + c] / n) as f32;
            if spp > 1 {
                let m2 = p[BEAUTY_SQ + c] / n;
                let sample_var = (m2 - mean * mean).max(0.0) * n / (n - 1.0);
                variance[i][c] = (sample_var / n) as f32;
                let o = p[BEAUTY_ODD + c];
                even[i][c] = ((sum - o) / n_even) as f32;
                odd[i][c] = (o / n_odd) as f32;
            }
        }
        let hits = p[ALBEDO + 3];
        film.depth[i] = if hits > 0.0 {
            (p[NORMAL + 3] / hits) as f32
        } else {
            f32::INFINITY
        };
        non_finite += p[EMISSION + 3] as u64;
        clamped += p[BEAUTY + 3] as u64;
        rays += p[BEAUTY_SQ + 3] as u64;
    }
    film.variance = Some(variance);
    Resolved {
        film,
        spp,
        even,
        odd,
        non_finite_samples: non_finite,
        clamped_samples: clamped,
        rays,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_is_exact_for_float32_sums_and_associative() {
        // Every float32 from 2^-41 up is exact in the unit of 2^-64.
        for v in [0.0f32, 1.0, -2.5, 1e-3, 3.0e7, 4.6e-13, 1e16, 1e18] {
            assert_eq!(from_fixed(to_fixed(v, 0), 0), f64::from(v), "{v}");
        }
        assert_eq!(from_fixed(to_fixed(1e30, 5), 5), 1e30f32 as f64);
        let xs = [0.1f32, 1e6, 3.3e-5, 7.0, 1e-9, 2.5e12];
        let a: i128 = xs.iter().map(|&x| to_fixed(x, 0)).sum();
        let b: i128 = xs.iter().rev().map(|&x| to_fixed(x, 0)).sum();
        assert_eq!(a, b);
        assert_eq!(to_fixed(f32::NAN, 0), 0);
    }

    #[test]
    fn blocks_are_counted_from_sample_zero() {
        assert_eq!(block_of(0, 1000), (0, 256));
        assert_eq!(block_of(300, 1000), (256, 512));
        assert_eq!(block_of(999, 1000), (768, 1000));
    }
}
