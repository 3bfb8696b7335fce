//! The command line: the default render works, and bad input gives a clear error (exit code 1,
//! the file/field/value named), never a panic.

mod common;
use std::process::Command;

fn illum(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_illum"))
        .args(args)
        .env("ILLUM_VALIDATION", "1")
        .output()
        .expect("running illum");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_clean_error(code: i32, err: &str, needles: &[&str]) {
    assert_eq!(code, 1, "expected exit code 1, stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    assert!(!err.contains("validation"), "validation message:\n{err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
}

/// Also: the header separates steady-state rendering from set-up (kernel compilation, upload,
/// build, warm-up), and the two add up to no more than the command's own wall time.
#[test]
fn renders_the_default_scene_to_exr_and_png() {
    let png = common::temp_path("default.png");
    let start = std::time::Instant::now();
    let (code, _, err) = illum(&[
        "render",
        "-o",
        png.to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "48",
        "--quiet",
    ]);
    assert_eq!(code, 0, "stderr:\n{err}");
    assert!(png.exists() && png.with_extension("exr").exists());
    let img = illum::output::read_exr(&png.with_extension("exr")).unwrap();
    let wall = start.elapsed().as_secs_f64();
    assert_eq!(img.width, 48);
    assert!(img.channel("Albedo.R").is_some());
    let seconds = |name: &str| -> f64 {
        img.attribute(name)
            .unwrap_or_else(|| panic!("missing {name}"))
            .parse()
            .unwrap()
    };
    let (render, setup) = (
        seconds("illum.renderSeconds"),
        seconds("illum.setupSeconds"),
    );
    assert!(
        render > 0.0 && setup > 0.0,
        "render {render} s, setup {setup} s"
    );
    assert!(
        render + setup <= wall,
        "render {render} s + setup {setup} s > wall {wall} s"
    );
}

#[test]
fn lists_devices() {
    let (code, out, err) = illum(&["devices"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("ray query:"), "{out}");
    assert!(out.contains("driver:"), "{out}");
}

#[test]
fn missing_scene_file_is_named() {
    let (code, _, err) = illum(&["render", "no/such/scene.json", "-o", "x.exr"]);
    assert_clean_error(code, &err, &["no/such/scene.json"]);
}

#[test]
fn bad_scene_value_is_named_with_its_field() {
    let path = common::temp_path("bad.json");
    std::fs::write(
        &path,
        r#"{"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov_y": 40},
            "materials": {"m": {}},
            "shapes": {"ball": {"sphere": {"center": [0,0,0], "radius": -1}, "material": "m"}}}"#,
    )
    .unwrap();
    let (code, _, err) = illum(&["render", path.to_str().unwrap(), "-o", "x.exr"]);
    assert_clean_error(code, &err, &["bad.json", "shapes.ball.sphere.radius", "-1"]);
}

#[test]
fn unknown_device_lists_the_devices() {
    let (code, _, err) = illum(&["render", "--device", "no-such-gpu", "-o", "x.exr"]);
    assert_clean_error(code, &err, &["no-such-gpu", "llvmpipe"]);
}

#[test]
fn bad_output_extension_and_zero_spp_are_rejected() {
    let (code, _, err) = illum(&["render", "-o", "out.tiff"]);
    assert_clean_error(code, &err, &["out.tiff", ".exr or .png"]);
    let out = common::temp_path("zero.exr");
    let (code, _, err) = illum(&["render", "-o", out.to_str().unwrap(), "--spp", "0"]);
    assert_clean_error(code, &err, &["samples per pixel"]);
}

#[test]
fn unwritable_output_is_named() {
    let (code, _, err) = illum(&[
        "render",
        "--spp",
        "1",
        "--width",
        "8",
        "-o",
        "/no/such/dir/x.exr",
        "--quiet",
    ]);
    assert_clean_error(code, &err, &["/no/such/dir/x.exr"]);
}

#[test]
fn compare_writes_table_plot_and_strip_and_matches_a_separate_render() {
    let dir = common::temp_path("compare");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.json");
    std::fs::write(
        &scene,
        r#"{"camera": {"position": [0, 1, 3], "look_at": [0, 0.4, 0], "fov_y": 40, "resolution": [24, 16]},
            "materials": {"m": {"diffuse": [0.4, 0.4, 0.4], "specular": [{"model": "dbrdf", "roughness": 0.2}]}},
            "shapes": {"s": {"sphere": {"center": [0, 0.4, 0], "radius": 0.4}, "material": "m"},
                       "f": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "m"}},
            "lights": {"l": {"sphere": {"center": [1, 1.5, 1], "radius": 0.2}, "intensity": 20}}}"#,
    )
    .unwrap();
    let s = scene.to_str().unwrap();
    let reference = dir.join("ref.exr");
    let r = reference.to_str().unwrap();
    let (code, _, err) = illum(&[
        "render", s, "-o", r, "--spp", "64", "--seed", "99", "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let prefix = dir.join("cmp");
    let (code, out, err) = illum(&[
        "compare",
        s,
        "--techniques",
        "light,mis",
        "--time",
        "0.3",
        "--reference",
        r,
        "-o",
        prefix.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "cmp-error.png",
        "cmp-strip.png",
        "cmp-light.exr",
        "cmp-mis.exr",
    ] {
        assert!(dir.join(f).exists(), "{f} missing; stdout:\n{out}");
    }
    // Table rows: technique, spp, seconds, relMSE, efficiency.
    for technique in ["light", "mis"] {
        let row: Vec<&str> = out
            .lines()
            .find(|l| l.starts_with(technique))
            .unwrap_or_else(|| panic!("no {technique} row in:\n{out}"))
            .split_whitespace()
            .collect();
        let (spp, relmse): (u32, f64) = (row[1].parse().unwrap(), row[3].parse().unwrap());
        let report = dir.join(format!("{technique}.csv"));
        let (code, _, err) = illum(&[
            "render",
            s,
            "-o",
            dir.join(format!("{technique}.exr")).to_str().unwrap(),
            "--technique",
            technique,
            "--spp",
            &spp.to_string(),
            "--reference",
            r,
            "--report",
            report.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
        let csv = std::fs::read_to_string(&report).unwrap();
        let last: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
        assert_eq!(last[1].parse::<u32>().unwrap(), spp);
        let separate: f64 = last[5].parse().unwrap();
        // Same seed and samples: the same image, so the same error (the table prints 5 digits).
        assert!(
            (separate - relmse).abs() <= 1e-4 * relmse,
            "{technique}: compare says {relmse}, render says {separate}"
        );
    }
}
