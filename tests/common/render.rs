//! Renders of test scenes on validated contexts, and what is read off them.

use super::{assert_no_validation_messages, context, scene, temp_path, trace_mode};
use illum::film::Window;
use illum::jobs::Part;
use illum::jobs::partial::{read_partial, write_partial};
use illum::render::{RenderOutput, RenderSettings, Renderer};
use illum::scene::Scene;
use illum::vk::Context;

pub fn render_with(ctx: &Context, scene: &Scene, spp: u32, seed: u64) -> RenderOutput {
    let settings = RenderSettings {
        spp,
        seed,
        trace: trace_mode(),
        ..Default::default()
    };
    Renderer::new(ctx.clone())
        .render(scene, &settings, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// One render per seed with the same renderer (its kernels compiled once).
pub fn render_seeds(
    renderer: &Renderer,
    scene: &Scene,
    s: &RenderSettings,
    seeds: &[u64],
) -> Vec<RenderOutput> {
    renderer
        .render_seeds(scene, s, seeds, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// Every pixel of every render exactly black, and shadow rays traced (more than two per pixel of
/// a `w` x `h` image): a fully shadowed scene.
pub fn assert_shadowed_black(outs: &[RenderOutput], w: u32, h: u32, name: &str) {
    for o in outs {
        for p in &o.film.beauty {
            assert_eq!(*p, [0.0; 3], "{name}: a shadowed pixel is lit");
        }
        assert!(
            o.stats.rays > u64::from(w * h * 2),
            "{name}: shadow rays were traced"
        );
    }
}

/// Renders on a fresh validated context and checks that validation stayed silent.
pub fn render(json: &str, spp: u32) -> RenderOutput {
    let ctx = context();
    let out = render_with(&ctx, &scene(json), spp, 0);
    assert_no_validation_messages(&ctx);
    out
}

/// Rec. 709 luminance of a pixel.
pub fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Independent renders (one per seed) summarised per `block` x `block` pixel block (whole
/// blocks only), followed by the whole image: for each, the mean luminance over the seeds and
/// the variance of that mean from the seeds' scatter.
pub fn block_stats(outs: &[RenderOutput], block: u32) -> Vec<(f64, f64)> {
    let per: Vec<Vec<f64>> = outs
        .iter()
        .map(|o| {
            let f = &o.film;
            let (bx, by) = (f.width / block, f.height / block);
            let mut v = vec![0.0; (bx * by) as usize + 1];
            for y in 0..f.height {
                for x in 0..f.width {
                    let l = luminance(f.beauty[(y * f.width + x) as usize]);
                    if x < bx * block && y < by * block {
                        v[((y / block) * bx + x / block) as usize] += l / f64::from(block * block);
                    }
                    v[(bx * by) as usize] += l / f64::from(f.width * f.height);
                }
            }
            v
        })
        .collect();
    let k = per.len() as f64;
    (0..per[0].len())
        .map(|b| {
            let m = per.iter().map(|p| p[b]).sum::<f64>() / k;
            let var = per.iter().map(|p| (p[b] - m).powi(2)).sum::<f64>() / (k - 1.0);
            (m, var / k)
        })
        .collect()
}

/// The channels of a film's EXR: beauty, then the AOV planes.
pub const EXR_CHANNELS: [&str; 16] = [
    "R",
    "G",
    "B",
    "Albedo.R",
    "Albedo.G",
    "Albedo.B",
    "N.X",
    "N.Y",
    "N.Z",
    "Z",
    "Emission.R",
    "Emission.G",
    "Emission.B",
    "Variance.R",
    "Variance.G",
    "Variance.B",
];

/// Renders one job of a split render and writes it as a partial EXR (`name`.exr in the test
/// folder), read back as a merge would; the sums must read back exactly.
pub fn render_part(r: &Renderer, scene: &Scene, s: &RenderSettings, name: &str) -> Part {
    let out = r
        .render(scene, s, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let path = temp_path(&format!("{name}.exr"));
    let info = illum::jobs::part_info(scene, s, &out, "test").unwrap();
    let job = out.sums().unwrap();
    write_partial(&path, &info, &job.sums).unwrap();
    let (info, sums) = read_partial(&path).unwrap();
    assert_eq!(sums, job.sums, "{name}: the partial EXR reads back exactly");
    Part { path, info, sums }
}

/// Four pixel windows of odd sizes that tile a 13x9 frame, none aligned with another's edges on
/// both axes: the crops split-render tests merge.
pub const ODD_TILES_13X9: [Window; 4] = [
    Window {
        x0: 0,
        y0: 0,
        x1: 5,
        y1: 4,
    },
    Window {
        x0: 5,
        y0: 0,
        x1: 13,
        y1: 4,
    },
    Window {
        x0: 0,
        y0: 4,
        x1: 7,
        y1: 9,
    },
    Window {
        x0: 7,
        y0: 4,
        x1: 13,
        y1: 9,
    },
];
