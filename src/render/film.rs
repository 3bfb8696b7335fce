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

pub fn download_and_resolve(
    ctx: &Context,
    film: &Buffer,
    w: u32,
    h: u32,
    spp: u32,
) -> Result<Resolved> {
    let raw: Vec<FilmPixel> = ctx.download(film, w as usize * h as usize)?;
    Ok(resolve(&raw, w, h, spp))
}

/// Beauty, emission, albedo and normal are averaged over all samples (misses count as 0, as
/// denoisers expect); Z over the samples that hit (+inf where none did); Variance is the variance
/// of the pixel mean, s² / n.
pub fn resolve(raw: &[FilmPixel], w: u32, h: u32, spp: u32) -> Resolved {
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
    for (i, p) in raw.iter().enumerate() {
        for c in 0..3 {
            let sum = f64::from(p.beauty[c]);
            let mean = sum / n;
            film.beauty[i][c] = mean as f32;
            film.albedo[i][c] = (f64::from(p.albedo[c]) / n) as f32;
            film.normal[i][c] = (f64::from(p.normal[c]) / n) as f32;
            film.emission[i][c] = (f64::from(p.emission[c]) / n) as f32;
            if spp > 1 {
                let m2 = f64::from(p.beauty_sq[c]) / n;
                let sample_var = (m2 - mean * mean).max(0.0) * n / (n - 1.0);
                variance[i][c] = (sample_var / n) as f32;
                let o = f64::from(p.beauty_odd[c]);
                even[i][c] = ((sum - o) / n_even) as f32;
                odd[i][c] = (o / n_odd) as f32;
            }
        }
        let hits = p.albedo[3];
        film.depth[i] = if hits > 0.0 {
            p.normal[3] / hits
        } else {
            f32::INFINITY
        };
        non_finite += p.emission[3] as u64;
        clamped += p.beauty[3] as u64;
        rays += p.beauty_sq[3] as u64;
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
