//! The device film: its buffers, read back into host sums at each block's end (rows split over
//! worker threads), downloaded as float32 for a window, and cleared for the next block.

use super::{AOV_CHANNELS, FILM_CHANNELS, FilmSums, Window, channels, to_fixed, worker_threads};
use crate::error::Result;
use crate::layout::FilmPixel;
use crate::vk::{Buffer, Context};

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
