//! Adaptive pixel sampling: a pilot decides each pixel's count, by a noise threshold
//! (`--noise-threshold`: each pixel stops where its estimated relative error reaches the target)
//! or at a budget (`--adaptive`: the rays of N samples a pixel, spread as the pixels' noise and
//! cost) (docs/adaptive-sampling.md).
//!
//! The pilot, `min_spp` samples per pixel with a seed of its own and left out of the image,
//! estimates each pixel's relMSE from its half-buffers (the error of its stratified samples, not
//! the s² / n of independent ones, which is 10x higher on scenes/bench/dome.json). A pixel's
//! estimate v is the larger of its own and its eight neighbours' mean (the neighbours steady the
//! estimate where the noise is smooth; its own catches what is noisy in it alone, a highlight a
//! pixel wide). With a threshold, scaled as 1/n, v reaches T² at n = min_spp · v / T², rounded up
//! to a power of two (whole (0,2)-nets of the camera samples) and capped by `--spp`; at a budget
//! the counts follow sqrt(v / c) ([`spread`]).
//!
//! The pilot's samples are independent of the image's, so a pixel's count is independent of the
//! samples it takes and the image stays unbiased; a rule that read the image's own samples
//! would stop early exactly where they happened to agree. The pilot is deterministic, so every
//! job of a split render decides the same counts (it renders the pilot over [`pilot_window`])
//! and jobs merge bit-identically.

use crate::film::{self, Window};
use crate::metrics::RELMSE_EPSILON;

/// What adaptive sampling aims at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Each pixel stops when its estimated relative RMS error reaches this (relMSE T²).
    Threshold(f64),
    /// The pixels' samples cost (in rays) what this many samples a pixel would, spread as
    /// sqrt(v / c) (v the estimated variance, c the cost of a sample): the spread that minimises
    /// the image's relMSE for that cost.
    Mean(u32),
}

/// The target and the pilot of adaptive sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    pub target: Target,
    /// Samples of the pilot every pixel takes before counts are decided: a power of two, 2 to
    /// 128.
    pub min_spp: u32,
}

/// With [`Target::Mean`], the fewest samples a pixel takes, as a share of the mean (no pixel is
/// left with so few that a light its pilot missed stays unseen), and the most, as a multiple.
pub const MEAN_FLOOR: u32 = 8;
pub const MEAN_CEILING: u32 = 16;

impl Adaptive {
    pub const DEFAULT_MIN_SPP: u32 = 16;

    pub fn threshold(error: f64, min_spp: u32) -> Adaptive {
        Adaptive {
            target: Target::Threshold(error),
            min_spp,
        }
    }

    pub fn mean(spp: u32, min_spp: u32) -> Adaptive {
        Adaptive {
            target: Target::Mean(spp),
            min_spp,
        }
    }

    /// Why it cannot drive a render of at most `spp` samples per pixel, if it cannot.
    pub fn check(&self, spp: u32) -> std::result::Result<(), String> {
        if !(self.min_spp.is_power_of_two() && (2..=128).contains(&self.min_spp)) {
            return Err(format!(
                "--min-spp must be a power of two from 2 to 128, got {}",
                self.min_spp
            ));
        }
        match self.target {
            Target::Threshold(error) => {
                if !(error.is_finite() && error > 0.0) {
                    return Err(format!(
                        "--noise-threshold must be a positive relative error (0.01 for 1%), got {error}"
                    ));
                }
                if spp <= self.min_spp {
                    return Err(format!(
                        "--noise-threshold needs --spp (the most samples a pixel takes) above \
                         --min-spp ({}), got {spp}",
                        self.min_spp
                    ));
                }
            }
            Target::Mean(mean) => {
                if mean < self.min_spp || mean > spp {
                    return Err(format!(
                        "--adaptive spreads --spp samples a pixel on average: they must be at \
                         least --min-spp ({}) and at most the cap ({spp}), got {mean}",
                        self.min_spp
                    ));
                }
            }
        }
        Ok(())
    }

    /// With [`Target::Threshold`] `error`: the sample count of a pixel whose relMSE after
    /// `min_spp` samples is estimated at `v`, a power of two from `min_spp`, at most `cap`.
    pub fn threshold_count(&self, error: f64, v: f64, cap: u32) -> u32 {
        let want = f64::from(self.min_spp) * v / (error * error);
        // NaN (no estimate) and anything past the cap take the cap.
        if want.is_nan() || want > f64::from(cap) {
            return cap;
        }
        let n = (want.ceil() as u32).max(self.min_spp);
        n.checked_next_power_of_two().unwrap_or(cap).min(cap)
    }
}

/// Counts that cost what `mean` samples a pixel would, spread as sqrt(v_p / c_p) for the
/// estimates `v` (NaN: the largest) and each pixel's cost of a sample `c` (its rays), from
/// mean / MEAN_FLOOR to `cap`: the image's relMSE, the mean of v_p · min_spp / n_p, is least for
/// a given cost, the sum of c_p n_p, when n_p is proportional to sqrt(v_p / c_p).
pub fn spread(v: &[f64], c: &[f64], mean: u32, cap: u32) -> Vec<u32> {
    let worst = v
        .iter()
        .copied()
        .filter(|x| !x.is_nan())
        .fold(0.0f64, f64::max);
    let c: Vec<f64> = c.iter().map(|c| c.max(1.0)).collect();
    let s: Vec<f64> = v
        .iter()
        .zip(&c)
        .map(|(&x, &c)| (if x.is_nan() { worst } else { x.max(0.0) } / c).sqrt())
        .collect();
    let total = f64::from(mean) * c.iter().sum::<f64>();
    let (lo, hi) = (f64::from((mean / MEAN_FLOOR).max(1)), f64::from(cap));
    let sum = |l: f64| {
        s.iter()
            .zip(&c)
            .map(|(&x, &c)| (l * x).clamp(lo, hi) * c)
            .sum::<f64>()
    };
    // The scale whose clamped counts add up to the total: the sum grows with it.
    let (mut a, mut b) = (0.0f64, 1.0f64);
    while sum(b) < total && b < 1e300 {
        b *= 2.0;
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if sum(m) < total {
            a = m;
        } else {
            b = m;
        }
    }
    s.iter()
        .map(|&x| (b * x).clamp(lo, hi).round() as u32)
        .collect()
}

/// The pilot's seed for a render of `seed`: streams of their own (the camera samples hash the
/// seed, so any other seed gives independent samples).
pub fn pilot_seed(seed: u64) -> u64 {
    seed ^ 0x5851_f42d_4c95_7f2d
}

/// The pixels whose pilot decides the counts of `window`'s in a `width` x `height` image: with a
/// threshold the window and the ring of pixels around it; with a mean the whole image, since
/// every pixel's count depends on all the others' (their total is fixed).
pub fn pilot_window(a: &Adaptive, window: Window, width: u32, height: u32) -> Window {
    match a.target {
        Target::Threshold(_) => ring(window, width, height),
        Target::Mean(_) => Window::full(width, height),
    }
}

/// The window grown by one pixel on every side, within a `width` x `height` image.
pub fn ring(window: Window, width: u32, height: u32) -> Window {
    Window {
        x0: window.x0.saturating_sub(1),
        y0: window.y0.saturating_sub(1),
        x1: (window.x1 + 1).min(width),
        y1: (window.y1 + 1).min(height),
    }
}

/// Each image pixel's end sample (row-major, `width` x `height`): the counts of `window`'s
/// pixels (with a mean, of every pixel of the pilot) from the pilot over `ring`
/// ([`pilot_window`]; its film sums, [`film::resolve`]d); other pixels keep `u32::MAX` (the
/// image renders only the window).
pub fn pixel_ends(
    t: &Adaptive,
    first: &film::Resolved,
    costs: &[f64],
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
    // A mean spreads over every pixel of the pilot (the image); a threshold decides each pixel
    // of the window alone.
    let decided = match t.target {
        Target::Threshold(_) => window,
        Target::Mean(_) => ring,
    };
    let mut pixels = Vec::with_capacity(decided.pixels());
    let mut estimates = Vec::with_capacity(decided.pixels());
    let mut cost = Vec::with_capacity(decided.pixels());
    for y in decided.y0..decided.y1 {
        for x in decided.x0..decided.x1 {
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
            // NaN (never expected: non-finite samples count as 0) takes the most samples.
            estimates.push(if own.is_nan() || local.is_nan() {
                f64::NAN
            } else {
                own.max(local)
            });
            pixels.push((y * width + x) as usize);
            let (lx, ly) = (x - ring.x0, y - ring.y0);
            cost.push(costs[(ly * ring.width() + lx) as usize]);
        }
    }
    let counts = match t.target {
        Target::Threshold(error) => estimates
            .iter()
            .map(|&v| t.threshold_count(error, v, cap))
            .collect(),
        Target::Mean(mean) => spread(&estimates, &cost, mean, cap),
    };
    let mut ends = vec![u32::MAX; width as usize * height as usize];
    for (p, c) in pixels.into_iter().zip(counts) {
        ends[p] = c;
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
    fn threshold_counts_are_powers_of_two_between_the_minimum_and_the_cap() {
        let t = Adaptive::threshold(0.1, 16);
        let count = |v| t.threshold_count(0.1, v, 1000);
        // v = T² reaches the target at the minimum; 4 T² at 4 x the minimum.
        assert_eq!(count(0.0), 16);
        assert_eq!(count(0.01), 16);
        assert_eq!(count(0.04), 64);
        assert_eq!(count(0.041), 128);
        assert_eq!(count(10.0), 1000);
        assert_eq!(count(f64::INFINITY), 1000);
        assert_eq!(count(f64::NAN), 1000);
        assert_eq!(t.threshold_count(0.1, 1e30, u32::MAX - 255), u32::MAX - 255);
    }

    #[test]
    fn spread_counts_follow_the_standard_deviations_and_keep_the_mean() {
        // Standard deviations 1, 2, 4 and 8 (v their squares): counts in proportion.
        let one = [1.0; 4];
        let c = spread(&[1.0, 4.0, 16.0, 64.0], &one, 60, 1000);
        assert_eq!(c, [16, 32, 64, 128]);
        // The floor (mean / 8) and the cap bind; the others share what is left.
        let c = spread(&[0.0, 1.0, 1.0, 1e12], &one, 64, 128);
        assert_eq!(c, [8, 60, 60, 128]);
        // No estimate takes the largest.
        assert_eq!(spread(&[f64::NAN, 1.0], &one[..2], 10, 100), [10, 10]);
        // Nothing to spread: every pixel at the floor.
        assert_eq!(spread(&[0.0, 0.0], &one[..2], 64, 128), [8, 8]);
        // Equally noisy, one pixel's samples cost 4x: it takes half as many (sqrt(1/4)), at the
        // cost of 100 samples each: 4 n + 2 n = 500, n = 83.3.
        assert_eq!(spread(&[1.0, 1.0], &[4.0, 1.0], 100, 1000), [83, 167]);
    }

    #[test]
    fn settings_are_checked() {
        let ok = Adaptive::threshold(0.05, 16);
        assert!(ok.check(17).is_ok());
        assert!(ok.check(16).unwrap_err().contains("--spp"));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = Adaptive::threshold(bad, 16).check(64).unwrap_err();
            assert!(e.contains("--noise-threshold"), "{e}");
        }
        for bad in [0, 1, 3, 256] {
            let e = Adaptive::threshold(0.05, bad).check(1024).unwrap_err();
            assert!(e.contains("--min-spp"), "{e}");
        }
        assert!(Adaptive::mean(64, 16).check(1024).is_ok());
        assert!(
            Adaptive::mean(8, 16)
                .check(1024)
                .unwrap_err()
                .contains("--adaptive")
        );
        assert!(
            Adaptive::mean(2048, 16)
                .check(1024)
                .unwrap_err()
                .contains("--adaptive")
        );
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
