//! Control variates of the dome (glsl/direct/control_variates.glsl; docs/techniques.md,
//! "Control variates", condition 2, and "Analytic unshadowed irradiance"): the
//! control radiance is the map's SH9 projection L_SH (src/gpu_scene/dome_sh.rs), G its SH9
//! irradiance, and the dome's sampler mixes in a uniform share so that its pdf is positive where
//! L_SH is not 0 (docs/control-variates.md).
//!
//! * Zero variance: a diffuse floor fully lit by a constant dome, or a dome whose map is uniform
//!   (its projection is then the constant band only, to ~1e-8): every sample equals G = rho L.
//! * Fully shadowed: inside a closed sphere every pixel is exactly 0.
//! * Unbiased (loo): a sky over a black lower hemisphere lights a glossy wall with an
//!   occluder. The wall's normal sees black texels, where the table's pdf is 0 and L_SH is not;
//!   without the uniform share the estimate is biased there. The glossy lobe's BRDF samples hit
//!   the dome with MIS weights from the same mixture pdf. Block means of 16 seeds against the
//!   plain estimator, Welch t, Šidák over the blocks.

mod common;
use common::*;
use glam::Vec4;
use illum::integrators::{ControlVariates, Direct, DirectLighting, Technique};
use illum::render::{RenderSettings, Renderer};
use illum::scene::{Scene, Texture, TextureFilter};

const W: u32 = 24;
const H: u32 = 16;
const ALBEDO: f64 = 0.5;
const RADIANCE: f64 = 2.0;

fn settings(cv: ControlVariates, spp: u32, light_samples: u32) -> RenderSettings {
    RenderSettings {
        spp,
        trace: trace_mode(),
        integrator: Direct(DirectLighting {
            technique: Technique::Mis,
            light_samples,
            // 8 N_max, not the default 2: the zero-variance case below needs 32 samples.
            dome_samples: 8,
            control_variates: cv,
            ..Default::default()
        })
        .into(),
        ..Default::default()
    }
}

/// A 40x40 plane through the origin with normal `n`, seen from 0.3 along it; `more` shapes
/// (", name: {...}"); a dome of radiance RADIANCE rotated by 37 degrees.
fn dome_scene(n: [f64; 3], more: &str) -> String {
    let c = n.map(|x| 0.3 * x);
    format!(
        r#"{{"camera": {{"position": [{}, {}, {}], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y": 60, "resolution": [{W}, {H}]}},
        "materials": {{"m": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}},
            "g": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}], "specular": [{{"model": "dbrdf", "roughness": 0.3, "fresnel": {{"schlick": [0.04, 0.04, 0.04]}}}}]}}}},
        "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [{}, {}, {}], "size": [40, 40]}}, "material": "m"}}{more}}},
        "lights": {{"sky": {{"dome": {{"rotation": 37}}, "color": [{RADIANCE}, {RADIANCE}, {RADIANCE}], "intensity": 1}}}}}}"#,
        c[0], c[1], c[2], n[0], n[1], n[2]
    )
}

/// The scene with a dome map of `w` x `h` texels given by `texel(i, j)`, nearest filter. With
/// `attach` false the texture is only added (so that the kernel has the same features).
fn with_map(json: &str, w: u32, h: u32, attach: bool, texel: impl Fn(u32, u32) -> Vec4) -> Scene {
    let mut sc = scene(json);
    let texels = (0..w * h).map(|k| texel(k % w, k / w)).collect();
    let mut t = Texture::new("map", w, h, texels);
    t.filter = TextureFilter::Nearest;
    sc.textures.push(t);
    if attach {
        sc.lights[0].texture = Some(sc.textures.len() as u32 - 1);
    }
    sc
}

/// The sky: rows above the horizon lit, varying in azimuth and colour; the lower half black.
fn sky(json: &str) -> Scene {
    with_map(json, 16, 8, true, |i, j| {
        if j < 4 {
            let a = 0.3 + 0.7 * (i as f32 / 15.0);
            Vec4::new(a, 0.6, 1.2 - a, 1.0)
        } else {
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        }
    })
}

#[test]
fn dome_fully_lit_plane_has_zero_variance() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let json = dome_scene([0.0, 1.0, 0.0], "");
    // E = pi L over the floor's hemisphere, so every pixel is rho L (x 0.7 for the uniform map).
    // The map's sampler puts about half of the samples below the horizon (untraced, g = 0), and
    // the control needs a traced sample (avgvis) or two (loo) to know the visibility: with 32
    // light samples, fewer than two above the horizon has probability 33 / 2^32 per pixel. The
    // textured dome takes 8 N_max samples here (settings), so N_max 4 gives it the same 32. The constant dome's
    // samples are cosine-weighted about the normal (glsl/lights/infinite_lights.glsl): each one
    // is rho L already, so the plain estimator is exact there too.
    let cases = [
        (
            "constant dome",
            with_map(&json, 4, 2, false, |_, _| Vec4::ONE),
            1.0,
            32,
            false,
        ),
        (
            "uniform map",
            with_map(&json, 4, 2, true, |_, _| Vec4::new(0.7, 0.7, 0.7, 1.0)),
            0.7,
            4,
            true,
        ),
    ];
    for (name, sc, scale, light_samples, plain_scatters) in cases {
        let expected = ALBEDO * RADIANCE * scale;
        for cv in [
            ControlVariates::Off,
            ControlVariates::AvgVis,
            ControlVariates::Loo,
        ] {
            let outs = render_seeds(&renderer, &sc, &settings(cv, 2, light_samples), &[3, 4]);
            let worst = outs
                .iter()
                .flat_map(|o| o.film.beauty.iter())
                .map(|p| (luminance(*p) / expected - 1.0).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "{name} {}: largest |pixel / expected - 1| = {worst:.2e}",
                cv.name()
            );
            if cv == ControlVariates::Off && plain_scatters {
                assert!(worst > 1e-2, "{name}: the plain estimator should scatter");
            } else {
                // float32 sums of 4 samples and the projection's 1e-8.
                assert!(worst < 1e-5, "{name}: a pixel is {worst:.2e} off rho L");
            }
        }
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn dome_fully_shadowed_plane_is_black() {
    // A closed sphere around camera and floor: every shadow ray is blocked, so both forms give
    // exactly 0 (without the visibility factor the control would add G).
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let ball = r#", "ball": {"sphere": {"center": [0, 0, 0], "radius": 5}, "material": "m"}"#;
    let sc = sky(&dome_scene([0.0, 1.0, 0.0], ball));
    for cv in [ControlVariates::AvgVis, ControlVariates::Loo] {
        let outs = render_seeds(&renderer, &sc, &settings(cv, 2, 4), &[5]);
        assert_shadowed_black(&outs, W, H, cv.name());
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn dome_leave_one_out_is_unbiased_with_a_black_ground() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    // A wall facing +X: the lower half of its lobe is black ground, where L_SH of this sky is
    // 0.5 + 0.75 y (times the sky's radiance, for a uniform sky): without the uniform share the
    // control would add about 18% of the unoccluded irradiance there (f64 quadrature).
    let ball =
        r#", "ball": {"sphere": {"center": [0.6, 0.1, 0.15], "radius": 0.2}, "material": "m"}"#;
    let json = dome_scene([1.0, 0.0, 0.0], ball)
        .replace(r#""material": "m"}, "ball""#, r#""material": "g"}, "ball""#);
    assert!(json.contains(r#""material": "g""#));
    let sc = sky(&json);
    let seeds = |base: u64| (0..16).map(|j| base * 64 + j).collect::<Vec<u64>>();
    let [plain, loo] = [(ControlVariates::Off, 1), (ControlVariates::Loo, 2)].map(|(cv, base)| {
        block_stats(
            &render_seeds(&renderer, &sc, &settings(cv, 4, 4), &seeds(base)),
            4,
        )
    });
    let lit = plain.last().unwrap().0;
    assert!(lit > 0.1, "the wall is dark: {lit}");
    let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / loo.len() as f64);
    let (mut vp, mut vl) = (0.0, 0.0);
    // (|t| / limit, block, t) of the worst block; the last "block" is the whole image.
    let mut worst = (0.0f64, 0usize, 0.0f64);
    for (b, (&(m1, v1), &(m0, v0))) in loo.iter().zip(&plain).enumerate() {
        let limit = t_for(per, welch_dof(&[(v1, 15.0), (v0, 15.0)]));
        let t = (m1 - m0) / (v1 + v0).sqrt();
        if b + 1 < loo.len() {
            vp += v0;
            vl += v1;
        }
        if t.abs() / limit > worst.0 {
            worst = (t.abs() / limit, b, t);
        }
    }
    let whole = (loo.last().unwrap().0, lit);
    eprintln!(
        "dome: worst block {} of {} at t = {:.2} ({:.2} x the limit); image {:.4} vs plain {:.4}; \
         variance of the block means: loo / plain = {:.3}",
        worst.1,
        loo.len(),
        worst.2,
        worst.0,
        whole.0,
        whole.1,
        vl / vp
    );
    assert!(
        worst.0 <= 1.0,
        "loo is biased: block {} at t = {:.2}",
        worst.1,
        worst.2
    );
    assert_no_validation_messages(&ctx);
}
