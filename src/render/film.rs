//! Film readback: per-pixel sums → means, AOVs, variance and the two half-buffers.

use crate::error::Result;
use crate::layout::FilmPixel;
use crate::output::Film;
use crate::vk::{Buffer, Context};

/// A film read back after `spp` samples per pixel.
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

/// The film's sums in float64 on the host. The GPU film holds float32 sums of the samples since
/// the last [`HostFilm::flush`], which moves them here and clears it: float32 sums of many samples
/// round systematically (3.2e-4 low after 32768 samples of a constant pixel), short ones do not.
pub struct HostFilm {
    sums: Vec<[f64; 24]>,
}

impl HostFilm {
    pub fn new(pixels: usize) -> HostFilm {
        HostFilm {
            sums: vec![[0.0; 24]; pixels],
        }
    }

    pub fn flush(&mut self, ctx: &Context, film: &Buffer) -> Result<()> {
        let raw: Vec<FilmPixel> = ctx.download(film, self.sums.len())?;
        for (acc, p) in self.sums.iter_mut().zip(&raw) {
            let v: &[f32; 24] = bytemuck::cast_ref(p);
            for (a, x) in acc.iter_mut().zip(v) {
                *a += f64::from(*x);
            }
        }
        ctx.one_shot(|cmd| {
            // SAFETY: the film buffer is alive until the wait.
            unsafe {
                ctx.device
                    .cmd_fill_buffer(cmd, film.buffer, 0, ash::vk::WHOLE_SIZE, 0)
            }
        })
    }
}

/// Beauty, emission, albedo and normal are averaged over all samples (misses count as 0, as
/// denoisers expect); Z over the samples that hit (+inf where none did); Variance is the variance
/// of the pixel mean, s² / n.
pub fn resolve(host: &HostFilm, w: u32, h: u32, spp: u32) -> Resolved {
    let raw = &host.sums;
    let mut film = Film::new(w, h);
    let n = f64::from(spp);
    let n_even = f64::from(spp.div_ceil(2));
    let n_odd = f64::from(spp / 2);
    let mut variance = vec![[0.0f32; 3]; raw.len()];
    let mut even = vec![[0.0f32; 3]; raw.len()];
    let mut odd = vec![[0.0f32; 3]; raw.len()];
    let mut non_finite = 0u64;
    let mut clamped = 0u64;
    let mut rays = 0u64;
    // Offsets of the FilmPixel members in the flattened sums.
    const BEAUTY: usize = 0;
    const BEAUTY_SQ: usize = 4;
    const ALBEDO: usize = 8;
    const NORMAL: usize = 12;
    const EMISSION: usize = 16;
    const BEAUTY_ODD: usize = 20;
    for (i, p) in raw.iter().enumerate() {
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
