//! Mouse camera moves, in double precision: orbit about the camera's look-at point (yaw about
//! its up vector, pitch short of the poles), pan (the look-at point and the camera move in the
//! image plane, the point under the cursor staying under it at the look-at distance), and dolly
//! (towards the look-at point, which it never reaches).

use crate::scene::Camera;
use glam::DVec3;

/// Radians of orbit per pixel of drag.
const ORBIT_PER_PIXEL: f64 = 0.005;
/// The distance to the look-at point changes by this factor per wheel step.
const DOLLY_PER_STEP: f64 = 0.9;

pub fn orbit(c: &Camera, dx: f64, dy: f64) -> Camera {
    let up = c.up.normalize();
    let offset = c.position - c.look_at;
    let r = offset.length();
    let yawed = rotate(offset, up, -dx * ORBIT_PER_PIXEL);
    // Pitch about the camera's right axis, kept 1° short of either pole.
    let right = (-yawed).cross(up).normalize();
    let polar = yawed.normalize().dot(up).clamp(-1.0, 1.0).acos();
    let limit = 1f64.to_radians();
    let target = (polar + dy * ORBIT_PER_PIXEL).clamp(limit, std::f64::consts::PI - limit);
    let pitched = rotate(yawed, right, target - polar);
    Camera {
        position: c.look_at + pitched.normalize() * r,
        ..c.clone()
    }
}

pub fn pan(c: &Camera, dx: f64, dy: f64) -> Camera {
    let forward = c.look_at - c.position;
    let d = forward.length();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward.normalize());
    // Pixels to scene units at the look-at distance.
    let per_pixel = 2.0 * d * (c.fov_y_deg.to_radians() * 0.5).tan() / f64::from(c.height);
    let shift = (-dx * right + dy * up) * per_pixel;
    Camera {
        position: c.position + shift,
        look_at: c.look_at + shift,
        ..c.clone()
    }
}

pub fn dolly(c: &Camera, steps: f64) -> Camera {
    let offset = c.position - c.look_at;
    Camera {
        position: c.look_at + offset * DOLLY_PER_STEP.powf(steps),
        ..c.clone()
    }
}

/// `v` rotated by `angle` about the unit axis `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: DVec3::new(0.0, 1.0, 5.0),
            look_at: DVec3::new(0.0, 1.0, 0.0),
            up: DVec3::Y,
            fov_y_deg: 40.0,
            width: 64,
            height: 48,
        }
    }

    #[test]
    fn an_orbit_keeps_the_distance_and_the_look_at_point() {
        let c = camera();
        let o = orbit(&c, 120.0, -40.0);
        assert!(((o.position - o.look_at).length() - 5.0).abs() < 1e-12);
        assert_eq!(o.look_at, c.look_at);
        assert!(o.position.distance(c.position) > 0.5);
        // A quarter turn of yaw from +Z goes to +X or -X, at the same height.
        let q = orbit(&c, std::f64::consts::FRAC_PI_2 / ORBIT_PER_PIXEL, 0.0);
        assert!((q.position.y - 1.0).abs() < 1e-9 && (q.position.x.abs() - 5.0).abs() < 1e-9);
        // Pitch turns from the up vector by the drag: 100 px down, 0.5 rad further from it.
        let down = orbit(&c, 0.0, 100.0);
        let polar = (down.position - down.look_at)
            .normalize()
            .dot(DVec3::Y)
            .acos();
        assert!(
            (polar - (std::f64::consts::FRAC_PI_2 + 0.5)).abs() < 1e-9,
            "{polar}"
        );
        // Pitch stops short of the pole.
        let top = orbit(&c, 0.0, -1e6);
        assert!((top.position - top.look_at).normalize().dot(DVec3::Y) < 1.0 - 1e-5);
    }

    #[test]
    fn pan_moves_both_points_and_dolly_only_the_distance() {
        let c = camera();
        let p = pan(&c, 10.0, 0.0);
        assert_eq!(p.position - c.position, p.look_at - c.look_at);
        assert!((p.position.y - c.position.y).abs() < 1e-12);
        let d = dolly(&c, 2.0);
        assert!(((d.position - d.look_at).length() - 5.0 * 0.81).abs() < 1e-12);
    }
}
