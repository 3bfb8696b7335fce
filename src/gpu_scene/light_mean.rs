//! The mean radiance of a textured rect, disk or sphere light over its surface: the constant
//! radiance of its control variate (glsl/direct/control_variates.glsl; docs/techniques.md,
//! "Control variates", condition 2).
//!
//! The mean is taken of what `texture_lookup` returns, under the uv parametrization the light's
//! samples use (glsl/scene/surface.glsl): rect uv = the unit square, affine in area; disk
//! uv = 0.5 + local xy / 2R, the disk inscribed in the unit square; sphere uv = lat-long of the
//! outward normal, theta = pi v, area ∝ sin(pi v). The lookup (bilinear or nearest, any wrap) is a
//! polynomial of degree ≤ 1 in u and in v between the breakpoints {0, 1, i/W, (i + 1/2)/W}: the
//! quadrature works cell by cell between them, with 2×2 Gauss points in each cell (exact for the
//! rect, ~1e-9 relative for the sphere's smooth sin weight) and, for the disk, 8×8 sub-cells on
//! cells the rim crosses (the rim's share of the area is then ~1e-3 / max(W, H) of it, a
//! relative error far below the sample noise). The control stays unbiased with any constant
//! radiance; the mean is what makes it cancel the most variance.

use crate::layout::{GpuLight, LIGHT_DISK, LIGHT_RECT, LIGHT_SPHERE, NONE};
use crate::scene::{Material, Mesh, Scene, Texture};
use glam::{DVec2, DVec3, Vec3};

/// Sets `GpuLight.mean` (radiance × surface mean of the texture) of textured rect, disk and sphere
/// lights.
pub fn set_means(lights: &mut [GpuLight], textures: &[Texture]) {
    for l in lights.iter_mut().filter(|l| l.texture != NONE) {
        let kind = match l.kind {
            LIGHT_RECT => Parametrization::Rect,
            LIGHT_DISK => Parametrization::Disk,
            LIGHT_SPHERE => Parametrization::Sphere,
            _ => continue,
        };
        let mean = surface_mean(&textures[l.texture as usize], kind);
        l.mean = (Vec3::from(l.radiance).as_dvec3() * mean)
            .as_vec3()
            .to_array();
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Parametrization {
    Rect,
    Disk,
    Sphere,
}

/// Breakpoints of the lookup along an axis of n texels in [0, 1], sorted.
fn breakpoints(n: u32) -> Vec<f64> {
    let n = f64::from(n);
    let mut b: Vec<f64> = (0..=(2 * n as u64)).map(|k| k as f64 / (2.0 * n)).collect();
    b.dedup();
    b
}

/// Mean RGB of `t`'s lookup over the surface of the given parametrization.
pub fn surface_mean(t: &Texture, kind: Parametrization) -> DVec3 {
    let (bu, bv) = (breakpoints(t.width), breakpoints(t.height));
    // Gauss-Legendre, 2 points on [-1, 1].
    let g = 0.5 / 3f64.sqrt();
    let gauss = [0.5 - g, 0.5 + g];
    let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
    let rgb = |u: f64, v: f64| t.lookup(DVec2::new(u, v)).truncate();
    for v in bv.windows(2) {
        for u in bu.windows(2) {
            let (u0, du, v0, dv) = (u[0], u[1] - u[0], v[0], v[1] - v[0]);
            match kind {
                Parametrization::Rect | Parametrization::Sphere => {
                    for a in gauss {
                        for b in gauss {
                            let (x, y) = (u0 + a * du, v0 + b * dv);
                            let w = du
                                * dv
                                * if kind == Parametrization::Sphere {
                                    (std::f64::consts::PI * y).sin()
                                } else {
                                    1.0
                                };
                            sum += w * rgb(x, y);
                            weight += w;
                        }
                    }
                }
                Parametrization::Disk => {
                    let r2 = |x: f64, y: f64| (x - 0.5).powi(2) + (y - 0.5).powi(2);
                    // Nearest and farthest points of the cell from the centre.
                    let near = r2((0.5f64).clamp(u0, u[1]), (0.5f64).clamp(v0, v[1]));
                    let far = [u0, u[1]]
                        .iter()
                        .flat_map(|&x| [v0, v[1]].map(|y| r2(x, y)))
                        .fold(0.0, f64::max);
                    if near >= 0.25 {
                        continue;
                    }
                    let k = if far <= 0.25 { 1 } else { 8 };
                    let (su, sv) = (du / k as f64, dv / k as f64);
                    for i in 0..k {
                        for j in 0..k {
                            for a in gauss {
                                for b in gauss {
                                    let (x, y) =
                                        (u0 + (i as f64 + a) * su, v0 + (j as f64 + b) * sv);
                                    if r2(x, y) <= 0.25 {
                                        sum += su * sv * rgb(x, y);
                                        weight += su * sv;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        DVec3::ZERO
    }
}

/// `GpuLight.mean` of the emissive triangle `tri` (3 indices) of `mesh` with material `m`:
/// emission × `triangle_mean` of its emission texture (zero without one).
pub fn triangle_light_mean(scene: &Scene, mesh: &Mesh, tri: &[u32], m: &Material) -> [f32; 3] {
    let Some(tex) = m.emission_texture else {
        return [0.0; 3];
    };
    let uv = |k: usize| {
        mesh.uvs
            .as_ref()
            .map_or(DVec2::ZERO, |u| u[tri[k] as usize].as_dvec2())
    };
    let mean = triangle_mean(&scene.textures[tex as usize], [uv(0), uv(1), uv(2)]);
    (m.emission.as_dvec3() * mean).as_vec3().to_array()
}

/// Mean RGB of `t`'s lookup over a triangle light's surface, whose vertices have texture
/// coordinates `uv` (zero without UVs, as `triangle_light_texcoord` reads them): uniform by area
/// on the triangle is uniform on its uv footprint, an affine image of it. The footprint is
/// clipped to each cell between the lookup's breakpoints (where the lookup is one polynomial of
/// degree ≤ 2: bilinear) and each clipped piece fanned into triangles, integrated with the
/// interior 3-point rule of degree 2: exact up to rounding. Footprints over more than 2^20 cells
/// (uvs far outside [0, 1] on a wrapping texture) and degenerate ones fall back to 256² equal
/// sub-triangles with the same rule (error ~ the texel steps / 256 relative).
pub fn triangle_mean(t: &Texture, uv: [DVec2; 3]) -> DVec3 {
    let (su, sv) = (2.0 * f64::from(t.width), 2.0 * f64::from(t.height));
    let lo = uv[0].min(uv[1]).min(uv[2]);
    let hi = uv[0].max(uv[1]).max(uv[2]);
    let (i0, i1) = (
        (lo.x * su).floor(),
        (hi.x * su).ceil().max((lo.x * su).floor() + 1.0),
    );
    let (j0, j1) = (
        (lo.y * sv).floor(),
        (hi.y * sv).ceil().max((lo.y * sv).floor() + 1.0),
    );
    let area2 = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
    let extent = (hi - lo).length_squared().max(1.0 / (su * sv));
    let rgb = |p: DVec2| t.lookup(p).truncate();
    if (i1 - i0) * (j1 - j0) > f64::from(1u32 << 20) || area2 <= 1e-12 * extent {
        return subdivided_mean(&rgb, uv, 256);
    }
    let (mut sum, mut area) = (DVec3::ZERO, 0.0);
    for j in j0 as i64..j1 as i64 {
        let strip = clip(&uv, 1, j as f64 / sv, true);
        let strip = clip(&strip, 1, (j + 1) as f64 / sv, false);
        if strip.len() < 3 {
            continue;
        }
        let (a, b) = strip
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.x), b.max(p.x))
            });
        for i in (a * su).floor() as i64..(b * su).ceil() as i64 {
            let cell = clip(&strip, 0, i as f64 / su, true);
            let cell = clip(&cell, 0, (i + 1) as f64 / su, false);
            for k in 1..cell.len().saturating_sub(1) {
                let (s, a) = triangle_rule(&rgb, [cell[0], cell[k], cell[k + 1]]);
                sum += s;
                area += a;
            }
        }
    }
    if area > 0.0 {
        sum / area
    } else {
        subdivided_mean(&rgb, uv, 256)
    }
}

/// The polygon's part on one side of the line coordinate `axis` = `value` (Sutherland-Hodgman):
/// the side ≥ value when `above`, else ≤.
fn clip(poly: &[DVec2], axis: usize, value: f64, above: bool) -> Vec<DVec2> {
    let inside = |p: DVec2| {
        if above {
            p[axis] >= value
        } else {
            p[axis] <= value
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (k, &a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        if inside(a) {
            out.push(a);
        }
        if inside(a) != inside(b) {
            let f = (value - a[axis]) / (b[axis] - a[axis]);
            let mut x = a + (b - a) * f;
            x[axis] = value;
            out.push(x);
        }
    }
    out
}

/// (∫ f dA, area) over a triangle by the interior 3-point rule (barycentrics 2/3, 1/6, 1/6):
/// exact for polynomials of degree 2; its points lie inside, never on a cell edge.
fn triangle_rule(f: &impl Fn(DVec2) -> DVec3, p: [DVec2; 3]) -> (DVec3, f64) {
    let a = 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]).abs();
    let q = |x: usize, y: usize, z: usize| (4.0 * p[x] + p[y] + p[z]) / 6.0;
    (
        (f(q(0, 1, 2)) + f(q(1, 2, 0)) + f(q(2, 0, 1))) * (a / 3.0),
        a,
    )
}

/// Mean of f over the barycentric domain, split into n² equal triangles.
fn subdivided_mean(f: &impl Fn(DVec2) -> DVec3, uv: [DVec2; 3], n: u32) -> DVec3 {
    let at = |a: f64, b: f64| {
        uv[0] + (uv[1] - uv[0]) * (a / f64::from(n)) + (uv[2] - uv[0]) * (b / f64::from(n))
    };
    let centroid = |p: [DVec2; 3]| f((p[0] + p[1] + p[2]) / 3.0);
    let mut sum = DVec3::ZERO;
    for i in 0..n {
        for j in 0..n - i {
            let (a, b) = (f64::from(i), f64::from(j));
            sum += centroid([at(a, b), at(a + 1.0, b), at(a, b + 1.0)]);
            if i + j + 1 < n {
                sum += centroid([at(a + 1.0, b), at(a + 1.0, b + 1.0), at(a, b + 1.0)]);
            }
        }
    }
    sum / f64::from(n * n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{TextureFilter, TextureWrap};
    use glam::Vec4;

    fn tex(filter: TextureFilter, wrap: TextureWrap) -> Texture {
        let texels = (0..12)
            .map(|i| Vec4::new(i as f32, (i * i % 7) as f32, 1.0, 1.0))
            .collect();
        let mut t = Texture::new("t", 4, 3, texels);
        t.filter = filter;
        t.wrap = [wrap; 2];
        t
    }

    /// Brute-force mean by a fine midpoint grid (n × n), against the exact quadrature.
    fn brute(t: &Texture, kind: Parametrization, n: usize) -> DVec3 {
        let (mut s, mut w) = (DVec3::ZERO, 0.0);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let wt = match kind {
                    Parametrization::Rect => 1.0,
                    Parametrization::Sphere => (std::f64::consts::PI * y).sin(),
                    Parametrization::Disk => {
                        f64::from(u8::from((x - 0.5).powi(2) + (y - 0.5).powi(2) <= 0.25))
                    }
                };
                s += wt * t.lookup(DVec2::new(x, y)).truncate();
                w += wt;
            }
        }
        s / w
    }

    #[test]
    fn means_match_a_fine_grid() {
        for filter in [TextureFilter::Bilinear, TextureFilter::Nearest] {
            for wrap in [TextureWrap::Repeat, TextureWrap::Clamp] {
                let t = tex(filter, wrap);
                for kind in [
                    Parametrization::Rect,
                    Parametrization::Disk,
                    Parametrization::Sphere,
                ] {
                    let (a, b) = (surface_mean(&t, kind), brute(&t, kind, 1200));
                    // The fine grid's own error: ~1/n of the texel steps at the kinks and rim.
                    assert!(
                        (a - b).abs().max_element() < 2e-3,
                        "{filter:?} {wrap:?} {kind:?}: {a} vs {b}"
                    );
                }
            }
        }
        // Bilinear with repeat over the whole square: exactly the texel mean.
        let t = tex(TextureFilter::Bilinear, TextureWrap::Repeat);
        let m = surface_mean(&t, Parametrization::Rect);
        let texels = texel_mean(&t);
        assert!((m - texels).abs().max_element() < 1e-12, "{m} vs {texels}");
    }

    fn texel_mean(t: &Texture) -> DVec3 {
        t.texels
            .iter()
            .fold(DVec3::ZERO, |a, v| a + v.truncate().as_dvec3())
            / t.texels.len() as f64
    }

    #[test]
    fn triangle_means_match_a_fine_grid() {
        // Footprints inside the square, over its edges (wrap or clamp) and across texel edges,
        // either winding; the exact clipping quadrature against 1200² sub-triangles.
        let tris = [
            [(0.1, 0.2), (0.9, 0.3), (0.4, 0.95)],
            [(-0.3, 0.1), (1.4, 0.6), (0.2, 1.7)],
            [(0.5, 0.5), (0.5, 0.0), (1.0, 0.5)],
            [(0.26, 0.31), (0.27, 0.33), (0.255, 0.35)],
        ];
        for filter in [TextureFilter::Bilinear, TextureFilter::Nearest] {
            for wrap in [TextureWrap::Repeat, TextureWrap::Clamp] {
                let t = tex(filter, wrap);
                for tri in tris {
                    let uv = tri.map(|(a, b)| DVec2::new(a, b));
                    let a = triangle_mean(&t, uv);
                    let b = subdivided_mean(&|p| t.lookup(p).truncate(), uv, 1200);
                    assert!(
                        (a - b).abs().max_element() < 2e-3,
                        "{filter:?} {wrap:?} {tri:?}: {a} vs {b}"
                    );
                }
            }
        }
        // Two triangles tiling the square, bilinear with repeat: exactly the texel mean.
        let t = tex(TextureFilter::Bilinear, TextureWrap::Repeat);
        let (p00, p10, p11, p01) = (DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y);
        let m = 0.5 * (triangle_mean(&t, [p00, p10, p11]) + triangle_mean(&t, [p00, p11, p01]));
        let texels = texel_mean(&t);
        assert!((m - texels).abs().max_element() < 1e-12, "{m} vs {texels}");
        // No UVs: every point reads uv (0, 0).
        let z = triangle_mean(&t, [DVec2::ZERO; 3]);
        assert!((z - t.lookup(DVec2::ZERO).truncate()).abs().max_element() < 1e-12);
    }
}
