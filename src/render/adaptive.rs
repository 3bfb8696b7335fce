//! Adaptive pixel sampling (`--noise-threshold`): each pixel stops at the sample count at which
//! its estimated relative error reaches the target (docs/adaptive-sampling.md).
//!
//! A pilot of `min_spp` samples per pixel, with a seed of its own and left out of the image,
//! estimates each pixel's relMSE from its half-buffers (the error of its stratified samples, not
//! the s² / n of independent ones, which is 10x higher on scenes/bench/dome.json). A pixel's
//! estimate v is the larger of its own and its eight neighbours' mean (the neighbours steady the
//! estimate where the noise is smooth; its own catches what is noisy in it alone, a highlight a
//! pixel wide); scaled as 1/n, it reaches T² at n = min_spp · v / T², rounded up to a power of
//! two (whole (0,2)-nets of the camera samples) and capped by `--spp`.
//!
//! The pilot's samples are independent of the image's, so a pixel's count is independent of the
//! samples it takes and the image stays unbiased; a rule that read the image's own samples
//! would stop early exactly where they happened to agree. The pilot is deterministic, so every
//! job of a split render decides the same counts (a crop renders the pilot over its window and
//! the ring of pixels around it) and jobs merge bit-identically.

use crate::film::{self, Window};
use crate::metrics::RELMSE_EPSILON;

/// The target and the first samples of adaptive sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseThreshold {
    /// Relative RMS error each pixel aims at (its relMSE T²).
    pub error: f64,
    /// Samples every pixel takes before counts are decided: a power of two, 2 to 128.
    pub min_spp: u32,
}

impl NoiseThreshold {
    pub const DEFAULT_MIN_SPP: u32 = 16;

    /// Why it cannot drive a render of at most `spp` samples per pixel, if it cannot.
    pub fn check(&self, spp: u32) -> std::result::Result<(), String> {
        if !(self.error.is_finite() && self.error > 0.0) {
            return Err(format!(
                "--noise-threshold must be a positive relative error (0.01 for 1%), got {}",
                self.error
            ));
        }
        if !(self.min_spp.is_power_of_two() && (2..=128).contains(&self.min_spp)) {
            return Err(format!(
                "--min-spp must be a power of two from 2 to 128, got {}",
                self.min_spp
            ));
        }
        if spp <= self.min_spp {
            return Err(format!(
                "--noise-threshold needs --spp (the most samples a pixel takes) above --min-spp \
                 ({}), got {spp}",
                self.min_spp
            ));
        }
        Ok(())
    }

    /// The sample count of a pixel whose neighbours' largest relative variance of the mean after
    /// `min_spp` samples is `v`: a power of two from `min_spp`, at most `cap`.
    pub fn count(&self, v: f64, cap: u32) -> u32 {
        let want = f64::from(self.min_spp) * v / (self.error * self.error);
        // NaN (no estimate) and anything past the cap take the cap.
        if want.is_nan() || want > f64::from(cap) {
            return cap;
        }
        let n = (want.ceil() as u32).max(self.min_spp);
        n.checked_next_power_of_two().unwrap_or(cap).min(cap)
    }
}

/// The pilot's seed for a render of `seed`: streams of their own (the camera samples hash the
/// seed, so any other seed gives independent samples).
pub fn pilot_seed(seed: u64) -> u64 {
    seed ^ 0x5851_f42d_4c95_7f2d
}

/// The window grown by one pixel on every side, within a `width` x `height` image: the pixels
/// whose first samples decide the window's counts.
pub fn ring(window: Window, width: u32, height: u32) -> Window {
    Window {
        x0: window.x0.saturating_sub(1),
        y0: window.y0.saturating_sub(1),
        x1: (window.x1 + 1).min(width),
        y1: (window.y1 + 1).min(height),
    }
}

/// Each image pixel's end sample (row-major, `width` x `height`): the counts of `window`'s
/// pixels from the pilot over `ring` (its film sums, [`film::resolve`]d); other pixels keep
/// `u32::MAX` (the image renders only the window).
pub fn pixel_ends(
    t: &NoiseThreshold,
    first: &film::Resolved,
    ring: Window,
    window: Window,
    (width, height): (u32, u32),
    cap: u32,
) -> Vec<u32> {
    // Each ring pixel's relMSE estimated from its half-buffers (crate::metrics::estimated_relmse):
    // unlike the Variance plane (s² / n, the error of independent samples) it measures the
    // error of the camera samples as they are, stratified (10x lower on scenes/bench/dome.json).
    let n = f64::from(t.min_spp);
    let scale = 1.0 / (n * (2.0 / (n / 2.0)));
    let v: Vec<f64> = (0..first.film.beauty.len())
        .map(|i| {
            let (m, e, o) = (first.film.beauty[i], first.even[i], first.odd[i]);
            (0..3)
                .map(|c| {
                    let d = f64::from(e[c]) - f64::from(o[c]);
                    d * d * scale / (f64::from(m[c]).powi(2) + RELMSE_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect();
    let rw = ring.width() as i64;
    let at = |x: i64, y: i64| -> Option<f64> {
        let (lx, ly) = (x - i64::from(ring.x0), y - i64::from(ring.y0));
        (lx >= 0 && ly >= 0 && lx < rw && ly < i64::from(ring.height()))
            .then(|| v[(ly * rw + lx) as usize])
    };
    let mut ends = vec![u32::MAX; width as usize * height as usize];
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            // The neighbours' mean: each estimate alone is one squared difference (a scaled χ²
            // of 3 degrees at most), their mean the local error level.
            let (mut sum, mut k) = (0.0f64, 0u32);
            for (dx, dy) in NEIGHBOURS {
                if let Some(q) = at(i64::from(x) + dx, i64::from(y) + dy) {
                    sum += q;
                    k += 1;
                }
            }
            let own = at(i64::from(x), i64::from(y)).expect("the ring holds the window");
            let local = if k == 0 { own } else { sum / f64::from(k) };
            // NaN (never expected: non-finite samples count as 0) takes the cap.
            let v = if own.is_nan() || local.is_nan() {
                f64::NAN
            } else {
                own.max(local)
            };
            ends[(y * width + x) as usize] = t.count(v, cap);
        }
    }
    ends
}

const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_powers_of_two_between_the_minimum_and_the_cap() {
        let t = NoiseThreshold {
            error: 0.1,
            min_spp: 16,
        };
        // v = T² reaches the target at the minimum; 4 T² at 4 x the minimum.
        assert_eq!(t.count(0.0, 1000), 16);
        assert_eq!(t.count(0.01, 1000), 16);
        assert_eq!(t.count(0.04, 1000), 64);
        assert_eq!(t.count(0.041, 1000), 128);
        assert_eq!(t.count(10.0, 1000), 1000);
        assert_eq!(t.count(f64::INFINITY, 1000), 1000);
        assert_eq!(t.count(f64::NAN, 1000), 1000);
        assert_eq!(t.count(1e30, u32::MAX - 255), u32::MAX - 255);
    }

    #[test]
    fn settings_are_checked() {
        let ok = NoiseThreshold {
            error: 0.05,
            min_spp: 16,
        };
        assert!(ok.check(17).is_ok());
        assert!(ok.check(16).unwrap_err().contains("--spp"));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = NoiseThreshold { error: bad, ..ok }.check(64).unwrap_err();
            assert!(e.contains("--noise-threshold"), "{e}");
        }
        for bad in [0, 1, 3, 256] {
            let e = NoiseThreshold { min_spp: bad, ..ok }
                .check(1024)
                .unwrap_err();
            assert!(e.contains("--min-spp"), "{e}");
        }
    }

    #[test]
    fn the_ring_grows_a_window_by_a_pixel_within_the_image() {
        let w = Window {
            x0: 0,
            y0: 3,
            x1: 5,
            y1: 8,
        };
        let r = ring(w, 5, 10);
        assert_eq!((r.x0, r.y0, r.x1, r.y1), (0, 2, 5, 9));
    }
}
