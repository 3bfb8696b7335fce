//! Conventions: texture filter and wrap modes, and the dome map conventions of
//! illum, Mitsuba 3 and pbrt-v4, against their documented mappings (f64 references in
//! src/scene/dome_map.rs and `Texture::lookup`).

use super::*;

/// Adds `texture` to a parsed scene and makes it the map of its dome (the dome must be the scene's
/// first light): test maps are made in code, not read from files.
fn with_dome_map(
    mut s: illum::scene::Scene,
    texture: illum::scene::Texture,
) -> illum::scene::Scene {
    s.textures.push(texture);
    s.lights[0].texture = Some(s.textures.len() as u32 - 1);
    s
}

fn dome_json(convention: &str, rotation: f64, camera: &str) -> String {
    format!(
        r#"{{"camera": {camera},
            "lights": {{"sky": {{"dome": {{"rotation": {rotation}, "convention": "{convention}"}}}}}}}}"#
    )
}

/// Convention: each dome convention puts a marked texel where its documentation says
/// (docs/scene-format.md): a camera aimed at the texel's centre, as the documented formulas place
/// it, sees it; aimed at the next texel's centre, it does not.
#[test]
fn each_dome_convention_puts_a_marked_texel_where_documented() {
    use glam::{DVec3, Vec4};
    use illum::scene::{DomeConvention, Texture, TextureFilter};
    let rotation: f64 = 30.0;
    let world = |m: DVec3| {
        let (s, c) = rotation.to_radians().sin_cos();
        DVec3::new(c * m.x + s * m.z, m.y, -s * m.x + c * m.z)
    };
    // The documented placement of texel (i, j)'s centre, in the map frame.
    let lat_long = |phi: f64, theta: f64| {
        DVec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    };
    let centre = |conv: DomeConvention, (w, h): (u32, u32), (i, j): (u32, u32)| -> DVec3 {
        let u = (f64::from(i) + 0.5) / f64::from(w);
        world(match conv {
            // u = 1/2 at -Z: phi = 2 pi (u - 1/2) from -Z toward +X; rows at (j + 1/2) / H.
            DomeConvention::Illum => lat_long(
                2.0 * PI * (u - 0.5),
                PI * (f64::from(j) + 0.5) / f64::from(h),
            ),
            // u = 0 at -Z; rows at theta = pi j / (H - 1).
            DomeConvention::Mitsuba => lat_long(2.0 * PI * u, PI * f64::from(j) / f64::from(h - 1)),
            // pbrt's equal-area square in pbrt's frame, whose (x, y, z) is illum's (x, -z, y).
            DomeConvention::Pbrt => {
                let p = illum::scene::dome_map::equal_area_square_to_sphere(glam::DVec2::new(
                    u,
                    (f64::from(j) + 0.5) / f64::from(h),
                ));
                DVec3::new(p.x, p.z, -p.y)
            }
        })
    };
    let ctx = context();
    for (conv, name, size, marked) in [
        (DomeConvention::Illum, "illum", (8, 4), (5, 1)),
        (DomeConvention::Mitsuba, "mitsuba", (8, 5), (5, 1)),
        (DomeConvention::Pbrt, "pbrt", (8, 8), (5, 2)),
    ] {
        let mut texels = vec![Vec4::new(0.0, 0.0, 0.0, 1.0); (size.0 * size.1) as usize];
        texels[(marked.1 * size.0 + marked.0) as usize] = Vec4::new(1000.0, 1000.0, 1000.0, 1.0);
        let mut map = Texture::new("marked", size.0, size.1, texels);
        map.filter = TextureFilter::Nearest; // crisp texels (Mitsuba's envmap is bilinear anyway)
        for (target, expect_marked) in [(marked, true), ((marked.0 + 1, marked.1), false)] {
            let d = centre(conv, size, target);
            let camera = format!(
                r#"{{"position": [0, 0, 0], "look_at": [{}, {}, {}], "fov_y": 1, "resolution": [3, 3]}}"#,
                d.x, d.y, d.z
            );
            let s = with_dome_map(scene(&dome_json(name, rotation, &camera)), map.clone());
            let out = render_with(&ctx, &s, 16, 1);
            let c = f64::from(out.film.beauty[4][0]);
            if expect_marked {
                assert!(
                    (c - 1000.0).abs() <= 20.0,
                    "{name}: the marked texel's centre reads {c}, not 1000"
                );
            } else {
                assert!(
                    c <= 10.0,
                    "{name}: the next texel's centre reads {c}, not ~0"
                );
            }
        }
    }
    assert_no_validation_messages(&ctx);
}

/// Convention: under every convention (and the texture's filter and wrap modes), a
/// diffuse floor lit by a dome map with light sampling alone matches the float64 quadrature of
/// the documented mapping (src/stress/closed_form.rs): the sampling tables and pdfs follow the
/// lookup, with no part of the map left unsampled.
#[test]
fn dome_maps_light_a_floor_as_the_quadrature_says_under_every_convention() {
    use glam::Vec4;
    use illum::scene::{Texture, TextureFilter, TextureWrap};
    let ctx = context();
    let cases = [
        (
            "illum",
            (16, 8),
            TextureFilter::Bilinear,
            TextureWrap::Repeat,
        ),
        (
            "illum",
            (16, 8),
            TextureFilter::Nearest,
            TextureWrap::Repeat,
        ),
        (
            "illum",
            (16, 8),
            TextureFilter::Bilinear,
            TextureWrap::Mirror,
        ),
        (
            "mitsuba",
            (16, 9),
            TextureFilter::Bilinear,
            TextureWrap::Repeat,
        ),
        ("pbrt", (16, 16), TextureFilter::Nearest, TextureWrap::Clamp),
    ];
    let limit = z_limit(1e-3, cases.len());
    for (k, (name, (w, h), filter, wrap)) in cases.into_iter().enumerate() {
        // Dark but not black, with a bright patch in the upper hemisphere of every convention.
        let texels = (0..w * h)
            .map(|t| {
                let (i, j) = (t % w, t / w);
                // pbrt's square has the zenith at its centre, the lat-long maps in the top rows.
                let bright = if name == "pbrt" {
                    (i == 7 || i == 8) && j == 7
                } else {
                    (i == 3 || i == 4) && j == 2
                };
                let v = if bright {
                    40.0
                } else {
                    0.05 + 0.02 * (i % 3) as f32
                };
                Vec4::new(v, v * 0.8, v * 0.6, 1.0)
            })
            .collect();
        let mut map = Texture::new("sky", w, h, texels);
        map.filter = filter;
        map.wrap = [wrap; 2];
        let json = format!(
            r#"{{"camera": {{"position": [0, 3, 0.01], "look_at": [0, 0, 0], "fov_y": 30, "resolution": [{RES}, {RES}]}},
                "materials": {{"floor": {{"diffuse": [0.5, 0.5, 0.5]}}}},
                "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]}}, "material": "floor"}}}},
                "lights": {{"sky": {{"dome": {{"rotation": 40, "convention": "{name}"}}, "visible": false}}}}}}"#
        );
        let s = with_dome_map(scene(&json), map);
        let expected: Vec<Option<f64>> = illum::stress::closed_form::image(&s)
            .unwrap_or_else(|e| panic!("{name}: closed form: {e}"))
            .iter()
            .map(|p| Some(f64::from(p[0])))
            .collect();
        let out = render_with(&ctx, &s, 8, 40 + k as u64);
        let label = format!(
            "{name} dome, {filter:?}, {wrap:?} (closed form {:.5})",
            expected[0].unwrap()
        );
        assert_mean_matches(&out.film, &expected, limit, &label);
    }
    assert_no_validation_messages(&ctx);
}

/// Convention: texture filter and wrap modes, seen directly on an emissive quad whose
/// uvs run from u = -1 to u = 2, against the f64 reference lookup (`Texture::lookup`). Pixels
/// where the lookup is not linear across the pixel (a texel edge for nearest, a texel centre for
/// bilinear) are left out; elsewhere the pixel mean is the lookup at its centre, exactly.
#[test]
fn texture_filter_and_wrap_modes_read_as_documented() {
    use glam::{DVec2, Vec4};
    use illum::scene::{Texture, TextureFilter, TextureWrap};
    const W: u32 = 48;
    const SPP: u32 = 8;
    let json = r#"{"camera": {"position": [0, 0, 2], "look_at": [0, 0, 0], "fov_y": 28.072486935852954, "resolution": [48, 16]},
        "materials": {"glow": {"diffuse": [0, 0, 0], "emission": [1, 1, 1]}},
        "shapes": {"quad": {"mesh": {"positions": [[-1.5, -0.5, 0], [1.5, -0.5, 0], [1.5, 0.5, 0], [-1.5, 0.5, 0]],
                                     "uvs": [[-1, 1], [2, 1], [2, 0], [-1, 0]], "indices": [0, 1, 2, 0, 2, 3]},
                            "material": "glow"}}}"#;
    let ctx = context();
    let texels = [1.0f32, 2.0, 4.0, 8.0]
        .map(|v| Vec4::new(v, v, v, 1.0))
        .to_vec();
    for filter in [TextureFilter::Nearest, TextureFilter::Bilinear] {
        for wrap in [TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror] {
            let mut t = Texture::new("strip", 4, 1, texels.clone());
            t.filter = filter;
            t.wrap = [wrap; 2];
            let mut s = scene(json);
            s.textures.push(t.clone());
            s.materials[0].emission_texture = Some(0);
            let out = render_with(&ctx, &s, SPP, 2);
            let mut checked = 0;
            for x in 0..W {
                // u = x_plane + 1/2 across the image: pixel x spans u in [x/16 - 1, (x+1)/16 - 1].
                let (u0, u1) = (f64::from(x) / 16.0 - 1.0, f64::from(x + 1) / 16.0 - 1.0);
                let edge = match filter {
                    TextureFilter::Nearest => (u0 * 4.0).floor() != (u1 * 4.0 - 1e-9).floor(),
                    TextureFilter::Bilinear => {
                        (u0 * 4.0 - 0.5).floor() != (u1 * 4.0 - 0.5 - 1e-9).floor()
                    }
                };
                if edge {
                    continue;
                }
                // The lookup is linear across the pixel: the column's mean estimates it at the
                // centre, with the spread of a uniform over the pixel's range of values (0 for
                // nearest, where every sample reads the same texel).
                let e = t.lookup(DVec2::new(0.5 * (u0 + u1), 0.5)).x;
                let range =
                    (t.lookup(DVec2::new(u1, 0.5)).x - t.lookup(DVec2::new(u0, 0.5)).x).abs();
                let mean = (0..16)
                    .map(|y| f64::from(out.film.beauty[(y * W + x) as usize][0]))
                    .sum::<f64>()
                    / 16.0;
                let tol = 5.0 * range / (12.0 * f64::from(SPP) * 16.0).sqrt() + 1e-5 * e;
                assert!(
                    (mean - e).abs() <= tol,
                    "{filter:?}, {wrap:?}: column {x} at u {:.3} reads {mean}, expected {e} (± {tol})",
                    0.5 * (u0 + u1)
                );
                checked += 1;
            }
            assert!(
                checked >= 30,
                "{filter:?}, {wrap:?}: only {checked} columns checked"
            );
        }
    }
    assert_no_validation_messages(&ctx);
}
