//! Farm renders: `illum render --part K/N [--split samples|tiles]` cuts an image into
//! N jobs that `illum merge` puts back bit for bit, whatever N: N dividing the blocks or not,
//! more parts than blocks, tiles. `exr_channels_match` (ignored: run by scripts/test-slurm.sh
//! on two files named by ILLUM_EXR_A and ILLUM_EXR_B) compares a Slurm render with one process.

mod common;
use common::*;
use illum::cli::part::{Split, plan};
use illum::jobs::{Part, merge};
use illum::render::{RenderSettings, Renderer};
use std::path::Path;

/// 13x9 pixels, 600 samples: blocks 0..256, 256..512 and a short 512..600.
const SCENE: &str = SMALL_SCENE;
const SPP: u32 = 600;

/// N = 1, 2, 4, 7 by samples (3 blocks: N = 2 does not divide them, N = 4 and 7 split blocks into
/// row bands) and N = 3, 4 by tiles, merged, equal the render in one piece bit for bit.
#[test]
fn parts_merge_bit_identical_whatever_n() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let settings = |samples, crop| RenderSettings {
        spp: SPP,
        seed: 11,
        trace: trace_mode(),
        samples,
        crop,
        ..Default::default()
    };
    let whole = r
        .render(&scene, &settings(None, None), &mut |_, _| {})
        .unwrap();
    for (split, ns) in [(Split::Samples, &[1, 2, 4, 7][..]), (Split::Tiles, &[3, 4])] {
        for &n in ns {
            let jobs = plan(n, split, SPP, 13, 9).unwrap();
            let parts: Vec<Part> = jobs
                .iter()
                .enumerate()
                .map(|(k, j)| {
                    let s = settings(Some(j.samples), Some(j.crop));
                    render_part(&r, &scene, &s, &format!("farm-{}-{k}-of-{n}", split.name()))
                })
                .collect();
            let merged =
                merge(&parts).unwrap_or_else(|e| panic!("{} parts by {}: {e}", n, split.name()));
            assert_eq!(
                merged.film,
                whole.film,
                "{n} parts by {} merged differ from one render",
                split.name()
            );
        }
    }
    assert_no_validation_messages(&ctx);
}

/// Every channel of two EXRs, bit for bit; panics naming the first channel and pixel that differ.
fn assert_same_channels(a: &Path, b: &Path) {
    let ea = illum::output::read_exr(a).unwrap_or_else(|e| panic!("{e}"));
    let eb = illum::output::read_exr(b).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (ea.width, ea.height),
        (eb.width, eb.height),
        "{} and {} differ in size",
        a.display(),
        b.display()
    );
    let names = |e: &illum::output::ExrImage| e.channels.iter().map(|c| c.0.clone()).collect();
    let (na, nb): (Vec<String>, Vec<String>) = (names(&ea), names(&eb));
    assert_eq!(
        na,
        nb,
        "{} and {} have other channels",
        a.display(),
        b.display()
    );
    assert!(na.iter().any(|n| n == "R"), "no beauty in {}", a.display());
    for ((name, va), (_, vb)) in ea.channels.iter().zip(&eb.channels) {
        if let Some(i) = (0..va.len()).find(|&i| va[i].to_bits() != vb[i].to_bits()) {
            panic!(
                "channel {name} differs at pixel ({}, {}): {} in {}, {} in {}",
                i as u32 % ea.width,
                i as u32 / ea.width,
                va[i],
                a.display(),
                vb[i],
                b.display()
            );
        }
    }
}

/// The command line: `--part K/3` (samples) and `--part K/2 --split tiles` without --spp (the
/// default 16, as `illum render`) merge to `illum render`'s channels bit for bit.
#[test]
fn the_command_line_renders_parts_that_merge_exactly() {
    let scene_path = temp_path("farm-scene.json");
    std::fs::write(&scene_path, SCENE).unwrap();
    let scene = scene_path.to_str().unwrap();
    let path = |name: &str| temp_path(name).to_str().unwrap().to_owned();
    for (n, spp, split) in [(3u32, Some("600"), "samples"), (2, None, "tiles")] {
        let mut common = vec!["--seed", "4", "--trace", "bvh", "--quiet"];
        if let Some(s) = spp {
            common.extend(["--spp", s]);
        }
        let whole = path(&format!("farm-cli-whole-{split}.exr"));
        let mut args = vec!["render", scene, "-o", &whole];
        args.extend(&common);
        let (code, err) = illum_cli(&args);
        assert_eq!(code, 0, "illum {args:?}:\n{err}");
        let parts: Vec<String> = (0..n)
            .map(|k| path(&format!("farm-cli-{split}-{k}.exr")))
            .collect();
        for (k, p) in parts.iter().enumerate() {
            let part = format!("{k}/{n}");
            let mut args = vec!["render", scene, "-o", p, "--part", &part, "--split", split];
            args.extend(&common);
            let (code, err) = illum_cli(&args);
            assert_eq!(code, 0, "illum {args:?}:\n{err}");
        }
        let merged = path(&format!("farm-cli-merged-{split}.exr"));
        let mut args = vec!["merge", "-o", merged.as_str(), "--quiet"];
        args.extend(parts.iter().map(String::as_str));
        let (code, err) = illum_cli(&args);
        assert_eq!(code, 0, "illum merge:\n{err}");
        assert_same_channels(Path::new(&whole), Path::new(&merged));
    }
}

/// Bad part numbers and plans that do not fit fail before rendering, naming the value.
#[test]
fn bad_parts_are_refused_naming_the_value() {
    let scene_path = temp_path("farm-bad-scene.json");
    std::fs::write(&scene_path, SCENE).unwrap();
    let scene = scene_path.to_str().unwrap();
    let out = temp_path("farm-bad.exr");
    let out = out.to_str().unwrap();
    let (code, err) = illum_cli(&["render", scene, "-o", out, "--part", "4/4"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("\"4/4\"") && err.contains("0 to 3"), "{err}");
    let (code, err) = illum_cli(&["render", scene, "-o", out, "--split", "tiles"]);
    assert_eq!(code, 2, "--split without --part: {err}");
    assert!(err.contains("--part"), "{err}");
    let (code, err) = illum_cli(&[
        "render", scene, "-o", out, "--part", "0/2", "--crop", "0,0,1,1",
    ]);
    assert_eq!(code, 2, "--part with --crop: {err}");
    // 17 tiles: no 17x1 or 1x17 grid fits 13x9.
    let (code, err) = illum_cli(&[
        "render", scene, "-o", out, "--part", "0/17", "--split", "tiles",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("17 tiles") && err.contains("13x9"), "{err}");
    // 16 spp is one block: 10 parts would need 10 row bands of a 9-row image.
    let (code, err) = illum_cli(&["render", scene, "-o", out, "--part", "0/10"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("only 9 rows") && err.contains("at most 9 parts"),
        "{err}"
    );
    assert!(!Path::new(out).exists(), "a refused part wrote {out}");
}

/// Run by scripts/test-slurm.sh: the EXRs named by ILLUM_EXR_A and ILLUM_EXR_B (a Slurm render
/// and one process) hold the same channels bit for bit. Header times may differ.
#[test]
#[ignore = "run by scripts/test-slurm.sh with ILLUM_EXR_A and ILLUM_EXR_B"]
fn exr_channels_match() {
    let get = |v: &str| {
        std::env::var(v).unwrap_or_else(|_| panic!("{v} must name an EXR (scripts/test-slurm.sh)"))
    };
    assert_same_channels(
        Path::new(&get("ILLUM_EXR_A")),
        Path::new(&get("ILLUM_EXR_B")),
    );
}
