//! Shared machinery of tests/sampling.rs and tests/brdf.rs: running the GLSL test kernels of
//! tests/kernels/ on a validated context, and the statistics (chi-square goodness of fit the
//! pbrt-v4 / Mitsuba 3 way, z-tests, Šidák correction).
//!
//! Chi-square goodness of fit of a direction sampler against its own pdf():
//! * The sphere (or the sampler's support) is parametrised by a 2D domain (x, y) ∈ [0,1]² with a
//!   known Jacobian dω/(dx dy): a polar grid about an axis, a cone, a light's surface, or the dome's
//!   texels. Each cell's probability is the integral of the GPU pdf() over the cell, by a 9×9
//!   midpoint rule (27×27 where the pdf is zero on part of the cell: an edge of the support), with
//!   the nested 3×3 (resp. 9×9) rule as an error estimate.
//! * Shape: the valid samples are binned and compared with the cell probabilities normalised to
//!   the number of valid samples; cells with expected count < 5 are pooled; p-value from the
//!   chi-square distribution with (categories - 1) degrees of freedom.
//! * Normalisation: the fraction of valid samples must equal the integral of pdf() (1 for lights),
//!   a z-test whose variance is the binomial variance plus the square of the quadrature error
//!   estimate.
//! * Every valid sample must have pdf() > 0 at its own direction (the sampler never goes where the
//!   pdf is zero; cells that the quadrature finds empty but that hold samples are pooled).
//! * Significance 0.01 for the whole suite, split over [`HYPOTHESES`] tests with Šidák's correction.
#![allow(dead_code)]

use ash::vk;
use glam::DVec3;
use illum::vk::{ComputePipeline, Context, ContextOptions, MemoryLocation};

/// Upper bound on the number of hypothesis tests (chi-square and z-tests) in tests/sampling.rs and
/// tests/brdf.rs together (about 290 today); Šidák's correction with an upper bound is conservative.
pub const HYPOTHESES: f64 = 400.0;
/// Family-wise significance level of the suite.
pub const SIGNIFICANCE: f64 = 0.01;

/// Per-test significance after Šidák's correction.
pub fn alpha() -> f64 {
    1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / HYPOTHESES)
}

pub fn context() -> Context {
    Context::new(&ContextOptions {
        device: std::env::var("ILLUM_TEST_DEVICE").ok(),
        validation: true,
    })
    .expect("creating a Vulkan context with validation layers")
}

/// Fails the test if the validation layers said anything.
pub fn assert_no_validation_messages(ctx: &Context) {
    assert!(ctx.validation_enabled(), "validation layers are not on");
    let m = ctx.validation_messages();
    assert!(
        m.is_empty(),
        "{} validation message(s):\n{}",
        m.len(),
        m.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// Kernels

/// A test kernel of tests/kernels/: binding 0 parameters, 1 input, 2 output (storage buffers), push
/// constants (mode, count, seed, 0); one invocation per item, 64 per workgroup.
pub struct Kernel {
    ctx: Context,
    pipeline: ComputePipeline,
}

impl Kernel {
    pub fn new(ctx: &Context, name: &str, spirv: &[u8]) -> Kernel {
        let s = vk::DescriptorType::STORAGE_BUFFER;
        let pipeline = ComputePipeline::new(ctx, name, spirv, &[(0, s), (1, s), (2, s)], 16, &[])
            .unwrap_or_else(|e| panic!("kernel {name}: {e}"));
        Kernel {
            ctx: ctx.clone(),
            pipeline,
        }
    }

    /// Runs `count` items and returns `out_len` elements of the output buffer.
    pub fn run<P: bytemuck::Pod, I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        params: &P,
        input: &[I],
        mode: u32,
        count: usize,
        seed: u32,
        out_len: usize,
    ) -> Vec<O> {
        let ctx = &self.ctx;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let pbuf = ctx
            .upload("test params", std::slice::from_ref(params), storage)
            .unwrap();
        let ibuf = ctx.upload("test input", input, storage).unwrap();
        let obuf = ctx
            .create_buffer(
                "test output",
                (out_len * std::mem::size_of::<O>()) as u64,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )
            .unwrap();
        self.pipeline
            .bind_buffer(0, vk::DescriptorType::STORAGE_BUFFER, &pbuf);
        self.pipeline
            .bind_buffer(1, vk::DescriptorType::STORAGE_BUFFER, &ibuf);
        self.pipeline
            .bind_buffer(2, vk::DescriptorType::STORAGE_BUFFER, &obuf);
        let push: [u32; 4] = [mode, count as u32, seed, 0];
        // Bounded dispatches (at most 2^16 groups each is not needed here: count <= 2^22).
        let groups = count.div_ceil(64) as u32;
        assert!(groups <= 65535, "too many items for one dispatch: {count}");
        ctx.one_shot(|cmd| {
            self.pipeline
                .dispatch(cmd, bytemuck::bytes_of(&push), [groups.max(1), 1, 1]);
            ctx.barrier(cmd);
        })
        .unwrap();
        ctx.download(&obuf, out_len).unwrap()
    }
}

#[path = "../common/stats.rs"]
mod stats;
pub use stats::erfc;

// ---------------------------------------------------------------------------------------------
// Special functions

pub fn erf(x: f64) -> f64 {
    1.0 - erfc(x)
}

/// Two-sided p-value of a standard normal statistic.
pub fn normal_two_sided_p(z: f64) -> f64 {
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// One-sided p-value P(Z > z).
pub fn normal_upper_p(z: f64) -> f64 {
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

fn ln_gamma(x: f64) -> f64 {
    // Lanczos (g = 7, n = 9), |relative error| < 1e-15 for x > 0.
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes gser/gcf).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let mut ap = a;
        let mut sum = 1.0 / a;
        let mut del = sum;
        for _ in 0..100_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - gln).exp() * h
    }
}

/// P(X >= x) for X chi-square distributed with `dof` degrees of freedom.
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    gamma_q(0.5 * dof, 0.5 * x)
}

/// Mean and standard error of the mean of `v` (sample variance).
pub fn mean_and_error(v: impl Iterator<Item = f64>) -> (f64, f64, usize) {
    let (mut n, mut s, mut s2) = (0usize, 0.0f64, 0.0f64);
    for x in v {
        n += 1;
        s += x;
        s2 += x * x;
    }
    let nf = n as f64;
    let mean = s / nf;
    let var = ((s2 - nf * mean * mean) / (nf - 1.0)).max(0.0);
    (mean, (var / nf).sqrt(), n)
}

/// Two-sided z-test of an estimate with standard error `err` against `expected` (whose own
/// uncertainty `ref_err` adds in quadrature). Panics with `what` when rejected at [`alpha`].
pub fn z_test(what: &str, estimate: f64, err: f64, expected: f64, ref_err: f64) {
    let sigma = (err * err + ref_err * ref_err).sqrt();
    let z = (estimate - expected) / sigma;
    let p = normal_two_sided_p(z);
    eprintln!("{what}: {estimate:.6} ± {err:.2e} vs {expected:.6} (z = {z:+.2}, p = {p:.3e})");
    assert!(
        p > alpha() || !z.is_finite() && estimate == expected,
        "{what}: {estimate} ± {err} differs from {expected} (z = {z:.2}, p = {p:.3e} < {:.3e})",
        alpha()
    );
}

// ---------------------------------------------------------------------------------------------
// Frames and domains

/// Orthonormal basis (t, b) around a unit vector (Duff et al. 2017), as make_basis in GLSL.
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let c = n.x * n.y * a;
    (
        DVec3::new(1.0 + s * n.x * n.x * a, s * c, -s * n.x),
        DVec3::new(c, s + n.y * n.y * a, -n.y),
    )
}

/// Angle between two unit vectors, accurate at small angles.
pub fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// (x, y) -> (direction, dω/(dx dy)).
pub type ToDir = Box<dyn Fn(f64, f64) -> Option<(DVec3, f64)>>;
/// direction -> (x, y).
pub type FromDir = Box<dyn Fn(DVec3) -> Option<(f64, f64)>>;

/// A parametrisation of (part of) the sphere of directions by (x, y) ∈ [0,1]²: `to_dir` gives the
/// direction and dω/(dx dy) (None where the point has no direction), `from_dir` the inverse (None
/// outside the domain).
pub struct Domain {
    pub to_dir: ToDir,
    pub from_dir: FromDir,
    pub nx: usize,
    pub ny: usize,
}

impl Domain {
    /// Polar grid about `axis` covering the whole sphere: θ = 2 atan(c tan(πx/2)) (θ ≈ cπx near the
    /// axis, so that a small c resolves a narrow lobe), φ = 2πy measured from `t`.
    pub fn polar(axis: DVec3, c: f64, nx: usize, ny: usize) -> Domain {
        let (t, b) = basis(axis);
        let pi = std::f64::consts::PI;
        Domain {
            to_dir: Box::new(move |x, y| {
                let tt = (0.5 * pi * x).tan();
                let theta = 2.0 * (c * tt).atan();
                let dtheta = pi * c * (1.0 + tt * tt) / (1.0 + c * c * tt * tt);
                let phi = 2.0 * pi * y;
                let (st, ct) = theta.sin_cos();
                let d = st * phi.cos() * t + st * phi.sin() * b + ct * axis;
                Some((d, st * dtheta * 2.0 * pi))
            }),
            from_dir: Box::new(move |d| {
                let theta = angle(d, axis);
                let x = (2.0 / pi) * ((0.5 * theta).tan() / c).atan();
                let phi = d.dot(b).atan2(d.dot(t)).rem_euclid(2.0 * pi);
                Some((x.clamp(0.0, 1.0), phi / (2.0 * pi)))
            }),
            nx,
            ny,
        }
    }

    /// A (θ, φ) grid about `axis` with the given cell edges (θ from the axis, φ from basis(axis).t),
    /// linear in between: cells need not be equal, so that they can follow a lobe (see
    /// [`quantile_edges`]) while the edges stay exactly on the support's boundary (θ = π/2 for a
    /// BRDF about its normal). Directions beyond the last θ edge are outside the domain.
    pub fn polar_edges(axis: DVec3, theta: Vec<f64>, phi: Vec<f64>) -> Domain {
        let (t, b) = basis(axis);
        let (nx, ny) = (theta.len() - 1, phi.len() - 1);
        let (th, ph) = (theta.clone(), phi.clone());
        Domain {
            to_dir: Box::new(move |x, y| {
                let (theta, dtheta) = piecewise(&th, x);
                let (phi, dphi) = piecewise(&ph, y);
                let (st, ct) = theta.sin_cos();
                let d = st * phi.cos() * t + st * phi.sin() * b + ct * axis;
                Some((d, st * dtheta * dphi))
            }),
            from_dir: Box::new(move |d| {
                let th_d = angle(d, axis);
                if th_d > theta[nx] {
                    return None;
                }
                let phi_d = d
                    .dot(b)
                    .atan2(d.dot(t))
                    .rem_euclid(2.0 * std::f64::consts::PI);
                Some((
                    piecewise_inverse(&theta, th_d),
                    piecewise_inverse(&phi, phi_d),
                ))
            }),
            nx,
            ny,
        }
    }

    /// The cone of directions within θ_cap of `axis`, om_cap = 1 - cos θ_cap: x = (1 - cos θ)/om_cap
    /// (equal solid angle per cell), φ = 2πy. Directions outside the cone are outside the domain.
    pub fn cone(axis: DVec3, om_cap: f64, nx: usize, ny: usize) -> Domain {
        let (t, b) = basis(axis);
        let pi = std::f64::consts::PI;
        Domain {
            to_dir: Box::new(move |x, y| {
                let omc = x * om_cap;
                let ct = 1.0 - omc;
                let st = (omc * (2.0 - omc)).max(0.0).sqrt();
                let phi = 2.0 * pi * y;
                Some((
                    st * phi.cos() * t + st * phi.sin() * b + ct * axis,
                    2.0 * pi * om_cap,
                ))
            }),
            from_dir: Box::new(move |d| {
                let h = 0.5 * angle(d, axis);
                let omc = 2.0 * h.sin() * h.sin();
                let x = omc / om_cap;
                let phi = d.dot(b).atan2(d.dot(t)).rem_euclid(2.0 * pi);
                (x <= 1.0).then_some((x, phi / (2.0 * pi)))
            }),
            nx,
            ny,
        }
    }

    /// Directions from `p` to the points of a surface patch: `point(x, y)` gives the point, its unit
    /// normal and dA/(dx dy); `inverse(p, d)` the (x, y) where the ray from p along d meets it.
    pub fn surface(
        p: DVec3,
        point: impl Fn(f64, f64) -> (DVec3, DVec3, f64) + 'static,
        inverse: impl Fn(DVec3, DVec3) -> Option<(f64, f64)> + 'static,
        nx: usize,
        ny: usize,
    ) -> Domain {
        Domain {
            to_dir: Box::new(move |x, y| {
                let (q, n, da) = point(x, y);
                let v = q - p;
                let d2 = v.length_squared();
                let d = v / d2.sqrt();
                let c = n.dot(d).abs();
                (c > 0.0 && d2 > 0.0).then_some((d, da * c / d2))
            }),
            from_dir: Box::new(move |d| inverse(p, d)),
            nx,
            ny,
        }
    }
}

/// Value and derivative at x ∈ [0,1] of the piecewise-linear map with equal steps in x onto `edges`.
fn piecewise(edges: &[f64], x: f64) -> (f64, f64) {
    let n = edges.len() - 1;
    let s = x * n as f64;
    let k = (s as usize).min(n - 1);
    let slope = (edges[k + 1] - edges[k]) * n as f64;
    (edges[k] + (s - k as f64) * (edges[k + 1] - edges[k]), slope)
}

fn piecewise_inverse(edges: &[f64], v: f64) -> f64 {
    let n = edges.len() - 1;
    let k = edges[1..n].partition_point(|&e| e <= v);
    let f = ((v - edges[k]) / (edges[k + 1] - edges[k])).clamp(0.0, 1.0);
    (k as f64 + f) / n as f64
}

/// `n + 1` cell edges over [lo, hi] at the quantiles of a density given on `weights.len()` equal
/// bins, mixed with the uniform density (fraction `uniform`) so that no region goes without cells.
pub fn quantile_edges(weights: &[f64], lo: f64, hi: f64, n: usize, uniform: f64) -> Vec<f64> {
    let m = weights.len();
    let total: f64 = weights.iter().sum();
    let mut cdf = vec![0.0; m + 1];
    for i in 0..m {
        let p = if total > 0.0 {
            weights[i] / total
        } else {
            1.0 / m as f64
        };
        cdf[i + 1] = cdf[i] + (1.0 - uniform) * p + uniform / m as f64;
    }
    let mut edges = vec![lo];
    for k in 1..n {
        let q = k as f64 / n as f64 * cdf[m];
        let i = cdf.partition_point(|&c| c <= q).clamp(1, m) - 1;
        let f = (q - cdf[i]) / (cdf[i + 1] - cdf[i]);
        edges.push(lo + (hi - lo) * (i as f64 + f) / m as f64);
    }
    edges.push(hi);
    edges
}

// ---------------------------------------------------------------------------------------------
// Chi-square test

/// Outcome of [`sampler_test`], for reporting.
#[derive(Debug)]
pub struct Chi2Report {
    pub chi2: f64,
    pub dof: usize,
    pub p: f64,
    pub integral: f64,
    pub integral_err: f64,
}

/// The k×k midpoint sub-points of cell (ix, iy).
fn cell_points(d: &Domain, ix: usize, iy: usize, k: usize) -> Vec<Option<(DVec3, f64)>> {
    let mut v = Vec::with_capacity(k * k);
    for b in 0..k {
        for a in 0..k {
            let x = (ix as f64 + (a as f64 + 0.5) / k as f64) / d.nx as f64;
            let y = (iy as f64 + (b as f64 + 0.5) / k as f64) / d.ny as f64;
            v.push((d.to_dir)(x, y));
        }
    }
    v
}

/// Integrates pdf × Jacobian over every cell: (integral, error estimate) per cell. Midpoint rule
/// on 9×9 sub-points, refined to 27×27 and 81×81 where the pdf is zero on part of the cell (an edge
/// of the support) or where the error estimate (half the difference to the nested 3× coarser rule)
/// is not small against the sd of the cell's count among `samples` draws.
fn integrate_cells(
    d: &Domain,
    samples: f64,
    pdf: &mut dyn FnMut(&[[f32; 4]]) -> Vec<f64>,
) -> (Vec<f64>, Vec<f64>) {
    let cells = d.nx * d.ny;
    let cell_area = 1.0 / cells as f64;
    let mut integral = vec![0.0; cells];
    let mut error = vec![0.0; cells];
    let mut list: Vec<usize> = (0..cells).collect();
    let mut k = 9;
    loop {
        // Evaluate in chunks of at most 2^20 directions.
        let per_chunk = ((1usize << 20) / (k * k)).max(1);
        let mut next = Vec::new();
        for chunk in list.chunks(per_chunk) {
            let mut dirs = Vec::with_capacity(chunk.len() * k * k);
            let mut jac = Vec::with_capacity(chunk.len() * k * k);
            for &c in chunk {
                for p in cell_points(d, c % d.nx, c / d.nx, k) {
                    let (dir, j) = p.unwrap_or((DVec3::Z, 0.0));
                    dirs.push([dir.x as f32, dir.y as f32, dir.z as f32, 0.0]);
                    jac.push(j);
                }
            }
            let values = pdf(&dirs);
            for (r, &c) in chunk.iter().enumerate() {
                let s: Vec<f64> = (0..k * k)
                    .map(|q| values[r * k * k + q] * jac[r * k * k + q])
                    .collect();
                let fine: f64 = s.iter().sum::<f64>() / (k * k) as f64;
                // The nested rule with a third of the points per axis: sub-points (3a+1, 3b+1).
                let kc = k / 3;
                let mut coarse = 0.0;
                for b in 0..kc {
                    for a in 0..kc {
                        coarse += s[(3 * b + 1) * k + 3 * a + 1];
                    }
                }
                coarse /= (kc * kc) as f64;
                integral[c] = fine * cell_area;
                error[c] = 0.5 * (fine - coarse).abs() * cell_area;
                let zeros = s.iter().filter(|&&x| x == 0.0).count();
                let count = integral[c] * samples;
                if (zeros > 0 && zeros < k * k) || error[c] * samples > 0.1 * count.max(1.0).sqrt()
                {
                    next.push(c);
                }
            }
        }
        if next.is_empty() || k >= 81 {
            break;
        }
        list = next;
        k *= 3;
    }
    (integral, error)
}

/// Chi-square test of a sampler against its pdf: `valid` are the directions of the valid samples
/// out of `total` samples drawn; `pdf` evaluates the GPU pdf() for directions (xyz of each entry).
pub fn sampler_test(
    name: &str,
    valid: &[DVec3],
    total: usize,
    domain: &Domain,
    pdf: &mut dyn FnMut(&[[f32; 4]]) -> Vec<f64>,
) -> Chi2Report {
    let cells = domain.nx * domain.ny;
    let (integral, error) = integrate_cells(domain, total as f64, pdf);
    let sum: f64 = integral.iter().sum();
    let err: f64 = error.iter().sum();

    let mut observed = vec![0.0f64; cells];
    let mut outside = 0usize;
    for &d in valid {
        match (domain.from_dir)(d) {
            Some((x, y)) => {
                let ix = ((x * domain.nx as f64) as usize).min(domain.nx - 1);
                let iy = ((y * domain.ny as f64) as usize).min(domain.ny - 1);
                observed[iy * domain.nx + ix] += 1.0;
            }
            None => outside += 1,
        }
    }
    assert_eq!(
        outside, 0,
        "{name}: {outside} valid samples outside the domain of the test (where the pdf is 0)"
    );

    // Normalisation: P(valid) = integral of the pdf. Besides the binomial variance and the
    // quadrature error, pdf() is float32: its values carry a few ulp of relative error (1e-6).
    let n = total as f64;
    let frac = valid.len() as f64 / n;
    let var = sum.clamp(0.0, 1.0) * (1.0 - sum.clamp(0.0, 1.0)) / n;
    let float_err = 1e-6 * sum;
    let z = (frac - sum) / (var + err * err + float_err * float_err).sqrt();
    let p_norm = normal_two_sided_p(z);
    assert!(
        p_norm > alpha(),
        "{name}: valid fraction {frac:.6} but the pdf integrates to {sum:.6} ± {err:.2e} (z = {z:.2}, p = {p_norm:.2e})"
    );

    // Shape: expected counts normalised to the valid samples, pooled below 5.
    let nv = valid.len() as f64;
    let mut order: Vec<usize> = (0..cells).collect();
    let expected: Vec<f64> = integral.iter().map(|i| i / sum * nv).collect();
    order.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut chi2, mut dof) = (0.0f64, 0usize);
    let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
    for &c in &order {
        let (o, e) = (observed[c], expected[c]);
        if e < 5.0 || (pool_e > 0.0 && pool_e < 5.0) {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else {
        assert!(
            pool_o == 0.0,
            "{name}: {pool_o} samples where the pdf integrates to 0"
        );
    }
    if std::env::var("ILLUM_CHI2_DEBUG").is_ok() {
        let mut worst: Vec<usize> = (0..cells).filter(|&c| expected[c] >= 5.0).collect();
        let dev = |c: usize| (observed[c] - expected[c]).powi(2) / expected[c];
        worst.sort_by(|&a, &b| dev(b).partial_cmp(&dev(a)).unwrap());
        for &c in worst.iter().take(12) {
            eprintln!(
                "  cell ({}, {}): observed {} expected {:.1} (quadrature error {:.2e})",
                c % domain.nx,
                c / domain.nx,
                observed[c],
                expected[c],
                error[c] / sum * nv
            );
        }
    }
    let dof = dof.saturating_sub(1).max(1);
    let p = chi2_sf(chi2, dof as f64);
    eprintln!(
        "{name}: chi2 = {chi2:.1}, dof = {dof}, p = {p:.3e}; valid {frac:.5}, pdf integral {sum:.5} ± {err:.1e}"
    );
    assert!(
        p > alpha(),
        "{name}: chi-square test rejects the sampler: chi2 = {chi2:.1} with {dof} dof, p = {p:.3e} < {:.3e}",
        alpha()
    );
    Chi2Report {
        chi2,
        dof,
        p,
        integral: sum,
        integral_err: err,
    }
}

/// Checks the pdf a sampler reported against pdf() re-evaluated at the sampled direction: every
/// valid sample must have pdf() > 0, and the two must agree to float precision (relative 1e-3
/// covers float32 rounding through different formulas, amplified by 1/cos at grazing angles), except
/// for samples that `ambiguous` says lie on a boundary where two float paths may pick different
/// cells.
pub fn check_reported_pdfs(
    name: &str,
    samples: &[(f64, f64)],
    ambiguous: impl Fn(usize) -> bool,
) -> usize {
    let mut mismatches = 0usize;
    for (i, &(reported, reeval)) in samples.iter().enumerate() {
        assert!(
            reeval > 0.0,
            "{name}: sample {i} has pdf {reported} but pdf() of its direction is {reeval}"
        );
        if (reported - reeval).abs() > 1e-3 * reported.max(reeval) {
            assert!(
                ambiguous(i),
                "{name}: sample {i}: sampler pdf {reported} vs pdf() {reeval}"
            );
            mismatches += 1;
        }
    }
    mismatches
}
