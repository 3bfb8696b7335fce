//! Inline test scenes and their geometry.

use illum::scene::Scene;
use std::path::Path;

pub fn scene(json: &str) -> Scene {
    illum::scene::from_json_str(json, "<test scene>", Path::new("."))
        .unwrap_or_else(|e| panic!("test scene: {e}"))
}

/// A small scene for the render-core tests (jobs, farm, prepared scenes): a glossy floor, a
/// diffuse ball, a rect light and a dome, at 13x9 pixels (odd sizes on purpose).
pub const SMALL_SCENE: &str = r#"{"camera": {"position": [0, 1.2, 3], "look_at": [0, 0.3, 0], "fov_y": 40, "resolution": [13, 9]},
    "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6], "specular": [{"model": "ggx", "roughness": 0.2}]},
                  "ball": {"diffuse": [0.7, 0.3, 0.2]}},
    "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
               "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "ball"}},
    "lights": {"key": {"rect": {"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]}, "intensity": 6},
               "sky": {"dome": {}, "color": [0.2, 0.3, 0.4]}}}"#;

/// The floor points (y = 0) seen through each pixel of a w × h camera at `pos` looking at the
/// origin (vertical field of view `fov_deg`, up +Y), on a 4 × 4 grid of sub-pixel positions.
pub fn floor_points(pos: glam::DVec3, fov_deg: f64, w: u32, h: u32) -> Vec<Vec<glam::DVec3>> {
    let f = (-pos).normalize();
    let r = f.cross(glam::DVec3::Y).normalize();
    let u = r.cross(f);
    let t = (fov_deg.to_radians() / 2.0).tan();
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut pts = Vec::new();
            for j in 0..4 {
                for i in 0..4 {
                    let nx = 2.0 * (f64::from(x) + (f64::from(i) + 0.5) / 4.0) / f64::from(w) - 1.0;
                    let ny = 2.0 * (f64::from(y) + (f64::from(j) + 0.5) / 4.0) / f64::from(h) - 1.0;
                    let d = (f + nx * r * t - ny * u * t).normalize();
                    pts.push(pos + d * (-pos.y / d.y));
                }
            }
            out.push(pts);
        }
    }
    out
}

/// The irradiance at a floor point p (normal +Y) from a square light of radiance `l` and side
/// 2 `s`, facing down at height `h` above the origin: the polygon formula of
/// `illum::stress::closed_form`.
pub fn square_light_irradiance(l: f64, h: f64, s: f64) -> impl Fn(glam::DVec3) -> f64 + Copy {
    use glam::DVec3;
    let corners = [
        DVec3::new(-s, h, -s),
        DVec3::new(s, h, -s),
        DVec3::new(s, h, s),
        DVec3::new(-s, h, s),
    ];
    move |p: DVec3| {
        let rel: Vec<DVec3> = corners.iter().map(|c| *c - p).collect();
        l * illum::stress::closed_form::polygon_irradiance(DVec3::Y, &rel)
    }
}
