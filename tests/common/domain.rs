//! Parametrisations of (parts of) the sphere of directions by the unit square, the cells of the
//! chi-square tests of direction samplers (chi2.rs).

use glam::DVec3;

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
