//! Many-light scenes for the light tree's tests and `illum bench lights`: a near-mirror floor
//! (where BRDF samples carry the MIS, so their PMF matters) with a glossy ball on it, under `n` small lights of equal total power scattered over it (a jittered
//! grid at varied heights, varied colours), unseen by the camera (only their light is measured:
//! a light seen directly adds pixel-coverage noise that no light selection changes). Radii shrink as 1/sqrt(n) so that the radiance, and
//! so the image's brightness, stays the same for every n.

use std::fmt::Write as _;

/// Which emitters the scene holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ManyLights {
    /// Sphere lights only.
    Spheres,
    /// Alternating sphere and one-sided rect lights, the rects tilted every which way (some face
    /// away from the floor: the tree's orientation cones must cull them, not bias the image).
    Mixed,
}

/// The scene as JSON, `width` x `height` pixels.
pub fn scene_json(n: usize, kind: ManyLights, width: u32, height: u32) -> String {
    let mut s = format!(
        r#"{{"camera": {{"position": [0, 7, 9], "look_at": [0, 0, 0], "fov_y": 55, "resolution": [{width}, {height}]}},
  "materials": {{"floor": {{"diffuse": [0.4, 0.4, 0.4], "specular": [{{"model": "ggx", "roughness": 0.05}}]}},
                "ball": {{"diffuse": [0.6, 0.5, 0.4], "specular": [{{"model": "ggx", "roughness": 0.3}}]}}}},
  "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [24, 24]}}, "material": "floor"}},
             "ball": {{"sphere": {{"center": [0, 1, 0], "radius": 1}}, "material": "ball"}}}},
  "lights": {{"#
    );
    let side = (n as f64).sqrt().ceil() as usize;
    let r = 0.4 / (n as f64 / 8.0).sqrt();
    let mut h: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut rnd = || {
        h ^= h << 13;
        h ^= h >> 7;
        h ^= h << 17;
        (h >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..n {
        let (gx, gz) = ((i % side) as f64, (i / side) as f64);
        let x = -10.0 + 20.0 * (gx + rnd()) / side as f64;
        let z = -10.0 + 20.0 * (gz + rnd()) / side as f64;
        let y = 0.4 + 2.6 * rnd();
        let color = [0.4 + 0.6 * rnd(), 0.4 + 0.6 * rnd(), 0.4 + 0.6 * rnd()];
        let sep = if i == 0 { "" } else { ",\n    " };
        let c = format!("[{:.4}, {:.4}, {:.4}]", color[0], color[1], color[2]);
        if kind == ManyLights::Mixed && i % 2 == 1 {
            // A square of the sphere's power per side: pi (2r)^2 L = pi 4 pi r^2 L / pi.
            let nrm = [rnd() - 0.5, -rnd() * 0.8 + 0.1, rnd() - 0.5];
            write!(
                s,
                r#"{sep}"l{i}": {{"rect": {{"center": [{x:.4}, {y:.4}, {z:.4}], "normal": [{:.3}, {:.3}, {:.3}], "size": [{:.5}, {:.5}]}}, "color": {c}, "intensity": {:.4}, "visible": false}}"#,
                nrm[0],
                nrm[1],
                nrm[2],
                2.0 * r,
                2.0 * r,
                std::f64::consts::PI * 2.0,
            )
            .unwrap();
        } else {
            write!(
                s,
                r#"{sep}"l{i}": {{"sphere": {{"center": [{x:.4}, {y:.4}, {z:.4}], "radius": {r:.6}}}, "color": {c}, "intensity": 2, "visible": false}}"#
            )
            .unwrap();
        }
    }
    s.push_str("}}\n");
    s
}
