//! UsdGeom's Cylinder, Cone and Capsule (and the `_1` schemas' unequal radii) as meshes: surfaces
//! of revolution about their axis, 256 segments around (the silhouette within 7.5e-5 of the
//! radius of the true surface), with the true surface's normals at the vertices so that
//! shading follows the quadric, and flat caps.

use crate::scene::format::MeshDef;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Segments around the axis, and of a capsule's half sphere from its pole to its equator.
const AROUND: usize = 256;
const HALF_SPHERE: usize = 64;

/// A point of a profile: radius from the axis, height along it, and the profile's outward
/// normal there (radial, axial).
type ProfilePoint = (f64, f64, f64, f64);

/// The (u, v, axis) frame of UsdGeom's `axis` token, right-handed (u × v = axis).
pub fn frame(axis: &str) -> Option<(DVec3, DVec3, DVec3)> {
    match axis {
        "X" => Some((DVec3::Y, DVec3::Z, DVec3::X)),
        "Y" => Some((DVec3::Z, DVec3::X, DVec3::Y)),
        "Z" => Some((DVec3::X, DVec3::Y, DVec3::Z)),
        _ => None,
    }
}

/// A frustum (a cylinder when the radii are equal, a cone when the top's is 0) of `height`
/// centred on the origin, capped where its radius is not 0.
pub fn frustum(bottom: f64, top: f64, height: f64, axis: (DVec3, DVec3, DVec3)) -> MeshDef {
    let (z0, z1) = (-height / 2.0, height / 2.0);
    let side = DVec3::new(height, bottom - top, 0.0).normalize();
    let mut strips = vec![vec![
        (bottom, z0, side.x, side.y),
        (top, z1, side.x, side.y),
    ]];
    if bottom > 0.0 {
        strips.push(vec![(0.0, z0, 0.0, -1.0), (bottom, z0, 0.0, -1.0)]);
    }
    if top > 0.0 {
        strips.push(vec![(top, z1, 0.0, 1.0), (0.0, z1, 0.0, 1.0)]);
    }
    revolve(&strips, axis)
}

/// A capsule: a cylinder of `height` and `radius` with half spheres of `radius` on its ends.
pub fn capsule(radius: f64, height: f64, axis: (DVec3, DVec3, DVec3)) -> MeshDef {
    let h = height / 2.0;
    let mut strip = Vec::new();
    // The poles exactly on the axis (cos(±π/2) is 6e-17 in floating point).
    let point = |phi: f64| {
        let (s, c) = phi.sin_cos();
        if c.abs() < 1e-12 {
            (0.0, s.signum())
        } else {
            (c, s)
        }
    };
    for k in 0..=HALF_SPHERE {
        let (c, s) = point(-FRAC_PI_2 + FRAC_PI_2 * k as f64 / HALF_SPHERE as f64);
        strip.push((radius * c, -h + radius * s, c, s));
    }
    for k in 0..=HALF_SPHERE {
        let (c, s) = point(FRAC_PI_2 * k as f64 / HALF_SPHERE as f64);
        strip.push((radius * c, h + radius * s, c, s));
    }
    revolve(&[strip], axis)
}

/// The strips of profile points revolved about the axis: rings of AROUND vertices joined by
/// triangles wound counter-clockwise seen from outside (a ring on the axis joins by one
/// triangle a segment).
fn revolve(strips: &[Vec<ProfilePoint>], (u, v, a): (DVec3, DVec3, DVec3)) -> MeshDef {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let around: Vec<(f64, f64)> = (0..AROUND)
        .map(|j| (TAU * j as f64 / AROUND as f64).sin_cos())
        .collect();
    for strip in strips {
        let first = positions.len() as u32;
        for &(r, z, nr, nz) in strip {
            for &(s, c) in &around {
                let radial = u * c + v * s;
                positions.push((radial * r + a * z).to_array());
                normals.push((radial * nr + a * nz).normalize().to_array());
            }
        }
        let at = |ring: usize, j: usize| first + (ring * AROUND + j % AROUND) as u32;
        for ring in 0..strip.len() - 1 {
            for j in 0..AROUND {
                let (p, q, r, s) = (
                    at(ring, j),
                    at(ring, j + 1),
                    at(ring + 1, j + 1),
                    at(ring + 1, j),
                );
                if strip[ring].0 > 0.0 {
                    indices.extend([p, q, r]);
                }
                if strip[ring + 1].0 > 0.0 {
                    indices.extend([p, r, s]);
                }
            }
        }
    }
    // Each triangle wound so that its face normal agrees with its vertices' normals.
    for t in indices.chunks_exact_mut(3) {
        let p = |i: u32| DVec3::from_array(positions[i as usize]);
        let n: DVec3 = t
            .iter()
            .map(|&i| DVec3::from_array(normals[i as usize]))
            .sum();
        if (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).dot(n) < 0.0 {
            t.swap(1, 2);
        }
    }
    MeshDef {
        positions,
        indices: Some(indices),
        normals: Some(normals),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mesh's signed volume (the divergence theorem over its triangles) and whether every
    /// edge is shared by exactly two triangles, in opposite directions (closed and consistently
    /// wound), vertices merged by position.
    fn volume_and_closed(m: &MeshDef) -> (f64, bool) {
        let p = |i: u32| DVec3::from_array(m.positions[i as usize]);
        let key = |i: u32| m.positions[i as usize].map(|x| (x * 1e9).round() as i64);
        let mut edges = std::collections::HashMap::new();
        let mut volume = 0.0;
        for t in m.indices.as_ref().unwrap().chunks_exact(3) {
            volume += p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0;
            for k in 0..3 {
                *edges.entry((key(t[k]), key(t[(k + 1) % 3]))).or_insert(0) += 1;
            }
        }
        let closed = edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
        (volume, closed)
    }

    #[test]
    fn quadrics_are_closed_outward_and_hold_their_volume() {
        use std::f64::consts::PI;
        let y = frame("Y").unwrap();
        // The inscribed polygon's area is sin(2π/n) n / (2π) of the circle's.
        let polygon = (TAU / AROUND as f64).sin() * AROUND as f64 / TAU;
        let cases = [
            ("cylinder", frustum(0.5, 0.5, 2.0, y), PI * 0.25 * 2.0),
            (
                "cone",
                frustum(1.0, 0.0, 2.0, frame("Z").unwrap()),
                PI * 2.0 / 3.0,
            ),
            (
                "frustum",
                frustum(1.0, 0.5, 1.0, frame("X").unwrap()),
                PI / 3.0 * (1.0 + 0.5 + 0.25),
            ),
            (
                "capsule",
                capsule(0.5, 1.0, y),
                PI * 0.25 + 4.0 / 3.0 * PI * 0.125,
            ),
        ];
        for (name, mesh, exact) in cases {
            let (v, closed) = volume_and_closed(&mesh);
            assert!(closed, "{name}: not closed");
            // Positive: outward; within the polygon's and (capsule) the latitudes' shortfall.
            let rel = v / (exact * polygon);
            assert!(
                rel > 0.999 && rel <= 1.0 + 1e-9,
                "{name}: volume {v} of {exact}: {rel}"
            );
            // Every vertex on the true surface's radius bound, its normal of unit length.
            for n in mesh.normals.as_ref().unwrap() {
                assert!((DVec3::from_array(*n).length() - 1.0).abs() < 1e-12);
            }
        }
        // The cylinder's side vertices lie on radius 0.5 about Y.
        let c = frustum(0.5, 0.5, 2.0, y);
        for p in &c.positions {
            let r = (p[0] * p[0] + p[2] * p[2]).sqrt();
            assert!(r < 1e-12 || (r - 0.5).abs() < 1e-12, "{p:?}");
        }
    }
}
