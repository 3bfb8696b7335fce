//! How a dome light's map covers the sphere, per [`DomeConvention`], in f64: the reference that
//! glsl/lights/dome_map.glsl and the `dome_texture` lookup of glsl/lights/lights.glsl implement, used
//! by the closed forms (src/stress/closed_form.rs) and the tests. Map coordinates (u, v) are in
//! [0, 1]², (0, 0) the top-left corner of the image.

use super::types::{DomeConvention, Texture, TextureWrap};
use glam::{DVec2, DVec3, DVec4};
use std::f64::consts::PI;

/// World direction to the map frame: undoes the dome's rotation of `rotation_deg` about +Y.
fn to_map_frame(rotation_deg: f64, d: DVec3) -> DVec3 {
    let (s, c) = rotation_deg.to_radians().sin_cos();
    DVec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
}

fn from_map_frame(rotation_deg: f64, d: DVec3) -> DVec3 {
    let (s, c) = rotation_deg.to_radians().sin_cos();
    DVec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

/// Map coordinates of the unit world direction `d`.
pub fn uv(convention: DomeConvention, rotation_deg: f64, d: DVec3) -> DVec2 {
    let m = to_map_frame(rotation_deg, d);
    match convention {
        // pbrt's light frame: its +Z is +Y here, its +Y is -Z.
        DomeConvention::Pbrt => equal_area_sphere_to_square(DVec3::new(m.x, -m.z, m.y)),
        DomeConvention::Illum | DomeConvention::Mitsuba => {
            let phi = m.x.atan2(-m.z);
            let theta = (m.x * m.x + m.z * m.z).sqrt().atan2(m.y);
            let u = phi / (2.0 * PI);
            let u = if convention == DomeConvention::Illum {
                u + 0.5
            } else {
                u.rem_euclid(1.0)
            };
            DVec2::new(u, theta / PI)
        }
    }
}

/// The unit world direction at map coordinates `uv`, and dω/du dv there.
pub fn direction(convention: DomeConvention, rotation_deg: f64, uv: DVec2) -> (DVec3, f64) {
    let (m, jacobian) = match convention {
        DomeConvention::Pbrt => {
            let p = equal_area_square_to_sphere(uv);
            (DVec3::new(p.x, p.z, -p.y), 4.0 * PI)
        }
        DomeConvention::Illum | DomeConvention::Mitsuba => {
            let u = if convention == DomeConvention::Illum {
                uv.x - 0.5
            } else {
                uv.x
            };
            let (phi, theta) = (2.0 * PI * u, PI * uv.y);
            let m = DVec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            (m, 2.0 * PI * PI * theta.sin())
        }
    };
    (from_map_frame(rotation_deg, m), jacobian)
}

/// The map's value at map coordinates `uv` as the convention looks it up: illum with the texture's
/// own filter and wrap; Mitsuba bilinear with rows at v = j/(H − 1), periodic in u and clamped in v;
/// pbrt the nearest texel.
pub fn lookup(t: &Texture, convention: DomeConvention, uv: DVec2) -> DVec4 {
    let (w, h) = (f64::from(t.width), f64::from(t.height));
    match convention {
        DomeConvention::Illum => t.lookup(uv),
        DomeConvention::Pbrt => {
            let i = ((uv.x * w).floor() as i64).clamp(0, i64::from(t.width) - 1);
            let j = ((uv.y * h).floor() as i64).clamp(0, i64::from(t.height) - 1);
            t.texel(i, j).as_dvec4()
        }
        DomeConvention::Mitsuba => {
            let x = uv.x * w - 0.5;
            let y = uv.y.clamp(0.0, 1.0) * (h - 1.0);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let texel = |i: i64, j: i64| {
                let i = TextureWrap::Repeat.index(i, i64::from(t.width));
                let j = TextureWrap::Clamp.index(j, i64::from(t.height));
                t.texels[(j * i64::from(t.width) + i) as usize].as_dvec4()
            };
            let (i, j) = (x0 as i64, y0 as i64);
            (texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx) * (1.0 - fy)
                + (texel(i, j + 1) * (1.0 - fx) + texel(i + 1, j + 1) * fx) * fy
        }
    }
}

/// Clarberg's equal-area octahedral map, pbrt-v4's EqualAreaSphereToSquare (exact atan).
pub fn equal_area_sphere_to_square(d: DVec3) -> DVec2 {
    let a = d.abs();
    let r = ((a.x * a.x + a.y * a.y) / (1.0 + a.z)).sqrt();
    let (big, small) = (a.x.max(a.y), a.x.min(a.y));
    let mut phi = if big == 0.0 {
        0.0
    } else {
        small.atan2(big) * 2.0 / PI
    };
    if a.x < a.y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    u = u.copysign(d.x);
    v = v.copysign(d.y);
    DVec2::new(0.5 * (u + 1.0), 0.5 * (v + 1.0))
}

/// pbrt-v4's EqualAreaSquareToSphere.
pub fn equal_area_square_to_sphere(p: DVec2) -> DVec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let sd = 1.0 - (up + vp);
    let r = 1.0 - sd.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * PI / 4.0;
    let z = (1.0 - r * r).copysign(sd);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mappings_invert() {
        for conv in [
            DomeConvention::Illum,
            DomeConvention::Mitsuba,
            DomeConvention::Pbrt,
        ] {
            for k in 0..200 {
                let (a, b) = (
                    (k as f64 * 0.618_034) % 1.0,
                    (k as f64 * 0.414_213 + 0.01) % 1.0,
                );
                let uvw = DVec2::new(a, 0.02 + 0.96 * b);
                let (d, _) = direction(conv, 37.0, uvw);
                let back = uv(conv, 37.0, d);
                assert!(
                    (back - uvw).abs().max_element() < 1e-9,
                    "{conv:?}: {uvw} -> {d} -> {back}"
                );
            }
        }
    }

    #[test]
    fn equal_area_square_has_uniform_measure() {
        // The Jacobian of the square-to-sphere map is 4π everywhere (away from its creases).
        for &(x, y) in &[(0.3, 0.2), (0.7, 0.55), (0.1, 0.9), (0.62, 0.31)] {
            let e = 1e-6;
            let p = |x: f64, y: f64| equal_area_square_to_sphere(DVec2::new(x, y));
            let du = (p(x + e, y) - p(x - e, y)) / (2.0 * e);
            let dv = (p(x, y + e) - p(x, y - e)) / (2.0 * e);
            let area = du.cross(dv).length();
            assert!((area - 4.0 * PI).abs() < 1e-4, "({x}, {y}): {area}");
        }
    }
}
