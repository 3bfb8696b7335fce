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

use crate::error::Result;
use crate::layout::{self, FilmPixel};
mod image;
pub mod memory;

use crate::vk::{Buffer, Context};
pub use image::{AovPlane, FILM_LAYERS, Film};

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

/// The device film of a render: FilmPixel per pixel of the frame and, when the integrator
/// declares AOV planes, the "aovs" buffer of their vec4s ([pixel][plane]).
#[derive(Clone, Copy)]
pub struct DeviceFilm<'a> {
    pub film: &'a Buffer,
    pub aovs: Option<&'a Buffer>,
    /// AOV planes in `aovs` (0 without it).
    pub aov_planes: usize,
    /// The image pixels it covers, row-major (Frame.film_x0, film_y0, film_width; the kernels'
    /// film_slot).
    pub window: Window,
    /// Where reads of the film land on the host, kept from one read to the next (None: a
    /// buffer for each read).
    pub readback: Option<&'a std::sync::Mutex<Option<Buffer>>>,
}

/// The device film as copied to the host: its rows down to the read window's last, FilmPixel's
/// floats a pixel, then each AOV plane's vec4 a pixel (`[pixel][plane]`).
struct Readback<'a> {
    film: &'a [f32],
    aovs: &'a [f32],
    /// The device film's window.
    window: Window,
    /// AOV floats a pixel.
    aov_floats: usize,
}

impl Readback<'_> {
    /// Pixel (x, y)'s FilmPixel floats and AOV floats.
    fn pixel(&self, x: u32, y: u32) -> (&[f32], &[f32]) {
        let w = self.window;
        let i = (y - w.y0) as usize * w.width() as usize + (x - w.x0) as usize;
        let a = self.aov_floats;
        (
            &self.film[i * FILM_CHANNELS..(i + 1) * FILM_CHANNELS],
            &self.aovs[i * a..(i + 1) * a],
        )
    }
}

/// Copies the device film's rows down to `window`'s last into the film's readback buffer (kept
/// from one read to the next, so that a block's commit allocates nothing), clears the device film
/// after the copy when `clear`, and gives `read` what was copied.
fn read_film<R>(
    ctx: &Context,
    film: DeviceFilm,
    window: Window,
    clear: bool,
    read: impl FnOnce(&Readback) -> R,
) -> Result<R> {
    let f = film.window;
    assert!(
        f.x0 <= window.x0 && window.x1 <= f.x1 && f.y0 <= window.y0 && window.y1 <= f.y1,
        "window {window} outside the device film's {f}"
    );
    let rows = (window.y1 - f.y0) as usize * f.width() as usize;
    let aov_floats = AOV_CHANNELS * film.aov_planes;
    let film_bytes = (rows * std::mem::size_of::<FilmPixel>()) as u64;
    let aov_bytes = match film.aovs {
        Some(_) => (rows * aov_floats * 4) as u64,
        None => 0,
    };
    let total = film_bytes + aov_bytes;
    let mut own = None;
    let mut kept = film
        .readback
        .map(|m| m.lock().unwrap_or_else(|p| p.into_inner()));
    let slot: &mut Option<Buffer> = match kept.as_deref_mut() {
        Some(s) => s,
        None => &mut own,
    };
    if total > 0 && slot.as_ref().is_none_or(|b| b.size < total) {
        *slot = None;
        *slot = Some(ctx.create_buffer(
            "film readback",
            total,
            ash::vk::BufferUsageFlags::TRANSFER_DST,
            crate::vk::MemoryLocation::GpuToCpu,
        )?);
    }
    ctx.one_shot(|cmd| {
        // SAFETY: the buffers are alive until the wait; the fill waits for the copy's reads.
        unsafe {
            if let Some(staging) = slot.as_ref().filter(|_| total > 0) {
                let copy = |src: &Buffer, at: u64, size: u64| {
                    if size > 0 {
                        ctx.device.cmd_copy_buffer(
                            cmd,
                            src.buffer,
                            staging.buffer,
                            &[ash::vk::BufferCopy::default().dst_offset(at).size(size)],
                        )
                    }
                };
                copy(film.film, 0, film_bytes);
                if let Some(a) = film.aovs {
                    copy(a, film_bytes, aov_bytes);
                }
                // The copies' writes made visible to the host's reads after the fence.
                let to_host = [ash::vk::MemoryBarrier::default()
                    .src_access_mask(ash::vk::AccessFlags::TRANSFER_WRITE)
                    .dst_access_mask(ash::vk::AccessFlags::HOST_READ)];
                ctx.device.cmd_pipeline_barrier(
                    cmd,
                    ash::vk::PipelineStageFlags::TRANSFER,
                    ash::vk::PipelineStageFlags::HOST,
                    ash::vk::DependencyFlags::empty(),
                    &to_host,
                    &[],
                    &[],
                );
            }
            if clear {
                ctx.barrier(cmd);
                fill_zero(ctx, cmd, film);
            }
        }
    })?;
    let floats: &[f32] = match slot.as_mut().filter(|_| total > 0) {
        Some(staging) => {
            let mapped = staging.mapped().ok_or_else(|| {
                crate::vk::Error::Invalid("readback buffer is not host visible".into())
            })?;
            bytemuck::cast_slice(&mapped[..total as usize])
        }
        None => &[],
    };
    let (film_floats, aovs) = floats.split_at(film_bytes as usize / 4);
    Ok(read(&Readback {
        film: film_floats,
        aovs,
        window: f,
        aov_floats,
    }))
}

/// Reads the device film's pixels inside `window` (within the film's own window), [`channels`]
/// floats a pixel: FilmPixel's, then each AOV plane's vec4.
pub fn download_window(ctx: &Context, film: DeviceFilm, window: Window) -> Result<Vec<f32>> {
    read_film(ctx, film, window, false, |r| {
        let mut out = Vec::with_capacity(window.pixels() * channels(film.aov_planes));
        for y in window.y0..window.y1 {
            for x in window.x0..window.x1 {
                let (p, a) = r.pixel(x, y);
                out.extend_from_slice(p);
                out.extend_from_slice(a);
            }
        }
        out
    })
}

/// Adds the device film's block in `sums`' window to `sums` exactly and clears the device film:
/// a complete block's commit, read where the device copied it (no copy of the block on the
/// host), over threads of whole rows.
pub fn commit_block(ctx: &Context, film: DeviceFilm, sums: &mut FilmSums) -> Result<()> {
    let window = sums.window;
    let channels = sums.channels();
    read_film(ctx, film, window, true, |r| {
        let add_rows = |y0: u32, out: &mut [i128]| {
            let mut k = 0;
            for y in y0.. {
                if k == out.len() {
                    break;
                }
                for x in window.x0..window.x1 {
                    let (p, a) = r.pixel(x, y);
                    let acc = &mut out[k..k + channels];
                    for (c, (s, v)) in acc.iter_mut().zip(p.iter().chain(a)).enumerate() {
                        *s = s.saturating_add(to_fixed(*v, c));
                    }
                    k += channels;
                }
            }
        };
        let row = window.width() as usize * channels;
        let rows = window.height() as usize;
        let threads = worker_threads(window.pixels()).min(rows.max(1));
        if threads <= 1 {
            return add_rows(window.y0, &mut sums.sums);
        }
        let per = rows.div_ceil(threads);
        std::thread::scope(|scope| {
            for (k, chunk) in sums.sums.chunks_mut(per * row).enumerate() {
                let y0 = window.y0 + (k * per) as u32;
                scope.spawn(move || add_rows(y0, chunk));
            }
        });
    })
}

/// Threads for host work over `pixels` pixels: the machine's cores, at most 8, none for fewer
/// than 16384 pixels a thread (a merge adds boundary blocks a pixel at a time: it never asks
/// the system).
fn worker_threads(pixels: usize) -> usize {
    const PIXELS_A_THREAD: usize = 16384;
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    if pixels < 2 * PIXELS_A_THREAD {
        return 1;
    }
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    cores.min(8).min(pixels / PIXELS_A_THREAD).max(1)
}

/// Records zeroing the device film and its AOV planes.
///
/// # Safety
/// `cmd` is recording and the film's buffers outlive its execution.
unsafe fn fill_zero(ctx: &Context, cmd: ash::vk::CommandBuffer, film: DeviceFilm) {
    // SAFETY: the caller's contract.
    unsafe {
        ctx.device
            .cmd_fill_buffer(cmd, film.film.buffer, 0, ash::vk::WHOLE_SIZE, 0);
        if let Some(a) = film.aovs {
            ctx.device
                .cmd_fill_buffer(cmd, a.buffer, 0, ash::vk::WHOLE_SIZE, 0);
        }
    }
}

/// Clears the device film (and its AOV planes) for the next block.
pub fn clear(ctx: &Context, film: DeviceFilm) -> Result<()> {
    // SAFETY: the film buffers are alive until the wait.
    Ok(ctx.one_shot(|cmd| unsafe { fill_zero(ctx, cmd, film) })?)
}

/// A film resolved from its sums after `spp` samples per pixel.
pub struct Resolved {
    pub film: Film,
    pub spp: u32,
    /// Means of the even- and odd-numbered samples (the half-buffers).
    pub even: Vec<[f32; 3]>,
    pub odd: Vec<[f32; 3]>,
    /// Samples each pixel took: `spp`, or fewer where adaptive sampling stopped it.
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
/// where the pixels' counts are not all `spp`. `sums` are the
/// window's pixels, `width` x `height`, with the planes `aov_planes` after FilmPixel's channels.
pub fn resolve(
    sums: &[i128],
    aov_planes: &[String],
    width: u32,
    height: u32,
    spp: u32,
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
    if counts.iter().any(|&c| c != spp) {
        film.samples = Some(counts.iter().map(|&c| c as f32).collect());
    }
    Resolved {
        film,
        spp,
        even,
        odd,
        counts,
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

    /// The conversion from the float's bits equals rounding its f64 product (half away from
    /// zero, saturating), on every kind of float and both scales.
    #[test]
    fn to_fixed_equals_the_rounded_f64_product() {
        let reference = |v: f32, c: usize| -> i128 {
            let x = (f64::from(v) * 2f64.powi(fixed_bits(c))).round();
            if x.is_nan() { 0 } else { x as i128 }
        };
        let mut x = 0x1234_5678_9abc_def0u64;
        let mut values = vec![
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1.5,
            2.5,
            -2.5,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-30,
            3e-8,
            6e-8,
            1.1920929e-7,
        ];
        values.extend((0..4000).map(|_| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            f32::from_bits((x >> 32) as u32)
        }));
        // Ties of both scales: odd multiples of 2^-25 and 2^-65.
        values.extend((0..64).map(|k| (2 * k + 1) as f32 * 2f32.powi(-25)));
        values.extend((0..64).map(|k| (2 * k + 1) as f32 * 2f32.powi(-65)));
        for v in values {
            for c in [0, crate::layout::FilmPixel::BEAUTY_SQ] {
                assert_eq!(
                    to_fixed(v, c),
                    reference(v, c),
                    "{v:e} ({:#x}), channel {c}",
                    v.to_bits()
                );
            }
        }
    }

    #[test]
    fn aov_names_are_exr_layers_of_their_own() {
        assert!(check_aov_names(&["Direct", "IndirectDiffuse", "Reflection", "A_2"]).is_ok());
        assert!(check_aov_names::<&str>(&[]).is_ok());
        for bad in [
            &["direct"][..],
            &["Albedo"],
            &["N"],
            &["Di rect"],
            &[""],
            &["A", "A"],
        ] {
            assert!(check_aov_names(bad).is_err(), "{bad:?}");
        }
        assert_eq!(channels(0), 24);
        assert_eq!(channels(3), 36);
        assert_eq!(fixed_bits(30), 64);
        assert_eq!(fixed_bits(DEPTH_SUM), 24);
    }

    #[test]
    fn blocks_are_counted_from_sample_zero() {
        assert_eq!(block_of(0, 1000), (0, 256));
        assert_eq!(block_of(300, 1000), (256, 512));
        assert_eq!(block_of(999, 1000), (768, 1000));
    }
}
