//! The film: per-pixel sums of every plane (FilmPixel's floats, then 4 per AOV plane that the
//! integrator declares; their count, offsets and names generated from glsl/shared/layout.glsl),
//! moved off the device on a fixed grid of sample blocks and accumulated exactly, so that a render
//! split into jobs (sample ranges, pixel windows) and merged is bit-identical to the render in one
//! piece.
//!
//! - Host sums are flat: pixel-major, [`channels`] values a pixel (FilmPixel's members in order,
//!   then each AOV plane's vec4 from the device's "aovs" buffer, [pixel][plane]).
//! - The device sums the samples of one block in float32: block k holds samples
//!   [256 k, min(256 (k + 1), N)) of an N-sample render, counted from sample 0 whatever the job,
//!   each dispatch taking them in index order. float32 sums of a block never depend on how the
//!   render was split, so long as the whole block was rendered.
//! - At each block's end its sums leave the device and are added here in fixed point (i128):
//!   integer addition is associative, so the total does not depend on the order in which blocks
//!   or jobs are added. The unit is 2^-64 (every float32 from 5e-13 up is exact in it; the range
//!   reaches 9e18, radiance 1e8 over 2^36 samples), and 2^-24 for the sums of squares and of hit
//!   distances (range 1e31: squared radiance 1e8 over 2^46 samples, a distance of 1e20 over
//!   2^36). Each block sum is rounded to it once,
//!   deterministically; sums saturate rather than wrap.
//! - A job whose sample range starts or ends inside a block renders that whole block (so that its
//!   float32 sums are the ones a render in one piece makes) and keeps it apart as a
//!   [`BoundaryBlock`]; merging takes each boundary block once, from whichever job has it.

use crate::layout::{self, FilmPixel};
mod device;
mod image;
pub mod memory;
pub mod split;

pub use device::{DeviceFilm, clear, commit_block, download_window};
pub use image::{AovPlane, FILM_LAYERS, Film};
pub use split::Split;

/// Samples per block of the film grid (and the most one invocation takes per dispatch).
pub const FILM_BLOCK: u32 = 256;
/// The most samples per pixel an image may have: sample indices are 32-bit, and the end of the
/// last block, a multiple of [`FILM_BLOCK`], must be one too (2^32 - 256).
pub const MAX_SPP: u32 = u32::MAX - (FILM_BLOCK - 1);

/// Why `spp` cannot be an image's sample count, if it cannot.
pub fn check_spp(spp: u32) -> std::result::Result<(), String> {
    if spp == 0 {
        Err("samples per pixel must be at least 1".into())
    } else if spp > MAX_SPP {
        Err(format!(
            "samples per pixel must be at most {MAX_SPP} (32-bit sample indices in blocks of \
             {FILM_BLOCK}), got {spp}"
        ))
    } else {
        Ok(())
    }
}
/// Floats per pixel in the device film (FilmPixel).
pub const FILM_CHANNELS: usize = FilmPixel::CHANNELS;
/// Floats per AOV plane and pixel (a vec4 of the "aovs" buffer: rgb sums, w unused).
pub const AOV_CHANNELS: usize = layout::AOV_CHANNELS as usize;

/// Channels per pixel of a film with `aov_planes` AOV planes.
pub fn channels(aov_planes: usize) -> usize {
    FILM_CHANNELS + AOV_CHANNELS * aov_planes
}

/// FilmPixel's normal.w, the sum of hit distances.
const DEPTH_SUM: usize = FilmPixel::NORMAL + 3;

/// Fixed-point unit of channel c's exact sums: 2^-fixed_bits(c). The squares (FilmPixel's
/// beauty_sq.rgb) and the hit distances get a coarser unit for their range (a camera inside a
/// sphere of radius 1e20 sums distances of 1e20); AOV planes have the beauty's.
pub fn fixed_bits(c: usize) -> i32 {
    if (FilmPixel::BEAUTY_SQ..FilmPixel::BEAUTY_SQ + 3).contains(&c) || c == DEPTH_SUM {
        24
    } else {
        64
    }
}

/// Why `names` cannot be a film's AOV planes, if they cannot: each is a layer name of the final
/// EXR (`<name>.R/G/B`), so it starts with an ASCII capital, continues with ASCII letters, digits
/// or `_`, is not one of the film's own layers (Albedo, N, Emission, Variance) and is not given
/// twice.
pub fn check_aov_names<S: AsRef<str>>(names: &[S]) -> std::result::Result<(), String> {
    for (k, name) in names.iter().enumerate() {
        let name = name.as_ref();
        let mut chars = name.chars();
        let well_formed = chars.next().is_some_and(|c| c.is_ascii_uppercase())
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
            && name.len() <= 64;
        if !well_formed {
            return Err(format!(
                "AOV plane {name:?} is not a layer name (an ASCII capital, then letters, digits or _; at most 64)"
            ));
        }
        if FILM_LAYERS.contains(&name) {
            return Err(format!("AOV plane {name:?} is a layer of the film itself"));
        }
        if names[..k].iter().any(|n| n.as_ref() == name) {
            return Err(format!("AOV plane {name:?} is given twice"));
        }
    }
    Ok(())
}

/// A float32 block sum of channel `c` in fixed point (NaN reads 0; out of range saturates).
#[inline]
pub fn to_fixed(v: f32, c: usize) -> i128 {
    // round(v 2^fixed_bits(c)), half away from zero, from v's bits: v = m 2^e with an integer
    // mantissa m < 2^24, so the product is m shifted (an f64 -> i128 conversion is a library
    // call, and this is the block commit's inner loop: 11 M channels a 640x480 block).
    let bits = v.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32;
    let negative = bits >> 31 == 1;
    if exp == 0xff {
        return match (bits & 0x7f_ffff != 0, negative) {
            (true, _) => 0,
            (false, false) => i128::MAX,
            (false, true) => i128::MIN,
        };
    }
    let (m, e) = if exp == 0 {
        (bits & 0x7f_ffff, -149)
    } else {
        ((bits & 0x7f_ffff) | 0x80_0000, exp - 150)
    };
    let shift = e + fixed_bits(c);
    let magnitude = if shift >= 104 {
        // m 2^shift >= 2^127 for a normal m (a subnormal never shifts this far).
        return if negative { i128::MIN } else { i128::MAX };
    } else if shift >= 0 {
        i128::from(m) << shift
    } else if shift > -40 {
        // Half away from zero on the magnitude.
        i128::from((u64::from(m) + (1u64 << (-shift - 1))) >> -shift)
    } else {
        0
    };
    if negative { -magnitude } else { magnitude }
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
    /// Window pixels, row-major, [`FilmSums::channels`] floats each.
    pub sums: Vec<f32>,
}

/// Exact sums of a job: its pixel window, the blocks it owns wholly (fixed point), and the blocks
/// it owns partly (float32, whole).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSums {
    pub window: Window,
    /// The integrator's AOV planes: channels [`FILM_CHANNELS`] + 4 k .. + 4 of a pixel are plane
    /// k's (rgb sums; the fourth is unused).
    pub aov_planes: Vec<String>,
    /// Window pixels, row-major, [`FilmSums::channels`] values each.
    pub sums: Vec<i128>,
    pub boundary: Vec<BoundaryBlock>,
}

/// `n` zero sums, in transparent huge pages where the kernel offers them on request: the first
/// block's commit touches every page of the sums (700 MB at 1280x960 with 3 AOV planes), and in
/// 4 KiB pages its faults, each a copy of the zero page with a TLB flush on every core the
/// threads run on, took 1.4 of its 1.6 s on lavapipe's machine.
pub fn zeroed_sums(n: usize) -> Vec<i128> {
    let v = vec![0i128; n];
    const HUGE: usize = 2 << 20;
    let bytes = n * std::mem::size_of::<i128>();
    if bytes >= 4 * HUGE {
        let start = v.as_ptr() as usize;
        let aligned = start.next_multiple_of(HUGE);
        let len = (start + bytes).saturating_sub(aligned) / HUGE * HUGE;
        // SAFETY: [aligned, aligned + len) lies inside v's allocation, which is not yet touched
        // (calloc maps fresh zero pages); the advice changes how pages come, not what they hold.
        unsafe { libc::madvise(aligned as *mut libc::c_void, len, libc::MADV_HUGEPAGE) };
    }
    v
}

impl FilmSums {
    pub fn new(window: Window, aov_planes: Vec<String>) -> FilmSums {
        FilmSums {
            window,
            sums: zeroed_sums(window.pixels() * channels(aov_planes.len())),
            aov_planes,
            boundary: Vec::new(),
        }
    }

    /// Values per pixel: [`FILM_CHANNELS`], and 4 per AOV plane.
    pub fn channels(&self) -> usize {
        channels(self.aov_planes.len())
    }

    /// Adds float32 block sums (window pixels, [`FilmSums::channels`] each) exactly.
    pub fn add_block(&mut self, block: &[f32]) {
        let channels = self.channels();
        add_block(&mut self.sums, block, channels);
    }

    /// Adds another job's fixed-point sums of the same window and planes.
    pub fn add_sums(&mut self, other: &[i128]) {
        for (a, x) in self.sums.iter_mut().zip(other) {
            *a = a.saturating_add(*x);
        }
    }

    /// The fixed-point sums of every sample this job rendered: borrowed when it has no boundary
    /// blocks (a render in one piece), so that resolving does not copy them (16 bytes a channel
    /// and pixel).
    pub fn all_sums(&self) -> std::borrow::Cow<'_, [i128]> {
        if self.boundary.is_empty() {
            std::borrow::Cow::Borrowed(&self.sums)
        } else {
            std::borrow::Cow::Owned(self.with_boundary().sums)
        }
    }

    /// The sums with the boundary blocks added: every sample this job rendered.
    pub fn with_boundary(&self) -> FilmSums {
        let mut all = FilmSums {
            window: self.window,
            aov_planes: self.aov_planes.clone(),
            sums: self.sums.clone(),
            boundary: Vec::new(),
        };
        for b in &self.boundary {
            all.add_block(&b.sums);
        }
        all
    }
}

/// Adds float32 sums to fixed-point ones, both `channels` values a pixel, exactly.
pub fn add_block(sums: &mut [i128], block: &[f32], channels: usize) {
    let add = |sums: &mut [i128], block: &[f32]| {
        for (acc, p) in sums
            .chunks_exact_mut(channels)
            .zip(block.chunks_exact(channels))
        {
            for (c, (a, x)) in acc.iter_mut().zip(p).enumerate() {
                *a = a.saturating_add(to_fixed(*x, c));
            }
        }
    };
    // Whole pixels to each thread (the sums are exact: the split changes nothing).
    let pixels = sums.len() / channels.max(1);
    let threads = worker_threads(pixels);
    if threads == 1 {
        return add(sums, block);
    }
    let per = pixels.div_ceil(threads) * channels;
    std::thread::scope(|scope| {
        for (s, b) in sums.chunks_mut(per).zip(block.chunks(per)) {
            scope.spawn(move || add(s, b));
        }
    });
}

/// Threads for host work over `pixels` pixels: the machine's cores, at most 8, none for fewer
/// than 16384 pixels a thread (a merge adds boundary blocks a pixel at a time: it never asks
/// the system).
pub(crate) fn worker_threads(pixels: usize) -> usize {
    const PIXELS_A_THREAD: usize = 16384;
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    if pixels < 2 * PIXELS_A_THREAD {
        return 1;
    }
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    cores.min(8).min(pixels / PIXELS_A_THREAD).max(1)
}

/// A film resolved from its sums after `spp` samples per pixel.
pub struct Resolved {
    pub film: Film,
    pub spp: u32,
    /// Means of the even- and odd-numbered samples (the half-buffers) where `split`, else the
    /// pixel's mean.
    pub even: Vec<[f32; 3]>,
    pub odd: Vec<[f32; 3]>,
    /// Whether each pixel's samples alternate between two sequences ([`Split`]): where its
    /// half-buffers estimate the error.
    pub split: Vec<bool>,
    /// Samples each pixel took: `spp` (twice that at a witness pixel, [`Split`]), or fewer where
    /// adaptive sampling stopped it.
    pub counts: Vec<u32>,
    pub non_finite_samples: u64,
    /// Camera samples whose direct lighting the firefly clamp reduced.
    pub clamped_samples: u64,
    /// Rays traced (camera and shadow rays).
    pub rays: u64,
}

/// Beauty, emission, albedo and normal are averaged over all of a pixel's samples (misses count
/// as 0, as denoisers expect; `spp`, or fewer where adaptive sampling stopped the pixel); Z over
/// the samples that hit (+inf where none did); Variance is the variance of the pixel mean,
/// s² / n; each AOV plane is averaged over all samples too. The film gets its SampleCount plane
/// where a pixel's count is not what `split` gives it for `spp`. `sums` are the window's pixels,
/// `width` x `height` at `origin` in the image, with the planes `aov_planes` after FilmPixel's
/// channels.
pub fn resolve(
    sums: &[i128],
    aov_planes: &[String],
    (width, height): (u32, u32),
    spp: u32,
    split: Split,
    origin: (u32, u32),
) -> Resolved {
    let mut film = Film::new(width, height);
    let channels = channels(aov_planes.len());
    film.aovs = aov_planes
        .iter()
        .map(|name| AovPlane {
            name: name.clone(),
            rgb: vec![[0.0; 3]; film.pixel_count()],
        })
        .collect();
    let mut counts = vec![0u32; film.pixel_count()];
    let mut variance = vec![[0.0f32; 3]; film.pixel_count()];
    let mut even = vec![[0.0f32; 3]; film.pixel_count()];
    let mut odd = vec![[0.0f32; 3]; film.pixel_count()];
    let splits = split.window(origin.0, origin.1, width, height);
    let (mut non_finite, mut clamped, mut rays) = (0u64, 0u64, 0u64);
    // Offsets of the FilmPixel members in the flattened sums.
    const BEAUTY: usize = FilmPixel::BEAUTY;
    const BEAUTY_SQ: usize = FilmPixel::BEAUTY_SQ;
    const ALBEDO: usize = FilmPixel::ALBEDO;
    const NORMAL: usize = FilmPixel::NORMAL;
    const EMISSION: usize = FilmPixel::EMISSION;
    const BEAUTY_ODD: usize = FilmPixel::BEAUTY_ODD;
    for (i, s) in sums.chunks_exact(channels).enumerate() {
        let p: [f64; FILM_CHANNELS] = std::array::from_fn(|k| from_fixed(s[k], k));
        let count = p[BEAUTY_ODD + 3] as u32;
        counts[i] = count;
        // A pixel of no samples resolves to zeros, never to NaN.
        let n = f64::from(count.max(1));
        let n_even = f64::from(count.div_ceil(2).max(1));
        let n_odd = f64::from((count / 2).max(1));
        for (k, plane) in film.aovs.iter_mut().enumerate() {
            let at = FILM_CHANNELS + AOV_CHANNELS * k;
            for c in 0..3 {
                plane.rgb[i][c] = (from_fixed(s[at + c], at + c) / n) as f32;
            }
        }
        for c in 0..3 {
            let sum = p[BEAUTY + c];
            let mean = sum / n;
            film.beauty[i][c] = mean as f32;
            film.albedo[i][c] = (p[ALBEDO + c] / n) as f32;
            film.normal[i][c] = (p[NORMAL + c] / n) as f32;
            film.emission[i][c] = (p[EMISSION + c] / n) as f32;
            if count > 1 {
                let m2 = p[BEAUTY_SQ + c] / n;
                let sample_var = (m2 - mean * mean).max(0.0) * n / (n - 1.0);
                variance[i][c] = (sample_var / n) as f32;
                if splits[i] {
                    let o = p[BEAUTY_ODD + c];
                    even[i][c] = ((sum - o) / n_even) as f32;
                    odd[i][c] = (o / n_odd) as f32;
                } else {
                    even[i][c] = mean as f32;
                    odd[i][c] = mean as f32;
                }
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
    // Counts other than the split's own (a witness pixel twice the render's samples): adaptive.
    if counts != split.counts(origin.0, origin.1, width, height, spp) {
        film.samples = Some(counts.iter().map(|&c| c as f32).collect());
    }
    Resolved {
        film,
        spp,
        even,
        odd,
        split: splits,
        counts,
        non_finite_samples: non_finite,
        clamped_samples: clamped,
        rays,
    }
}

#[cfg(test)]
mod tests;
