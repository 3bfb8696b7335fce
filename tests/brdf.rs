//! glsl/scene/microfacet.glsl on the GPU (tests/kernels/sample_brdf.comp): chi-square tests of every
//! sampler against its own pdf, the D-BRDF's weight = F identity, directional albedos against
//! quadrature references (and the tables of docs/techniques.md, "Reference values"), Fresnel, the
//! delta lobe and invalid input.

mod common;

use common::*;
use glam::DVec3;
use illum::layout::*;
use std::f64::consts::PI;

const N: usize = 1 << 20;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BrdfParams {
    lobe: GpuLobe,
    n: [f32; 4],
    t: [f32; 4],
    b: [f32; 4],
    v: [f32; 4],
}

fn lobe(distribution: u32, a: (f64, f64), fresnel: u32, f0: [f32; 3]) -> GpuLobe {
    GpuLobe {
        fresnel0: [f0[0], f0[1], f0[2], 0.0],
        fresnel1: [0.0; 4],
        alpha: [a.0 as f32, a.1 as f32],
        distribution,
        fresnel,
    }
}

fn white(distribution: u32, a: (f64, f64)) -> GpuLobe {
    lobe(distribution, a, FRESNEL_CONSTANT, [1.0; 3])
}

/// A tilted shading frame (so that the world/local transforms are exercised) and a view direction
/// at `theta_deg` from the normal, azimuth 30° from the tangent.
struct Setup {
    n: DVec3,
    t: DVec3,
    b: DVec3,
    v: DVec3,
}

fn setup(theta_deg: f64) -> Setup {
    let n = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let (t, b) = basis(n);
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sp, cp) = 30f64.to_radians().sin_cos();
    let v = (st * (cp * t + sp * b) + ct * n).normalize();
    Setup { n, t, b, v }
}

impl Setup {
    fn params(&self, lobe: GpuLobe) -> BrdfParams {
        BrdfParams {
            lobe,
            n: f4(self.n, 0.0),
            t: f4(self.t, 0.0),
            b: f4(self.b, 0.0),
            v: f4(self.v, 0.0),
        }
    }
    /// The view direction in the local frame (x along t, y along b, z along n).
    fn v_local(&self) -> DVec3 {
        DVec3::new(self.v.dot(self.t), self.v.dot(self.b), self.v.dot(self.n))
    }
}

/// Samples of mode 0: (wi, pdf), (weight, pdf(wi)), (f_cos(wi), flags).
struct Samples(Vec<[f32; 4]>);

impl Samples {
    fn get(k: &Kernel, p: &BrdfParams, seed: u32) -> Samples {
        Samples(k.run(p, &[[0f32; 4]], 0, N, seed, 3 * N))
    }
    fn valid(&self, i: usize) -> bool {
        (self.0[3 * i + 2][3] as u32) & 1 != 0
    }
    fn delta(&self, i: usize) -> bool {
        (self.0[3 * i + 2][3] as u32) & 2 != 0
    }
    fn dir(&self, i: usize) -> DVec3 {
        d3(self.0[3 * i])
    }
    fn pdf(&self, i: usize) -> f64 {
        f64::from(self.0[3 * i][3])
    }
    fn weight(&self, i: usize) -> DVec3 {
        d3(self.0[3 * i + 1])
    }
    fn pdf_eval(&self, i: usize) -> f64 {
        f64::from(self.0[3 * i + 1][3])
    }
    fn f_cos_eval(&self, i: usize) -> DVec3 {
        d3(self.0[3 * i + 2])
    }
}

fn eval_pdfs(k: &Kernel, p: &BrdfParams, dirs: &[[f32; 4]]) -> Vec<f64> {
    let out: Vec<[f32; 4]> = k.run(p, dirs, 1, dirs.len(), 0, dirs.len());
    out.iter().map(|o| f64::from(o[3])).collect()
}

// ---------------------------------------------------------------------------------------------
// Chi-square

fn chi2_case(k: &Kernel, name: &str, lobe: GpuLobe, theta_deg: f64, seed: u32) {
    let s = setup(theta_deg);
    let prm = s.params(lobe);
    let out = Samples::get(k, &prm, seed);
    let mut valid = Vec::new();
    let mut pdfs = Vec::new();
    for i in 0..N {
        if out.valid(i) {
            valid.push(out.dir(i));
            pdfs.push((out.pdf(i), out.pdf_eval(i)));
            // The weight is f cos / pdf as brdf_eval() computes them.
            let w = out.weight(i).x;
            let w_eval = out.f_cos_eval(i).x / out.pdf_eval(i);
            // float32: Lambda at grazing l loses digits, so allow 1e-6 absolute (weights are O(1)).
            assert!(
                (w - w_eval).abs() <= 1e-3 * w.max(w_eval) + 1e-6,
                "{name}: sample {i}: weight {w} but f cos / pdf = {w_eval}"
            );
        }
    }
    check_reported_pdfs(name, &pdfs, |_| false);
    // A (theta, phi) grid of the hemisphere about n, whose last theta edge is the horizon (where the
    // pdf drops to 0), with cell edges at the quantiles of the pdf's marginals so that the cells
    // follow the lobe.
    let (m_theta, m_phi) = (256usize, 512usize);
    let (t, b) = basis(s.n);
    let mut dirs = Vec::with_capacity(m_theta * m_phi);
    for j in 0..m_phi {
        for i in 0..m_theta {
            let theta = 0.5 * PI * (i as f64 + 0.5) / m_theta as f64;
            let phi = 2.0 * PI * (j as f64 + 0.5) / m_phi as f64;
            let d = theta.sin() * (phi.cos() * t + phi.sin() * b) + theta.cos() * s.n;
            dirs.push(f4(d, 0.0));
        }
    }
    let p = eval_pdfs(k, &prm, &dirs);
    let (mut w_theta, mut w_phi) = (vec![0.0; m_theta], vec![0.0; m_phi]);
    for j in 0..m_phi {
        for i in 0..m_theta {
            let w = p[j * m_theta + i] * (0.5 * PI * (i as f64 + 0.5) / m_theta as f64).sin();
            w_theta[i] += w;
            w_phi[j] += w;
        }
    }
    let domain = Domain::polar_edges(
        s.n,
        quantile_edges(&w_theta, 0.0, 0.5 * PI, 32, 0.2),
        quantile_edges(&w_phi, 0.0, 2.0 * PI, 64, 0.2),
    );
    sampler_test(name, &valid, N, &domain, &mut |dirs| {
        eval_pdfs(k, &prm, dirs)
    });
}

fn chi2_cases(cases: &[(&str, GpuLobe)]) {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let mut seed = 1;
    for (name, lobe) in cases {
        for theta in [0.0, 45.0, 80.0] {
            chi2_case(&k, &format!("{name} at {theta}°"), *lobe, theta, seed);
            seed += 1;
        }
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn chi2_dbrdf_isotropic() {
    chi2_cases(&[
        ("D-BRDF alpha 0.05", white(DIST_DBRDF, (0.05, 0.05))),
        ("D-BRDF alpha 0.3", white(DIST_DBRDF, (0.3, 0.3))),
        ("D-BRDF alpha 1.0", white(DIST_DBRDF, (1.0, 1.0))),
    ]);
}

#[test]
fn chi2_dbrdf_anisotropic_and_beckmann_smith() {
    chi2_cases(&[
        ("D-BRDF alpha (0.05, 0.4)", white(DIST_DBRDF, (0.05, 0.4))),
        (
            "Beckmann-Smith alpha 0.3",
            white(DIST_BECKMANN_SMITH, (0.3, 0.3)),
        ),
        (
            "Beckmann-Smith alpha (0.4, 0.1)",
            white(DIST_BECKMANN_SMITH, (0.4, 0.1)),
        ),
    ]);
}

#[test]
fn chi2_ggx() {
    chi2_cases(&[
        ("GGX alpha 0.2", white(DIST_GGX_SMITH, (0.2, 0.2))),
        ("GGX alpha (0.1, 0.5)", white(DIST_GGX_SMITH, (0.1, 0.5))),
        (
            "GGX separable alpha 0.6",
            white(DIST_GGX_SMITH_SEPARABLE, (0.6, 0.6)),
        ),
    ]);
}

// ---------------------------------------------------------------------------------------------
// Weights, Fresnel, delta lobe, invalid input

#[test]
fn dbrdf_weight_is_exactly_fresnel() {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let f0 = [0.04f32, 0.5, 0.9];
    for (a, theta) in [((0.3, 0.3), 45.0), ((1.0, 1.0), 80.0), ((0.05, 0.4), 70.0)] {
        let s = setup(theta);
        let l = lobe(DIST_DBRDF, a, FRESNEL_SCHLICK, f0);
        let out = Samples::get(&k, &s.params(l), 99);
        let (mut count, mut worst, mut worst_eval) = (0usize, 0.0f64, 0.0f64);
        for i in 0..N {
            if !out.valid(i) {
                assert_eq!(out.weight(i), DVec3::ZERO);
                continue;
            }
            count += 1;
            let wi = out.dir(i);
            let vh = s.v.dot((s.v + wi).normalize());
            let m = (1.0 - vh).powi(5);
            let f = DVec3::new(f0[0].into(), f0[1].into(), f0[2].into());
            let fresnel = f + (DVec3::ONE - f) * m;
            let w = out.weight(i);
            worst = worst.max((w - fresnel).abs().max_element());
            // brdf_eval() agrees: f cos / pdf(l) = F (it evaluates D with exp(), the sampler did not).
            let e = out.f_cos_eval(i) / out.pdf(i);
            worst_eval = worst_eval.max((e - fresnel).abs().max_element());
        }
        eprintln!(
            "D-BRDF {a:?} at {theta}°: {count} valid samples, max |weight - F| = {worst:.2e}, max |f cos / pdf - F| = {worst_eval:.2e}"
        );
        assert!(count > N / 2);
        // float32: F from a v.h that differs by a few ulps, |dF/d(v.h)| <= 5.
        assert!(worst < 1e-5, "weight differs from F by {worst}");
        // exp() of up to -16.6 in float32 against (1 - u1): relative ~1e-6 per unit of exponent.
        assert!(
            worst_eval < 1e-4,
            "f cos / pdf differs from F by {worst_eval}"
        );
    }
    assert_no_validation_messages(&ctx);
}

/// Rust reference of Mitsuba 3's fresnel_conductor through complex arithmetic (Fresnel's equations
/// with a complex refractive index), independent of the GLSL's real-arithmetic form.
fn conductor_reference(c: f64, eta: f64, k: f64) -> f64 {
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: C| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        let re = ((r + a.0) / 2.0).sqrt();
        let im = ((r - a.0) / 2.0).max(0.0).sqrt().copysign(a.1);
        C(re, im)
    };
    let n = C(eta, k);
    let n2 = mul(n, n);
    let s2 = 1.0 - c * c;
    let root = sqrt(C(n2.0 - s2, n2.1));
    let rs = div(C(c - root.0, -root.1), C(c + root.0, root.1));
    let n2c = C(n2.0 * c, n2.1 * c);
    let rp = div(
        C(n2c.0 - root.0, n2c.1 - root.1),
        C(n2c.0 + root.0, n2c.1 + root.1),
    );
    0.5 * (rs.0 * rs.0 + rs.1 * rs.1 + rp.0 * rp.0 + rp.1 * rp.1)
}

#[test]
fn fresnel_terms() {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let cosines: Vec<[f32; 4]> = (0..=40).map(|i| [i as f32 / 40.0, 0.0, 0.0, 0.0]).collect();
    let s = setup(0.0);
    // Gold at 650, 550, 450 nm (eta, k), aluminium-like, and a dielectric-like k = 0.
    let eta = [0.143f32, 0.374, 1.442];
    let kk = [3.983f32, 2.385, 1.603];
    let mut conductor = lobe(DIST_DBRDF, (0.3, 0.3), FRESNEL_CONDUCTOR, eta);
    conductor.fresnel1 = [kk[0], kk[1], kk[2], 0.0];
    let out: Vec<[f32; 4]> = k.run(
        &s.params(conductor),
        &cosines,
        2,
        cosines.len(),
        0,
        cosines.len(),
    );
    for (c, f) in cosines.iter().zip(&out) {
        for ch in 0..3 {
            let r = conductor_reference(c[0].into(), eta[ch].into(), kk[ch].into());
            assert!(
                (f64::from(f[ch]) - r).abs() < 2e-6,
                "conductor F({}) channel {ch}: {} vs {r}",
                c[0],
                f[ch]
            );
        }
    }
    let schlick = lobe(DIST_DBRDF, (0.3, 0.3), FRESNEL_SCHLICK, [0.04, 0.5, 1.0]);
    let out: Vec<[f32; 4]> = k.run(
        &s.params(schlick),
        &cosines,
        2,
        cosines.len(),
        0,
        cosines.len(),
    );
    for (c, f) in cosines.iter().zip(&out) {
        for (ch, f0) in [0.04f64, 0.5, 1.0].iter().enumerate() {
            let r = f0 + (1.0 - f0) * (1.0 - f64::from(c[0])).powi(5);
            assert!((f64::from(f[ch]) - r).abs() < 1e-6);
        }
    }
    let constant = lobe(DIST_DBRDF, (0.3, 0.3), FRESNEL_CONSTANT, [0.25, 0.5, 0.75]);
    let out: Vec<[f32; 4]> = k.run(
        &s.params(constant),
        &cosines,
        2,
        cosines.len(),
        0,
        cosines.len(),
    );
    assert!(out.iter().all(|f| f[..3] == [0.25, 0.5, 0.75]));
    assert_no_validation_messages(&ctx);
}

#[test]
fn delta_lobe_and_invalid_views() {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let s = setup(40.0);
    // Roughness 0 along both axes (uploaded as 0): a perfect mirror.
    let l = lobe(DIST_DBRDF, (0.0, 0.0), FRESNEL_SCHLICK, [0.04, 0.04, 0.04]);
    let prm = s.params(l);
    let out: Vec<[f32; 4]> = k.run(&prm, &[[0f32; 4]], 0, 256, 5, 3 * 256);
    let out = Samples(out);
    let mirror = 2.0 * s.n.dot(s.v) * s.n - s.v;
    let f = 0.04 + 0.96 * (1.0 - s.n.dot(s.v)).powi(5);
    for i in 0..256 {
        assert!(out.valid(i) && out.delta(i));
        assert!((out.dir(i) - mirror).length() < 1e-6);
        assert!((out.weight(i) - DVec3::splat(f)).abs().max_element() < 1e-6);
        assert_eq!(out.pdf(i), 1.0);
        // A light sample never hits a delta lobe: brdf_eval() is 0 even in the mirror direction.
        assert_eq!(out.pdf_eval(i), 0.0);
        assert_eq!(out.f_cos_eval(i), DVec3::ZERO);
    }
    // alpha clamped to 1e-4 along one axis: not a delta lobe.
    let l = lobe(DIST_GGX_SMITH, (0.0, 2e-3), FRESNEL_CONSTANT, [1.0; 3]);
    let out = Samples(k.run(&s.params(l), &[[0f32; 4]], 0, 256, 6, 3 * 256));
    assert!((0..256).all(|i| !out.delta(i) && out.pdf(i).is_finite()));
    // Down to Mitsuba's floor of 1e-4 the lobe stays a Beckmann lobe, exact in float32: samples
    // within a few alpha of the mirror direction, the D-BRDF's weight F, and brdf_eval() in the
    // sampled direction returning the sampler's own pdf (1e4 to 1e7 per steradian here).
    for a in [(1e-4, 1e-4), (1e-4, 5e-4)] {
        let out = Samples(k.run(
            &s.params(lobe(DIST_DBRDF, a, FRESNEL_SCHLICK, [0.04; 3])),
            &[[0f32; 4]],
            0,
            256,
            8,
            3 * 256,
        ));
        for i in 0..256 {
            assert!(out.valid(i) && !out.delta(i), "alpha {a:?}: sample {i}");
            assert!(
                (out.dir(i) - mirror).length() < 40.0 * a.1,
                "alpha {a:?}: {:?}",
                out.dir(i)
            );
            assert!((out.weight(i) - DVec3::splat(f)).abs().max_element() < 1e-4);
            let (p, pe) = (out.pdf(i), out.pdf_eval(i));
            assert!(
                (p - pe).abs() <= 2e-2 * p,
                "alpha {a:?}: pdf {p} vs eval {pe}"
            );
        }
    }
    // View below the shading horizon: no valid sample, and eval 0 for every model.
    for dist in [
        DIST_DBRDF,
        DIST_BECKMANN_SMITH,
        DIST_GGX_SMITH,
        DIST_GGX_SMITH_SEPARABLE,
    ] {
        let mut below = s.params(white(dist, (0.3, 0.3)));
        below.v = f4(-s.v, 0.0);
        let out = Samples(k.run(&below, &[[0f32; 4]], 0, 1024, 7, 3 * 1024));
        for i in 0..1024 {
            assert!(!out.valid(i) && out.weight(i) == DVec3::ZERO && out.pdf(i) == 0.0);
        }
        let dirs = [f4(s.n, 0.0), f4(s.v, 0.0), f4(-s.n, 0.0)];
        let e: Vec<[f32; 4]> = k.run(&below, &dirs, 1, 3, 0, 3);
        assert!(e.iter().all(|x| *x == [0.0; 4]), "{e:?}");
        // l below the horizon: 0 too.
        let e: Vec<[f32; 4]> = k.run(
            &s.params(white(dist, (0.3, 0.3))),
            &[f4(-s.n, 0.0)],
            1,
            1,
            0,
            1,
        );
        assert_eq!(e[0], [0.0; 4]);
    }
    assert_no_validation_messages(&ctx);
}

// ---------------------------------------------------------------------------------------------
// Albedo references (float64 quadrature)

/// Geometry of a slope-space sample: for azimuth psi of the slope (a1 cos psi, a2 sin psi) r, the
/// half vector tilts by beta = atan(r s) toward m = -(a1 cos psi, a2 sin psi)/s. l = reflect(v, h) is
/// above the horizon (and v.h > 0) iff beta < delta/2 + pi/4 with delta = atan2(m.v, v.z), since
/// l.z = v.z cos 2beta + (m.v) sin 2beta. Returns (s, r*) with the slope radius bound r*.
fn slope_bound(a: (f64, f64), v: DVec3, psi: f64) -> (f64, f64, DVec3) {
    let sv = DVec3::new(a.0 * psi.cos(), a.1 * psi.sin(), 0.0);
    let s = sv.length();
    let m = -sv / s;
    let delta = m.dot(DVec3::new(v.x, v.y, 0.0)).atan2(v.z);
    let beta = 0.5 * delta + 0.25 * PI;
    (s, beta.tan() / s, sv)
}

/// Exact D-BRDF albedo with F = 1: P(l above the horizon) = E_psi[1 - exp(-r*^2)].
fn dbrdf_albedo(a: (f64, f64), v: DVec3) -> f64 {
    let n = 20_000;
    (0..n)
        .map(|k| {
            let psi = 2.0 * PI * (k as f64 + 0.5) / n as f64;
            let (_, r, _) = slope_bound(a, v, psi);
            1.0 - (-r * r).exp()
        })
        .sum::<f64>()
        / n as f64
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Smith {
    /// Beckmann, separable, Walter's rational G1 (what microfacet.glsl implements).
    BeckmannWalter,
    /// Beckmann, separable, exact Lambda with erf (the table of docs/techniques.md,
    /// "Reference values").
    BeckmannExact,
    GgxCorrelated,
    GgxSeparable,
}

fn lambda_beckmann_exact(w: DVec3, a: (f64, f64)) -> f64 {
    let t = ((a.0 * w.x).powi(2) + (a.1 * w.y).powi(2)).sqrt() / w.z;
    if t <= 0.0 {
        return 0.0;
    }
    let x = 1.0 / t;
    -0.5 * erfc(x) + (-x * x).exp() / (2.0 * x * PI.sqrt())
}

fn g1_walter(w: DVec3, a: (f64, f64)) -> f64 {
    let t = ((a.0 * w.x).powi(2) + (a.1 * w.y).powi(2)).sqrt() / w.z;
    if t <= 0.0 {
        return 1.0;
    }
    let x = 1.0 / t;
    if x >= 1.6 {
        1.0
    } else {
        (3.535 * x + 2.181 * x * x) / (1.0 + 2.276 * x + 2.577 * x * x)
    }
}

fn lambda_ggx(w: DVec3, a: (f64, f64)) -> f64 {
    let t2 = ((a.0 * w.x).powi(2) + (a.1 * w.y).powi(2)) / (w.z * w.z);
    ((1.0 + t2).sqrt() - 1.0) / 2.0
}

/// Cook-Torrance albedo with F = 1: E over h ~ D(h)(n.h) of G2 (v.h)/((n.v)(n.h)), integrated in
/// slope space over the azimuth psi of the slope (midpoint rule: spectral for a periodic integrand)
/// and the tilt beta of h up to the horizon bound beta* (so the integrand is smooth; Gauss-Legendre
/// panels), with u1(beta) the sampler's inverse: u1 = 1 - exp(-r^2) (Beckmann) or r^2 / (1 + r^2)
/// (GGX), r = tan(beta) / s.
fn ct_albedo(smith: Smith, a: (f64, f64), v: DVec3) -> f64 {
    const GL_X: [f64; 8] = [
        -0.960_289_856_497_536_2,
        -0.796_666_477_413_626_7,
        -0.525_532_409_916_329,
        -0.183_434_642_495_649_8,
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_2,
    ];
    const GL_W: [f64; 8] = [
        0.101_228_536_290_376_3,
        0.222_381_034_453_374_5,
        0.313_706_645_877_887_3,
        0.362_683_783_378_362,
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let ggx = matches!(smith, Smith::GgxCorrelated | Smith::GgxSeparable);
    let (n_psi, panels) = (1024, 64);
    let mut total = 0.0;
    for k in 0..n_psi {
        let psi = 2.0 * PI * (k as f64 + 0.5) / n_psi as f64;
        let (s, rstar, sv) = slope_bound(a, v, psi);
        let m = -sv / s;
        let beta_star = (rstar * s).atan();
        let mut inner = 0.0;
        for p in 0..panels {
            let lo = beta_star * p as f64 / panels as f64;
            let hi = beta_star * (p + 1) as f64 / panels as f64;
            for (x, w) in GL_X.iter().zip(GL_W) {
                let beta = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x;
                let (sb, cb) = beta.sin_cos();
                let r = sb / (cb * s);
                // du1/dbeta = du1/dr * dr/dbeta, dr/dbeta = 1 / (s cos^2 beta).
                let du_dr = if ggx {
                    2.0 * r / ((1.0 + r * r) * (1.0 + r * r))
                } else {
                    2.0 * r * (-r * r).exp()
                };
                let du = du_dr / (s * cb * cb);
                let h = DVec3::new(sb * m.x, sb * m.y, cb);
                let vh = v.dot(h);
                let l = 2.0 * vh * h - v;
                if vh <= 0.0 || l.z <= 0.0 {
                    continue;
                }
                let g = match smith {
                    Smith::BeckmannWalter => g1_walter(v, a) * g1_walter(l, a),
                    Smith::BeckmannExact => {
                        1.0 / ((1.0 + lambda_beckmann_exact(v, a))
                            * (1.0 + lambda_beckmann_exact(l, a)))
                    }
                    Smith::GgxCorrelated => 1.0 / (1.0 + lambda_ggx(v, a) + lambda_ggx(l, a)),
                    Smith::GgxSeparable => {
                        1.0 / ((1.0 + lambda_ggx(v, a)) * (1.0 + lambda_ggx(l, a)))
                    }
                };
                inner += w * 0.5 * (hi - lo) * du * g * vh / (v.z * h.z);
            }
        }
        total += inner;
    }
    total / n_psi as f64
}

/// Mean weight (albedo with F = 1) of N GPU samples and its standard error.
fn gpu_albedo(k: &Kernel, lobe: GpuLobe, theta_deg: f64, seed: u32) -> (f64, f64) {
    gpu_albedo_n(k, lobe, theta_deg, seed, N)
}

fn gpu_albedo_n(k: &Kernel, lobe: GpuLobe, theta_deg: f64, seed: u32, n: usize) -> (f64, f64) {
    let s = setup(theta_deg);
    let out = Samples(k.run(&s.params(lobe), &[[0f32; 4]], 0, n, seed, 3 * n));
    let (m, e, _) = mean_and_error((0..n).map(|i| out.weight(i).x));
    (m, e)
}

const ANGLES: [f64; 4] = [0.0, 45.0, 70.0, 85.0];

#[test]
fn dbrdf_albedo_matches_quadrature_and_the_course_table() {
    // docs/techniques.md, "Reference values" (Monte Carlo values, 4e5 samples each, rounded to
    // 1e-3).
    let table = [
        (0.05, [1.000, 1.000, 1.000, 0.891]),
        (0.2, [1.000, 0.998, 0.889, 0.619]),
        (0.5, [0.982, 0.846, 0.668, 0.543]),
        (1.0, [0.631, 0.605, 0.547, 0.514]),
    ];
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let mut seed = 100;
    for (alpha, row) in table {
        for (theta, tab) in ANGLES.iter().zip(row) {
            let reference = dbrdf_albedo((alpha, alpha), setup(*theta).v_local());
            // The table's own error: binomial sd of 4e5 samples plus rounding.
            let table_sd = (reference * (1.0 - reference) / 4e5).sqrt() + 0.5e-3 / 3.0;
            z_test(
                &format!("D-BRDF albedo table alpha {alpha} at {theta}° vs quadrature"),
                tab,
                table_sd,
                reference,
                0.0,
            );
            let (m, e) = gpu_albedo(&k, white(DIST_DBRDF, (alpha, alpha)), *theta, seed);
            seed += 1;
            // The weights are 0 or 1 (F = 1): under the null hypothesis their sd is binomial, which
            // also covers runs where every sample was valid (sample variance 0).
            let e = e.max((reference * (1.0 - reference) / N as f64).sqrt());
            z_test(
                &format!("D-BRDF albedo alpha {alpha} at {theta}° (GPU) vs quadrature"),
                m,
                e,
                reference,
                0.0,
            );
            assert!(m <= 1.0);
        }
    }
    // 0° has a closed form: 1 - exp(-1/alpha^2) (0.632 at alpha 1).
    assert!((dbrdf_albedo((1.0, 1.0), DVec3::Z) - (1.0 - (-1.0f64).exp())).abs() < 1e-12);
    // Anisotropic.
    for theta in ANGLES {
        let reference = dbrdf_albedo((0.05, 0.4), setup(theta).v_local());
        let (m, e) = gpu_albedo(&k, white(DIST_DBRDF, (0.05, 0.4)), theta, seed);
        seed += 1;
        let e = e.max((reference * (1.0 - reference) / N as f64).sqrt());
        z_test(
            &format!("D-BRDF albedo alpha (0.05, 0.4) at {theta}°"),
            m,
            e,
            reference,
            0.0,
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn beckmann_smith_albedo_matches_quadrature_and_the_table() {
    // docs/techniques.md, "Reference values": Cook-Torrance Beckmann + separable Smith with the
    // exact (erf) Lambda, Monte Carlo with 4e5 samples, rounded to 1e-3.
    let table = [
        (0.2, [1.000, 0.997, 0.933, 0.930]),
        (1.0, [0.462, 0.649, 0.820, 0.904]),
    ];
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let mut seed = 200;
    for (alpha, row) in table {
        for (theta, tab) in ANGLES.iter().zip(row) {
            let v = setup(*theta).v_local();
            let exact = ct_albedo(Smith::BeckmannExact, (alpha, alpha), v);
            let walter = ct_albedo(Smith::BeckmannWalter, (alpha, alpha), v);
            eprintln!(
                "Beckmann-Smith alpha {alpha} at {theta}°: exact Lambda {exact:.5}, Walter G1 {walter:.5} (difference {:+.1e}), table {tab}",
                walter - exact
            );
            // The weights vary (up to ~2), so the table's sd is bounded by that of a [0, 2] variable.
            let table_sd = 1.0 / 4e5f64.sqrt() + 0.5e-3 / 3.0;
            z_test(
                &format!(
                    "Beckmann-Smith albedo table alpha {alpha} at {theta}° vs exact-Lambda quadrature"
                ),
                tab,
                table_sd,
                exact,
                0.0,
            );
            let (m, e) = gpu_albedo(&k, white(DIST_BECKMANN_SMITH, (alpha, alpha)), *theta, seed);
            seed += 1;
            z_test(
                &format!(
                    "Beckmann-Smith albedo alpha {alpha} at {theta}° (GPU) vs Walter-G1 quadrature"
                ),
                m,
                e,
                walter,
                0.0,
            );
        }
    }
    for theta in ANGLES {
        let v = setup(theta).v_local();
        let reference = ct_albedo(Smith::BeckmannWalter, (0.4, 0.1), v);
        let (m, e) = gpu_albedo(&k, white(DIST_BECKMANN_SMITH, (0.4, 0.1)), theta, seed);
        seed += 1;
        z_test(
            &format!("Beckmann-Smith albedo alpha (0.4, 0.1) at {theta}°"),
            m,
            e,
            reference,
            0.0,
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn ggx_albedo_matches_quadrature() {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let mut seed = 300;
    for (dist, smith) in [
        (DIST_GGX_SMITH, Smith::GgxCorrelated),
        (DIST_GGX_SMITH_SEPARABLE, Smith::GgxSeparable),
    ] {
        for a in [(0.2, 0.2), (1.0, 1.0), (0.1, 0.5)] {
            for theta in ANGLES {
                let reference = ct_albedo(smith, a, setup(theta).v_local());
                let (m, e) = gpu_albedo(&k, white(dist, a), theta, seed);
                seed += 1;
                z_test(
                    &format!("GGX {smith:?} albedo alpha {a:?} at {theta}°"),
                    m,
                    e,
                    reference,
                    0.0,
                );
            }
        }
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn albedo_never_exceeds_one() {
    let ctx = context();
    let k = Kernel::new(&ctx, "sample_brdf", illum_test_kernels::SAMPLE_BRDF_PLAIN);
    let mut seed = 400;
    for dist in [
        DIST_DBRDF,
        DIST_BECKMANN_SMITH,
        DIST_GGX_SMITH,
        DIST_GGX_SMITH_SEPARABLE,
    ] {
        for a in [(0.01, 0.01), (0.3, 0.3), (1.0, 1.0)] {
            let mut line = String::new();
            for theta in [0.0, 30.0, 60.0, 75.0, 89.0] {
                let (m, e) = gpu_albedo_n(&k, white(dist, a), theta, seed, N / 4);
                seed += 1;
                line += &format!(" {theta}°: {m:.4}");
                // One-sided z-test of albedo <= 1. A lobe that reflects all (white, alpha 0.01)
                // has weights of exactly 1 up to float32 rounding: a few ulps of 1 at most.
                let z = (m - 1.0) / e.max(f64::MIN_POSITIVE);
                assert!(
                    m <= 1.0 + 4.0 * f64::from(f32::EPSILON) || normal_upper_p(z) > alpha(),
                    "model {dist} alpha {a:?} at {theta}°: albedo {m} ± {e} exceeds 1"
                );
            }
            eprintln!("model {dist} alpha {a:?}:{line}");
        }
    }
    assert_no_validation_messages(&ctx);
}
