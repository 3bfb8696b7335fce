//! The dome's radiance projected on real spherical harmonics of order 2 (SH9), in world
//! directions: the control radiance L_SH of the dome's control variate (docs/techniques.md,
//! "Control variates", condition 2, and "Analytic unshadowed irradiance";
//! glsl/lights/irradiance.glsl `sh9_*`).
//!
//! L_lm = ∫ L(w) Y_lm(w) dω over the sphere, with L what the renderer looks up
//! (src/scene/dome_map.rs: the convention's map, filter, wrap and the rotation about +Y, the
//! reference of glsl/lights/dome_map.glsl), integrated over the map: dω = J du dv with J the
//! convention's Jacobian. Maps of up to 2^16 texels: the lookup is a polynomial of degree ≤ 1
//! in u and in v between its breakpoints (texel edges and centres; Mitsuba's rows at
//! j/(H − 1)), split further into at least 64 cells per axis, and the quadrature takes
//! Gauss-Legendre points in each cell, 3×3 up to about 1 M points, else 2×2. On a constant 8×8
//! lat-long map the other bands come out below 1e-11 of L_00; pbrt's octahedral square has
//! creases along its diagonals inside cells: 1e-7 there. Larger maps sum texels over blocks
//! (`project_blocks`), for the scene's load time: its error is stated there.
//!
//! The projected map is clamped at 4 times its mean luminance (`clamp_luminance`): SH9 smears
//! a sun over the whole sphere, a control that correlates badly with the samples.
//!
//! Precision and clamp only decide how much variance the control removes: the control stays
//! exact for any coefficients, because the kernel's G is the SH9 irradiance of the same L_SH that its
//! samples evaluate (Funk-Hecke: exact for a band-limited function).

use super::dome::{self, DomeTable, luminance};
use crate::scene::dome_map;
use crate::scene::{DomeConvention, Light, LightKind, Texture};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// The clamp of the projected map's luminance, in multiples of its mean (`clamp_luminance`), by
/// measurement (docs/control-variates.md): 1, 2, 4 and 8 do alike, no clamp is 2x worse.
const SH_CLAMP: f64 = 4.0;

/// Real SH basis Y_lm(d) of a unit direction, order 00, 1-1, 10, 11, 2-2, 2-1, 20, 21, 22, with
/// (x, y, z) the world axes (the same as `sh9_basis` in glsl/lights/irradiance.glsl).
pub fn basis(d: DVec3) -> [f64; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282_094_791_773_878_1,
        0.488_602_511_902_919_9 * y,
        0.488_602_511_902_919_9 * z,
        0.488_602_511_902_919_9 * x,
        1.092_548_430_592_079_2 * x * y,
        1.092_548_430_592_079_2 * y * z,
        0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
        1.092_548_430_592_079_2 * x * z,
        0.546_274_215_296_039_6 * (x * x - y * y),
    ]
}

/// L_SH(d) = Σ L_lm Y_lm(d) (the tests' reference of `sh9_eval`).
#[cfg(test)]
pub fn eval(c: &[DVec3; 9], d: DVec3) -> DVec3 {
    basis(d).iter().zip(c).map(|(y, c)| *c * *y).sum()
}

#[cfg(test)]
/// ∫ L_SH(w) max(0, n·w) dω = Σ A_l L_lm Y_lm(n), A = π, 2π/3, π/4 (Ramamoorthi & Hanrahan 2001).
pub fn irradiance(c: &[DVec3; 9], n: DVec3) -> DVec3 {
    const BAND: [usize; 9] = [0, 1, 1, 1, 2, 2, 2, 2, 2];
    let a = [PI, 2.0 * PI / 3.0, PI / 4.0];
    basis(n)
        .iter()
        .zip(c)
        .zip(BAND)
        .map(|((y, c), l)| *c * (a[l] * y))
        .sum()
}

/// The most luminance the projection takes of a point of the map: `SH_CLAMP` times the map's
/// mean (texels weighted by their rows' solid angle). SH9 spreads a small bright source (a sun)
/// over the whole sphere, and that lobe correlates badly with samples that the table aims at the
/// source: clamped, the control follows the smooth sky and leaves the sun to the samples.
fn clamp_luminance(t: &Texture, radiance: DVec3, convention: DomeConvention) -> f64 {
    let h = f64::from(t.height);
    let (mut sum, mut weight) = (0.0, 0.0);
    for j in 0..t.height {
        let row = match convention {
            DomeConvention::Pbrt => 1.0,
            DomeConvention::Mitsuba => (PI * f64::from(j) / (h - 1.0).max(1.0)).sin(),
            DomeConvention::Illum => (PI * (f64::from(j) + 0.5) / h).sin(),
        };
        for i in 0..t.width {
            let l = t.texel(i64::from(i), i64::from(j)).truncate().as_dvec3() * radiance;
            sum += row * luminance(l).max(0.0);
            weight += row;
        }
    }
    if weight > 0.0 && sum > 0.0 {
        SH_CLAMP * sum / weight
    } else {
        f64::INFINITY
    }
}

/// Breakpoints of the convention's lookup along one axis of n texels in [0, 1], sorted.
fn breakpoints(n: u32, extra_rows: Option<u32>) -> Vec<f64> {
    let mut b: Vec<f64> = (0..=2 * u64::from(n))
        .map(|k| k as f64 / (2.0 * f64::from(n)))
        .collect();
    if let Some(m) = extra_rows.filter(|&m| m > 0) {
        b.extend((0..=m).map(|j| f64::from(j) / f64::from(m)));
    }
    b.sort_by(f64::total_cmp);
    b.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    // At least 64 cells: the smooth factors vary too much over a small map's texels.
    let split = 64usize.div_ceil(b.len() - 1);
    let mut out = Vec::with_capacity((b.len() - 1) * split + 1);
    for w in b.windows(2) {
        out.extend((0..split).map(|k| w[0] + (w[1] - w[0]) * k as f64 / split as f64));
    }
    out.push(1.0);
    out
}

/// The sampling tables of dome light `l` with map `t` (src/gpu_scene/dome.rs) and its SH9
/// coefficients.
pub fn table(t: &Texture, l: &Light, convention: DomeConvention) -> DomeTable {
    let mut table = dome::build(t, l.radiance(), convention);
    let rotation = match l.kind {
        LightKind::Dome { rotation_deg, .. } => rotation_deg,
        _ => 0.0,
    };
    let sh = project(t, l.radiance().as_dvec3(), convention, rotation);
    table.sh = sh.map(|c| c.as_vec3().extend(0.0).to_array());
    table
}

/// SH9 coefficients (RGB, `radiance` ⊙ texture) of a dome whose map `t` covers the sphere as
/// `convention` says, rotated by `rotation_deg` about +Y. Maps of more than 2^16 texels take
/// `project_blocks` (scene load time: the quadrature took 0.9 s for 2048×1024).
pub fn project(
    t: &Texture,
    radiance: DVec3,
    convention: DomeConvention,
    rotation_deg: f64,
) -> [DVec3; 9] {
    if u64::from(t.width) * u64::from(t.height) > 1 << 16 {
        project_blocks(t, radiance, convention, rotation_deg)
    } else {
        project_exact(t, radiance, convention, rotation_deg)
    }
}

/// The luminance-clamped texel (i, j) times `radiance`.
fn clamped(l: DVec3, cap: f64) -> DVec3 {
    let lum = luminance(l);
    if lum > cap { l * (cap / lum) } else { l }
}

/// Large maps: the texels (each taken as its value times its centre's dω/du dv) summed over
/// blocks of k × k, k = ceil(sqrt(texels / 2^16)), and Y_lm taken at each block's centre:
/// O(texels) adds and 2^16 direction evaluations (24 ms for 2048×1024, 59 ms for 4096×2048, on
/// the loaded 2-core machine). Y_lm of order 2 varies by O(block angle²) over a block;
/// `blocks_match_the_quadrature` measured at most 8e-5 of L_00 on 512×256 maps with a hot texel
/// (k = 2) and checks 5e-4.
fn project_blocks(
    t: &Texture,
    radiance: DVec3,
    convention: DomeConvention,
    rotation_deg: f64,
) -> [DVec3; 9] {
    let (w, h) = (t.width, t.height);
    let k = ((f64::from(w) * f64::from(h) / 65536.0).sqrt().ceil() as u32).max(1);
    let cap = clamp_luminance(t, radiance, convention);
    let mitsuba = convention == DomeConvention::Mitsuba;
    // Row j's centre v and height: Mitsuba's rows lie on v = j / (H − 1).
    let row = |j: u32| {
        if mitsuba {
            let dv = 1.0 / f64::from(h.saturating_sub(1).max(1));
            let edge = j == 0 || j + 1 == h;
            (f64::from(j) * dv, if edge { 0.5 * dv } else { dv })
        } else {
            ((f64::from(j) + 0.5) / f64::from(h), 1.0 / f64::from(h))
        }
    };
    let du = 1.0 / f64::from(w);
    let mut c = [DVec3::ZERO; 9];
    for bj in (0..h).step_by(k as usize) {
        let je = (bj + k).min(h);
        for bi in (0..w).step_by(k as usize) {
            let ie = (bi + k).min(w);
            let mut sum = DVec3::ZERO;
            for j in bj..je {
                let (v, dv) = row(j);
                let jacobian = dome_map::direction(convention, rotation_deg, DVec2::new(0.5, v)).1;
                let mut s = DVec3::ZERO;
                for i in bi..ie {
                    let l = t.texel(i64::from(i), i64::from(j)).truncate().as_dvec3() * radiance;
                    s += clamped(l, cap);
                }
                sum += s * (jacobian * du * dv);
            }
            let uv = DVec2::new(
                0.5 * f64::from(bi + ie) * du,
                0.5 * (row(bj).0 + row(je - 1).0),
            );
            let (d, _) = dome_map::direction(convention, rotation_deg, uv);
            for (ck, y) in c.iter_mut().zip(basis(d)) {
                *ck += sum * y;
            }
        }
    }
    c
}

/// Gauss points between the lookup's breakpoints (see the header).
fn project_exact(
    t: &Texture,
    radiance: DVec3,
    convention: DomeConvention,
    rotation_deg: f64,
) -> [DVec3; 9] {
    let mitsuba_rows = (convention == DomeConvention::Mitsuba).then(|| t.height.saturating_sub(1));
    let (bu, bv) = (
        breakpoints(t.width, None),
        breakpoints(t.height, mitsuba_rows),
    );
    let cells = (bu.len() - 1) * (bv.len() - 1);
    let g2 = 0.5 / 3f64.sqrt();
    let g3 = 0.5 * 0.6f64.sqrt();
    let rule: &[(f64, f64)] = if cells * 9 <= 1 << 20 {
        &[
            (0.5 - g3, 5.0 / 18.0),
            (0.5, 4.0 / 9.0),
            (0.5 + g3, 5.0 / 18.0),
        ]
    } else {
        &[(0.5 - g2, 0.5), (0.5 + g2, 0.5)]
    };
    let cap = clamp_luminance(t, radiance, convention);
    let mut c = [DVec3::ZERO; 9];
    for v in bv.windows(2) {
        let dv = v[1] - v[0];
        for u in bu.windows(2) {
            let du = u[1] - u[0];
            for &(a, wa) in rule {
                for &(b, wb) in rule {
                    let uv = DVec2::new(u[0] + a * du, v[0] + b * dv);
                    let (d, jacobian) = dome_map::direction(convention, rotation_deg, uv);
                    let l = clamped(
                        dome_map::lookup(t, convention, uv).truncate() * radiance,
                        cap,
                    );
                    let w = jacobian * du * dv * wa * wb;
                    for (ck, y) in c.iter_mut().zip(basis(d)) {
                        *ck += l * (w * y);
                    }
                }
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::TextureFilter;
    use glam::Vec4;

    const CONVENTIONS: [DomeConvention; 3] = [
        DomeConvention::Illum,
        DomeConvention::Mitsuba,
        DomeConvention::Pbrt,
    ];

    #[test]
    fn constant_map_projects_on_the_constant_band_only() {
        // ∫ L Y_00 dω = L √(4π); every other band integrates to 0.
        for conv in CONVENTIONS {
            for filter in [TextureFilter::Bilinear, TextureFilter::Nearest] {
                let mut t = Texture::new("c", 8, 8, vec![Vec4::splat(0.7); 64]);
                t.filter = filter;
                let c = project(&t, DVec3::new(1.0, 2.0, 3.0), conv, 37.0);
                let l00 = DVec3::new(1.0, 2.0, 3.0) * f64::from(0.7f32) * (4.0 * PI).sqrt();
                let tol = if conv == DomeConvention::Pbrt {
                    1e-7
                } else {
                    1e-11
                };
                assert!(
                    ((c[0] - l00) / l00).abs().max_element() < tol,
                    "{conv:?} {filter:?}: {} vs {l00}",
                    c[0]
                );
                for (k, ck) in c.iter().enumerate().skip(1) {
                    assert!(
                        (*ck / l00).abs().max_element() < tol,
                        "{conv:?} {filter:?}: c[{k}] = {ck}"
                    );
                }
            }
        }
    }

    #[test]
    fn band_one_points_at_a_bright_texel_through_the_convention_and_rotation() {
        // One bright texel of a 16×8 map (nearest): L ≈ δ toward its centre, so (L11, L1-1, L10)
        // ∝ (x, y, z) of the direction dome_map gives that centre (its mean over the texel).
        for conv in CONVENTIONS {
            let (w, h) = if conv == DomeConvention::Pbrt {
                (16, 16)
            } else {
                (16, 8)
            };
            let (i, j) = (5u32, 2u32);
            let mut texels = vec![Vec4::ZERO; (w * h) as usize];
            texels[(j * w + i) as usize] = Vec4::ONE;
            let mut t = Texture::new("hot", w, h, texels);
            t.filter = TextureFilter::Nearest;
            let c = project(&t, DVec3::ONE, conv, 37.0);
            let axis = DVec3::new(c[3].x, c[1].x, c[2].x).normalize();
            // Mitsuba's lookup is bilinear between texel centres: its bright patch is centred on
            // the texel centre, at v = j / (H - 1).
            let centre = match conv {
                DomeConvention::Mitsuba => {
                    DVec2::new((i as f64 + 0.5) / w as f64, j as f64 / (h - 1) as f64)
                }
                _ => DVec2::new((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64),
            };
            let (d, _) = dome_map::direction(conv, 37.0, centre);
            assert!(axis.dot(d) > 0.995, "{conv:?}: {axis} vs {d}");
        }
    }

    #[test]
    fn blocks_match_the_quadrature() {
        // A 512×256 sky with a hot texel (under the clamp), each convention: the block sums
        // (k = 2) against the Gauss quadrature, within 5e-4 of L_00 (measured: 8e-5).
        for conv in CONVENTIONS {
            let (w, h) = if conv == DomeConvention::Pbrt {
                (362, 362)
            } else {
                (512, 256)
            };
            let texels = (0..w * h)
                .map(|k| {
                    let (i, j) = (k % w, k / w);
                    let s = 1.0 + (i as f32 * 0.05).sin() + 2.0 * (j as f32 / h as f32);
                    let hot = if (i, j) == (100, 40) { 50.0 } else { 0.0 };
                    Vec4::new(s + hot, 0.5 * s, 0.2 * s + hot, 1.0)
                })
                .collect();
            let mut t = Texture::new("sky", w, h, texels);
            t.filter = TextureFilter::Nearest;
            let radiance = DVec3::new(1.0, 0.9, 0.8);
            let (a, b) = (
                project_blocks(&t, radiance, conv, 37.0),
                project_exact(&t, radiance, conv, 37.0),
            );
            let scale = b[0].abs().max_element();
            for k in 0..9 {
                let e = (a[k] - b[k]).abs().max_element() / scale;
                assert!(e < 5e-4, "{conv:?}: c[{k}] {} vs {} ({e:.1e})", a[k], b[k]);
            }
        }
    }

    #[test]
    fn irradiance_is_the_clamped_cosine_integral_of_the_sh_function() {
        // Funk-Hecke: for arbitrary coefficients, the closed form equals ∫ L_SH max(0, n·w) dω
        // by a fine f64 quadrature in (cos θ, φ) about +Z (midpoint, 800 × 1600).
        let mut c = [DVec3::ZERO; 9];
        for (k, ck) in c.iter_mut().enumerate() {
            let x = k as f64;
            *ck = DVec3::new((1.3 * x).sin(), (0.7 * x + 1.0).cos(), 0.2 * x - 0.5);
        }
        for n in [
            DVec3::Y,
            DVec3::new(0.3, -0.5, 0.8).normalize(),
            DVec3::new(-0.9, 0.1, -0.2).normalize(),
        ] {
            let (nu, np) = (800, 1600);
            let mut sum = DVec3::ZERO;
            for a in 0..nu {
                let z = -1.0 + 2.0 * (a as f64 + 0.5) / nu as f64;
                let s = (1.0 - z * z).sqrt();
                for b in 0..np {
                    let phi = 2.0 * PI * (b as f64 + 0.5) / np as f64;
                    let w = DVec3::new(s * phi.cos(), s * phi.sin(), z);
                    sum += eval(&c, w) * n.dot(w).max(0.0);
                }
            }
            let quad = sum * (4.0 * PI / (nu * np) as f64);
            let e = irradiance(&c, n);
            assert!((quad - e).abs().max_element() < 1e-4, "{n}: {quad} vs {e}");
        }
    }
}
