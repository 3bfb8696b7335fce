//! Same scene, same image: emissive geometry and a light of the same radiance agree at every
//! distance and size, lights are opaque objects (they cast shadows and hide what is behind
//! them), and an emitter never lights itself from the wrong side. Expectations come from float64
//! closed forms (src/stress/closed_form.rs) or exact geometry; the statistics use the scatter of
//! the per-pixel residuals, not the renderer's own variance report.

mod common;
#[path = "fidelity/maps.rs"]
mod maps;
use common::*;
use std::f64::consts::PI;

/// Checks the image mean against `expected` (pixels whose expectation is None are left out) by a
/// z-test at the two-sided limit `z`. The standard error comes from the residuals themselves:
/// pixels are independent, so under the hypothesis (every residual has zero mean) sum r_i^2 is
/// an unbiased estimate of the variance of sum r_i. 1e-5 of the expectation is allowed on top
/// for float32 rounding (zero-variance estimators). Returns the z.
fn assert_mean_matches(
    film: &illum::output::Film,
    expected: &[Option<f64>],
    z: f64,
    what: &str,
) -> f64 {
    let (mut sum, mut sq, mut abs, mut n) = (0.0, 0.0, 0.0, 0usize);
    for (p, e) in film.beauty.iter().zip(expected) {
        let Some(e) = e else { continue };
        let r = f64::from(p[0]) - e;
        sum += r;
        sq += r * r;
        abs += e.abs();
        n += 1;
    }
    assert!(n > 0, "{what}: no pixel to test");
    let tol = z * sq.sqrt() + 1e-5 * abs;
    let got = sum / sq.sqrt().max(1e-300);
    eprintln!(
        "{what}: mean residual {:.3e} over {n} pixels (z {got:.2})",
        sum / n as f64
    );
    assert!(
        sum.abs() <= tol,
        "{what}: image mean off by {:.4e} (relative {:.3e}; z = {got:.2}, limit {z:.2})",
        sum / n as f64,
        sum / abs
    );
    got
}

/// Two-sided z limit for `tests` tests at family-wise level `alpha` (Šidák).
fn z_limit(alpha: f64, tests: usize) -> f64 {
    z_for(1.0 - (1.0 - alpha).powf(1.0 / tests as f64))
}

fn mean(film: &illum::output::Film) -> f64 {
    film.beauty.iter().map(|p| f64::from(p[0])).sum::<f64>() / film.beauty.len() as f64
}

const RES: u32 = 24;
const ALBEDO: f64 = 0.5;

/// A sphere emitter of radius r at height 2r above a Lambert floor, seen from straight above at
/// distance `dist`, the view aimed at the floor 6r to the side so that the camera never sees the
/// emitter (and the closed form needs no visible light). `emitter` is the light or shape entry.
fn sphere_scene(r: f64, dist: f64, emitter: &str) -> String {
    let h = 2.0 * r;
    let target = 6.0 * r;
    let slant = (dist * dist + target * target).sqrt();
    let fov = 2.0 * (1.5 * r / slant).atan().to_degrees();
    format!(
        r#"{{"camera": {{"position": [0, {dist}, 0], "look_at": [{target}, 0, 0], "up": [0, 0, -1],
                        "fov_y": {fov}, "resolution": [{RES}, {RES}]}},
            "materials": {{"floor": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}},
                          "glow": {{"diffuse": [0, 0, 0], "emission": [100, 100, 100]}}}},
            "shapes": {{"floor": {{"rect": {{"center": [{target}, 0, 0], "normal": [0, 1, 0],
                                             "size": [{s}, {s}]}}, "material": "floor"}}
                        {emitter_shape}}},
            "lights": {{{emitter_light}}}}}"#,
        s = 40.0 * r,
        emitter_shape = if emitter == "shape" {
            format!(
                r#", "ball": {{"sphere": {{"center": [0, {h}, 0], "radius": {r}}}, "material": "glow"}}"#
            )
        } else {
            String::new()
        },
        emitter_light = if emitter == "light" {
            format!(
                r#""ball": {{"sphere": {{"center": [0, {h}, 0], "radius": {r}}}, "intensity": 100, "visible": false}}"#
            )
        } else {
            String::new()
        },
    )
}

/// A former bug: shadow rays ended inside a small emissive sphere when the shading point was
/// far from the camera (−20 % at 20 units, −23 % at 200). An emissive sphere and a sphere light of
/// the same radiance must both match the closed form over camera distances 1 to 1e4 and sizes
/// 1e-3 to 10.
#[test]
fn emissive_spheres_and_sphere_lights_match_the_closed_form_at_every_distance_and_size() {
    let cases = [
        (1e-3, 1.0),
        (1e-3, 20.0),
        (0.1, 20.0),
        (0.1, 200.0),
        (1.0, 1e4),
        (10.0, 1e3),
        (10.0, 1e4),
    ];
    let ctx = context();
    let limit = z_limit(1e-3, 2 * cases.len());
    for (k, (r, dist)) in cases.into_iter().enumerate() {
        let light_scene = scene(&sphere_scene(r, dist, "light"));
        let expected: Vec<Option<f64>> = illum::stress::closed_form::image(&light_scene)
            .unwrap_or_else(|e| panic!("closed form: {e}"))
            .iter()
            .map(|p| Some(f64::from(p[0])))
            .collect();
        let truth = expected.iter().flatten().sum::<f64>() / expected.len() as f64;
        assert!(
            truth > 0.0,
            "r {r}, distance {dist}: the view sees no light"
        );
        for (what, s) in [
            ("light", light_scene),
            ("shape", scene(&sphere_scene(r, dist, "shape"))),
        ] {
            let out = render_with(&ctx, &s, 16, 3 + k as u64);
            let label =
                format!("sphere {what} of radius {r} seen from {dist} (closed form {truth:.5})");
            assert_mean_matches(&out.film, &expected, limit, &label);
        }
    }
    assert_no_validation_messages(&ctx);
}

/// A former bug: a one-sided emissive sphere shell seen from its centre emits nothing inward
/// and so lights nothing inside: every pixel is exactly 0. Two-sided, each inner point sees the
/// whole shell: L = Le + rho Le exactly, checked as a mean.
#[test]
fn an_emissive_shell_lights_its_inside_only_when_two_sided() {
    let shell = |two_sided: bool| {
        format!(
            r#"{{"camera": {{"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 90, "resolution": [16, 16]}},
                "materials": {{"shell": {{"diffuse": [0.8, 0.8, 0.8], "emission": [1, 1, 1], "two_sided": {two_sided}}}}},
                "shapes": {{"shell": {{"sphere": {{"center": [0, 0, 0], "radius": 3}}, "material": "shell"}}}}}}"#
        )
    };
    let ctx = context();
    let one = render_with(&ctx, &scene(&shell(false)), 16, 5);
    let worst = one
        .film
        .beauty
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]))
        .fold(0.0f32, f32::max);
    assert_eq!(
        worst, 0.0,
        "a one-sided shell lit its own inside (up to {worst})"
    );
    let two = render_with(&ctx, &scene(&shell(true)), 16, 5);
    let expected = vec![Some(1.8); two.film.beauty.len()];
    assert_mean_matches(&two.film, &expected, z_for(1e-3), "two-sided shell");
    assert_no_validation_messages(&ctx);
}

/// A floor under a delta sun straight down, with a disk emitter hovering at height 1 facing up
/// (it lights nothing below): `disk` is its light or shape entry. The camera looks at the floor
/// from the side, so that it never sees the disk.
fn hover_scene(disk: &str) -> String {
    format!(
        r#"{{"camera": {{"position": [3, 2, 0], "look_at": [0, 0, 0], "fov_y": 28, "resolution": [{RES}, {RES}]}},
            "materials": {{"floor": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}},
                          "glow": {{"diffuse": [0, 0, 0], "emission": [4, 4, 4]}}}},
            "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]}}, "material": "floor"}}
                        {shape}}},
            "lights": {{"sun": {{"sun": {{"direction": [0, 1, 0], "angular_diameter": 0}}, "intensity": 1}}
                        {light}}}}}"#,
        shape = if disk.starts_with("shape") {
            r#", "disk": {"disk": {"center": [0, 1, 0], "normal": [0, 1, 0], "radius": 0.5}, "material": "glow"}"#
        } else {
            ""
        },
        light = match disk {
            "light" =>
                r#", "disk": {"disk": {"center": [0, 1, 0], "normal": [0, 1, 0], "radius": 0.5}, "intensity": 4}"#,
            "light-no-shadows" =>
                r#", "disk": {"disk": {"center": [0, 1, 0], "normal": [0, 1, 0], "radius": 0.5}, "intensity": 4, "shadows": false}"#,
            _ => "",
        },
    )
}

/// Per pixel: Some(1) where the floor it sees lies wholly in the disk's shadow, Some(0) wholly
/// outside it, None where the shadow's edge may cross the pixel or the pixel sees the disk. A 9x9
/// grid over the pixel including its edges, with a margin of 0.02 (a pixel spans ~0.075 of floor).
fn hover_shadow_fraction() -> Vec<Option<f64>> {
    use glam::DVec3;
    let pos = DVec3::new(3.0, 2.0, 0.0);
    let f = (-pos).normalize();
    let right = f.cross(DVec3::Y).normalize();
    let up = right.cross(f);
    let t = (28f64.to_radians() / 2.0).tan();
    let mut out = Vec::new();
    for y in 0..RES {
        for x in 0..RES {
            let (mut inside, mut outside, mut sees_disk) = (true, true, false);
            for j in 0..=8 {
                for i in 0..=8 {
                    let nx = 2.0 * (f64::from(x) + f64::from(i) / 8.0) / f64::from(RES) - 1.0;
                    let ny = 2.0 * (f64::from(y) + f64::from(j) / 8.0) / f64::from(RES) - 1.0;
                    let d = (f + nx * right * t - ny * up * t).normalize();
                    let q = pos + d * ((1.0 - pos.y) / d.y);
                    sees_disk |= q.x * q.x + q.z * q.z <= 0.27;
                    let p = pos + d * (-pos.y / d.y);
                    let r = (p.x * p.x + p.z * p.z).sqrt();
                    inside &= r < 0.48;
                    outside &= r > 0.52;
                }
            }
            out.push(match (sees_disk, inside, outside) {
                (false, true, _) => Some(1.0),
                (false, _, true) => Some(0.0),
                _ => None,
            });
        }
    }
    out
}

/// Convention: lights are opaque objects, like Mitsuba's and pbrt's. A disk light
/// hovering over a sunlit floor casts the disk's exact shadow (zero variance: a delta sun); with
/// "shadows": false it casts none; an emissive disk casts the same shadow.
#[test]
fn a_light_casts_a_shadow_unless_told_not_to() {
    let frac = hover_shadow_fraction();
    let lit = ALBEDO / PI;
    let count = |v: f64| frac.iter().filter(|&&f| f == Some(v)).count();
    assert!(count(1.0) >= 20, "the view misses the shadow");
    assert!(count(0.0) >= 100, "the view misses the lit floor");
    let ctx = context();
    for (what, shadows) in [
        ("light", true),
        ("shape", true),
        ("light-no-shadows", false),
    ] {
        let out = render_with(&ctx, &scene(&hover_scene(what)), 8, 9);
        for (i, (p, &f)) in out.film.beauty.iter().zip(&frac).enumerate() {
            let Some(f) = f else {
                continue; // the pixel sees the disk, or the shadow's edge may cross it
            };
            let e = if shadows { lit * (1.0 - f) } else { lit };
            assert!(
                (f64::from(p[0]) - e).abs() <= 1e-5 * e + 1e-6,
                "{what}: pixel {i} (shadowed fraction {f}) is {} instead of {e}",
                p[0]
            );
        }
    }
    assert_no_validation_messages(&ctx);
}

/// Two rect emitters facing down over a glossy floor, the lower one hiding most of the upper one:
/// BRDF samples (MIS) and light samples both stop at the first emitter. The two lights must give
/// the image the same emitters as geometry give (geometry occludes through the tracer alone).
#[test]
fn a_light_hides_the_light_behind_it_like_emissive_geometry() {
    let stacked = |as_lights: bool| {
        let entry = |name: &str, y: f64, size: f64, radiance: f64| {
            let geom = format!(
                r#""rect": {{"center": [0, {y}, 0], "normal": [0, -1, 0], "size": [{size}, {size}]}}"#
            );
            if as_lights {
                format!(r#""{name}": {{{geom}, "intensity": {radiance}}}"#)
            } else {
                format!(r#""{name}": {{{geom}, "material": "e{name}"}}"#)
            }
        };
        let (low, high) = (entry("low", 1.0, 0.8, 2.0), entry("high", 1.3, 0.6, 9.0));
        let floor = r#""floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [8, 8]}, "material": "floor"}"#;
        let (shapes, lights) = if as_lights {
            (floor.to_string(), format!("{low}, {high}"))
        } else {
            (format!("{floor}, {low}, {high}"), String::new())
        };
        format!(
            r#"{{"camera": {{"position": [2.5, 0.8, 0], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [{RES}, {RES}]}},
                "materials": {{"floor": {{"diffuse": [0.3, 0.3, 0.3], "specular": [{{"model": "ggx", "roughness": 0.15}}]}},
                              "elow": {{"diffuse": [0, 0, 0], "emission": [2, 2, 2]}},
                              "ehigh": {{"diffuse": [0, 0, 0], "emission": [9, 9, 9]}}}},
                "shapes": {{{shapes}}},
                "lights": {{{lights}}}}}"#
        )
    };
    let ctx = context();
    let a = render_with(&ctx, &scene(&stacked(true)), 32, 11);
    let b = render_with(&ctx, &scene(&stacked(false)), 32, 11);
    // Paired residuals (same seed, same samples): any systematic difference is a bug.
    let expected: Vec<Option<f64>> = b
        .film
        .beauty
        .iter()
        .map(|p| Some(f64::from(p[0])))
        .collect();
    let label = format!(
        "stacked lights ({:.5}) vs emissive geometry ({:.5})",
        mean(&a.film),
        mean(&b.film)
    );
    assert_mean_matches(&a.film, &expected, z_for(1e-3), &label);
    assert_no_validation_messages(&ctx);
}

/// Largest per-pixel Welch t (red channel) between two batch means; pixels where both batches
/// have no spread must agree to float rounding (else t = inf).
fn largest_t(a: &Batches, b: &Batches) -> (f64, f64) {
    let (mut worst, mut dof) = (0.0f64, f64::INFINITY);
    for i in 0..a.mean.len() {
        let (va, vb) = (a.var[i][0], b.var[i][0]);
        let d = (a.mean[i][0] - b.mean[i][0]).abs();
        let floor = 1e-6 * a.mean[i][0].abs().max(b.mean[i][0].abs()) + 1e-9;
        if d <= floor {
            continue;
        }
        let t = if va + vb > 0.0 {
            d / (va + vb).sqrt()
        } else {
            f64::INFINITY
        };
        let k = f64::from(a.k - 1);
        dof = dof.min(welch_dof(&[(va, k), (vb, k)]));
        worst = worst.max(t);
    }
    (worst, dof)
}

/// Convention: a sphere's "pole" orients its anisotropic tangents (Mitsuba's and
/// pbrt's dp/du, latitudes about the pole). A scene with the pole along +Z must render like the
/// same scene rotated so that +Z becomes +Y with the default pole (+Y): per pixel, Welch's t of
/// the two scenes' means over 8 independent renders each stays within the Šidák limit at 1e-3
/// over the pixels; and the same scene without its pole is rejected (the test has power). The
/// spread of independent renders, not an image-wide F-ratio, sets the scale: with scrambled
/// Sobol samples the error is uneven across pixels, so a few pixels carry an image-wide sum.
#[test]
fn a_sphere_pole_orients_its_anisotropy() {
    // R: rotation by -90 degrees about X, taking +Z to +Y: (x, y, z) -> (x, z, -y).
    let rot = |v: [f64; 3]| [v[0], v[2], -v[1]];
    let v = |a: [f64; 3]| format!("[{}, {}, {}]", a[0], a[1], a[2]);
    let sphere_scene = |rotated: bool, pole: Option<[f64; 3]>| {
        let r = |a: [f64; 3]| if rotated { v(rot(a)) } else { v(a) };
        let pole = pole
            .map(|p| format!(r#", "pole": {}"#, v(p)))
            .unwrap_or_default();
        format!(
            r#"{{"camera": {{"position": {}, "look_at": [0, 0, 0], "up": {}, "fov_y": 40, "resolution": [{RES}, {RES}]}},
                "materials": {{"brushed": {{"diffuse": [0.05, 0.05, 0.05],
                                          "specular": [{{"model": "beckmann", "roughness": [0.05, 0.4]}}]}}}},
                "shapes": {{"ball": {{"sphere": {{"center": [0, 0, 0], "radius": 1}}, "material": "brushed"{pole}}}}},
                "lights": {{"bulb": {{"sphere": {{"center": {}, "radius": 0.3}}, "intensity": 30}}}}}}"#,
            r([3.0, 1.0, 2.0]),
            r([0.0, 1.0, 0.0]),
            r([2.0, 3.0, 3.0]),
        )
    };
    let ctx = context();
    let renderer = illum::render::Renderer::new(ctx.clone());
    let batches = |json: String, seed: u64| {
        let settings = illum::render::RenderSettings {
            spp: 128,
            seed,
            trace: trace_mode(),
            ..Default::default()
        };
        Batches::render(&renderer, &scene(&json), &settings, 8)
    };
    let a = batches(sphere_scene(false, Some([0.0, 0.0, 1.0])), 1);
    let b = batches(sphere_scene(true, None), 2);
    let c = batches(sphere_scene(false, None), 3);
    let pixels = (RES * RES) as f64;
    let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / pixels);
    let (same, dof) = largest_t(&a, &b);
    let (other, dof_c) = largest_t(&c, &b);
    let (limit, limit_c) = (t_for(per, dof), t_for(per, dof_c));
    eprintln!(
        "largest |t|: pole +Z vs rotated {same:.2} (limit {limit:.2}), no pole vs rotated {other:.2} (limit {limit_c:.2})"
    );
    assert!(
        same <= limit,
        "pole +Z vs the rotated scene: |t| {same} over {limit}"
    );
    assert!(
        other > limit_c,
        "without a pole the scenes should differ: |t| {other} within {limit_c}"
    );
    assert_no_validation_messages(&ctx);
}
