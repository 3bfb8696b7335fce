//! Witness blocks (src/film/split.rs): in an image of 512 blocks of 8 × 8 pixels or more, one
//! block in 16 takes two independent camera sequences (twice the samples) and the others one.
//! The witnesses' pixels have half the others' variance, the error estimate made from them
//! follows the true error pass by pass, and split renders still merge bit for bit.

mod common;
use common::*;
use illum::film::{Split, Window};
use illum::jobs::{Part, merge, part_info};
use illum::render::{RenderSettings, Renderer};

/// A Lambert plane (albedo 0.5) under a sun of 30° angular diameter, 45° from the normal, with
/// E⊥ = 3, at 256 × 128 (512 blocks): the radiance is 0.5/π · 3 · cos 45° everywhere
/// (tests/report.rs has it at 64 × 64, where every pixel splits).
const SUN_PLANE: &str = r#"{
    "camera": {"position": [0, 1, 0], "look_at": [0, 0, -1], "fov_y": 40, "resolution": [256, 128]},
    "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
    "shapes": {"floor": {"disk": {"center": [0, 0, -1], "normal": [0, 1, 0], "radius": 1000}, "material": "m"}},
    "lights": {"sun": {"sun": {"direction": [1, 1, 0], "angular_diameter": 30}, "intensity": 3}}}"#;
const W: u32 = 256;
const H: u32 = 128;
const SPP: u32 = 24;
const SEED: u64 = 5;

fn answer() -> f32 {
    (0.5 / std::f64::consts::PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2) as f32
}

fn settings(samples: Option<(u32, u32)>, crop: Option<Window>) -> RenderSettings {
    RenderSettings {
        spp: SPP,
        seed: SEED,
        trace: trace_mode(),
        samples,
        crop,
        ..Default::default()
    }
}

#[test]
fn witness_blocks_estimate_the_error_and_merge_exactly() {
    let split = Split::of_image(W, H, SEED);
    assert!(split.witnesses(), "256 x 128 has 512 blocks: witnesses");
    assert!(
        !Split::of_image(W, H - 8, SEED).witnesses(),
        "496 blocks: every pixel splits"
    );
    let ctx = context();
    let s = scene(SUN_PLANE);
    let r = Renderer::new(ctx.clone());
    let reference = vec![[answer(); 3]; (W * H) as usize];
    let whole = r
        .render(
            &s,
            &RenderSettings {
                reference: Some(reference),
                ..settings(None, None)
            },
            &mut |_, _| {},
        )
        .unwrap();
    assert_eq!(
        part_info(&s, &settings(None, None), &whole, "test")
            .unwrap()
            .witness,
        split.word()
    );

    // The witnesses took two sequences' samples: half the squared error of the other pixels,
    // each class a mean of grey χ²(1) terms (relative spread sqrt(2/n)), within 5 spreads.
    let (mut se, mut n) = ([0.0f64; 2], [0usize; 2]);
    for (i, p) in whole.film.beauty.iter().enumerate() {
        let (x, y) = (i as u32 % W, i as u32 / W);
        let k = usize::from(split.splits(x, y));
        se[k] += (f64::from(p[0]) - f64::from(answer())).powi(2);
        n[k] += 1;
    }
    assert_eq!(n[1] * 16, n[0] + n[1], "one block in 16 is a witness");
    let ratio = (se[1] / n[1] as f64) / (se[0] / n[0] as f64);
    let spread = (2.0 / n[1] as f64).sqrt() + (2.0 / n[0] as f64).sqrt();
    assert!(
        (ratio - 0.5).abs() < 5.0 * spread * 0.5,
        "witness pixels' squared error {ratio} of the others', expected 0.5"
    );

    // The estimate against the true error at every pass: the witnesses' terms (2048 pixels,
    // relative spread sqrt(2/2048)), the true error over every pixel (sqrt(2/32768)), within 5
    // spreads of their difference, plus the image-based denominator's bias (≤ 3 relMSE).
    let sd = (2.0f64 / 2048.0).sqrt() + (2.0f64 / 32768.0).sqrt();
    let mut checked = 0;
    for p in &whole.passes {
        let (Some(est), Some(err)) = (p.estimated_relmse, p.error) else {
            continue;
        };
        assert!(
            (est / err.relmse - 1.0).abs() < 5.0 * sd + 3.0 * err.relmse,
            "pass {} ({} spp): estimated relMSE {est}, true {}",
            p.pass,
            p.spp,
            err.relmse
        );
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} passes");

    // Jobs by sample range and by window (an edge inside a block) merge to the one render.
    let whole = r.render(&s, &settings(None, None), &mut |_, _| {}).unwrap();
    let parts: Vec<Part> = [(0, 7), (7, SPP)]
        .iter()
        .map(|&(a, b)| render_part(&r, &s, &settings(Some((a, b)), None), &format!("w-s{a}")))
        .collect();
    assert_eq!(
        merge(&parts).unwrap().film,
        whole.film,
        "sample ranges merged differ"
    );
    let tiles = [
        Window {
            x0: 0,
            y0: 0,
            x1: 100,
            y1: H,
        },
        Window {
            x0: 100,
            y0: 0,
            x1: W,
            y1: H,
        },
    ];
    let parts: Vec<Part> = tiles
        .iter()
        .map(|w| render_part(&r, &s, &settings(None, Some(*w)), &format!("w-c{}", w.x0)))
        .collect();
    assert_eq!(
        merge(&parts).unwrap().film,
        whole.film,
        "tiles merged differ"
    );
    assert_no_validation_messages(&ctx);
}
