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
    // --width keeps the camera's aspect (the default scene is 2:1).
    assert_eq!(img.height, 24);
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
    // Whatever the machine has (lavapipe in CI, a GPU elsewhere): the name `illum devices` gives.
    let (_, listing, _) = illum(&["devices"]);
    let first = listing
        .lines()
        .next()
        .and_then(|l| l.split_once(": "))
        .and_then(|(_, rest)| rest.rsplit_once(" ("))
        .map(|(name, _)| name.to_string())
        .unwrap_or_else(|| panic!("cannot read `illum devices`:\n{listing}"));
    assert_clean_error(code, &err, &["no-such-gpu", &first]);
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

fn write_scene(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = common::temp_path(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

const SMALL_SCENE: &str = r#"{"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov_y": 40, "resolution": [8, 8]},
    "materials": {"m": {}},
    "shapes": {"ball": {"sphere": {"center": [0,0,0], "radius": 1}, "material": "m"}},
    "lights": {"sky": {"dome": {}}}}"#;

#[test]
fn scene_as_top_level_array_is_rejected() {
    let path = write_scene("array.json", format!("[{SMALL_SCENE}]").as_bytes());
    let (code, _, err) = illum(&["render", path.to_str().unwrap(), "-o", "x.exr"]);
    assert_clean_error(
        code,
        &err,
        &["array.json", "top level", "JSON object", "an array"],
    );
}

#[test]
fn null_field_is_rejected_with_its_field() {
    let text = SMALL_SCENE.replace(r#""fov_y": 40"#, r#""fov_y": 40, "up": null"#);
    let path = write_scene("null-up.json", text.as_bytes());
    let (code, _, err) = illum(&["render", path.to_str().unwrap(), "-o", "x.exr"]);
    assert_clean_error(code, &err, &["null-up.json", "camera.up", "null"]);
}

#[test]
fn utf8_byte_order_mark_is_accepted() {
    let mut bytes = b"\xef\xbb\xbf".to_vec();
    bytes.extend(SMALL_SCENE.as_bytes());
    let path = write_scene("bom.json", &bytes);
    let out = common::temp_path("bom.exr");
    let (code, _, err) = illum(&[
        "render",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.exists());
}

/// A scene file that never ends (a link to /dev/zero) is cut off at the cap, named.
#[test]
fn endless_scene_file_is_capped() {
    let path = common::temp_path("endless.json");
    let _ = std::fs::remove_file(&path);
    std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
    let start = std::time::Instant::now();
    let (code, _, err) = illum(&["render", path.to_str().unwrap(), "-o", "x.exr"]);
    assert_clean_error(
        code,
        &err,
        &["endless.json", "larger than 64 MiB", "/dev/zero"],
    );
    assert!(start.elapsed().as_secs_f64() < 10.0);
}

#[test]
fn missing_validation_layer_is_not_called_a_missing_vulkan_library() {
    let out = Command::new(env!("CARGO_BIN_EXE_illum"))
        .args(["render", "--validate", "--spp", "1", "--width", "8", "-o"])
        .arg(common::temp_path("layer.exr"))
        // The loader then looks for explicit layers only there.
        .env("VK_LAYER_PATH", "/nonexistent-layer-folder")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("VK_LAYER_KHRONOS_validation") && err.contains("not installed"),
        "{err}"
    );
    assert!(!err.contains("cannot load the Vulkan library"), "{err}");
}

#[test]
fn compare_rejects_technique_and_duplicate_techniques() {
    // --technique belongs to render; compare takes --techniques (a usage error: exit code 2).
    let (code, _, err) = illum(&["compare", "--technique", "mis"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--technique") && err.contains("--techniques"),
        "{err}"
    );
    let prefix = common::temp_path("dup");
    let (code, _, err) = illum(&[
        "compare",
        "--techniques",
        "mis,light,mis",
        "-o",
        prefix.to_str().unwrap(),
    ]);
    assert_clean_error(code, &err, &["--techniques", "mis is named twice"]);
}

#[test]
fn stress_names_a_bad_scenes_folder_and_how_to_fix_it() {
    let report = common::temp_path("stress.md");
    let r = report.to_str().unwrap();
    let (code, _, err) = illum(&["stress", "--scenes", "/no/such/scenes", "-o", r]);
    assert_clean_error(
        code,
        &err,
        &["/no/such/scenes", "no such folder", "scenes/stress"],
    );
    let empty = common::temp_path("empty-scenes");
    std::fs::create_dir_all(&empty).unwrap();
    let (code, _, err) = illum(&["stress", "--scenes", empty.to_str().unwrap(), "-o", r]);
    assert_clean_error(code, &err, &["empty-scenes", "holds no", "scenes/stress"]);
    assert!(!report.exists());
}

/// Every option of render and compare is documented, with its default.
#[test]
fn help_documents_options_and_defaults() {
    let (code, out, _) = illum(&["render", "--help"]);
    assert_eq!(code, 0);
    for needle in [
        "--height <HEIGHT>",
        "follows the camera's aspect",
        "[default: 16",
        "[default: illum.exr]",
        "[default: mis]",
        "[default: off]",
    ] {
        assert!(
            out.contains(needle),
            "render --help lacks {needle:?}:\n{out}"
        );
    }
    let (code, out, _) = illum(&["compare", "--help"]);
    assert_eq!(code, 0);
    for opt in [
        "--width",
        "--height",
        "--seed",
        "--device",
        "--trace",
        "--techniques",
    ] {
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with(opt))
            .unwrap_or_else(|| panic!("compare --help lacks {opt}:\n{out}"));
        assert!(
            line.len() > opt.len() + 20,
            "compare {opt} is undocumented: {line:?}"
        );
    }
}

/// Each integrator reads its own parameters and refuses the others by name and origin (the
/// command line, `--param`, the scene file); unknown integrators are refused everywhere, compare
/// included (it once rendered `full` for a name it did not know).
#[test]
fn integrators_refuse_parameters_and_names_they_do_not_take() {
    let out = common::temp_path("params.exr");
    let o = out.to_str().unwrap();
    let quick = ["--spp", "1", "--width", "8", "--height", "8", "-o", o];
    let (code, _, err) = illum(
        &[
            &["render", "--integrator", "direct", "--max-depth", "3"],
            &quick[..],
        ]
        .concat(),
    );
    assert_clean_error(
        code,
        &err,
        &[
            "direct integrator takes no parameter max_depth (--max-depth)",
            "light_samples",
        ],
    );
    let (code, _, err) = illum(&[&["render", "--param", "light_sample=3"], &quick[..]].concat());
    assert_clean_error(code, &err, &["light_sample (--param light_sample=3)"]);
    let (code, _, err) =
        illum(&[&["render", "--param", "light_samples=many"], &quick[..]].concat());
    assert_clean_error(code, &err, &["--param light_samples=many", "\"many\""]);
    let (code, _, err) = illum(&[&["render", "--integrator", "fool"], &quick[..]].concat());
    assert_clean_error(
        code,
        &err,
        &["unknown integrator \"fool\"", "direct, full, path"],
    );
    let (code, _, err) = illum(&[
        "compare",
        "--integrators",
        "direct,fool",
        "--time",
        "0.1",
        "-o",
        o,
    ]);
    assert_clean_error(code, &err, &["unknown integrator \"fool\"", "full-nocache"]);

    // A scene's section: read by the integrator it names, refused by name and file.
    let dir = common::temp_path("params-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.json");
    let write = |section: &str| {
        std::fs::write(
            &scene,
            format!(
                r#"{{"camera": {{"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 8]}},
                "lights": {{"sky": {{"dome": {{}}, "color": [1, 1, 1], "intensity": 1}}}},
                "integrator": {section}}}"#
            ),
        )
        .unwrap()
    };
    let s = scene.to_str().unwrap();
    write(r#"{"type": "path", "max_depth": 2, "specular_depth": 3}"#);
    let (code, _, err) = illum(&["render", s, "--spp", "1", "-o", o]);
    assert_clean_error(
        code,
        &err,
        &[
            "path integrator takes no parameter specular_depth",
            "s.json: integrator.specular_depth",
        ],
    );
    write(r#"{"type": "path", "max_depth": 0}"#);
    let (code, _, err) = illum(&["render", s, "--spp", "1", "-o", o]);
    assert_clean_error(code, &err, &["--max-depth counts path segments"]);
    // Another integrator on the command line leaves the section's parameters out; its own
    // options override the section's.
    let (code, _, err) = illum(&["render", s, "--spp", "1", "--integrator", "direct", "-o", o]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = illum(&["render", s, "--spp", "1", "--max-depth", "1", "-o", o]);
    assert_eq!(code, 0, "{err}");
    write(r#"{"type": "path", "max_depth": [2]}"#);
    let (code, _, err) = illum(&["render", s, "--spp", "1", "-o", o]);
    assert_clean_error(
        code,
        &err,
        &["integrator.max_depth", "a number, a boolean or a string"],
    );
}

/// A closed stderr (`illum render … 2>&1 | head -1` once head has quit) costs the render
/// nothing: the image is written and the exit code is 0 (`eprintln!` would panic at the first
/// line, before or after the write).
#[test]
fn a_closed_stderr_does_not_stop_a_render() {
    use std::process::Stdio;
    let out = common::temp_path("closed-stderr.exr");
    let _ = std::fs::remove_file(&out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_illum"))
        .args([
            "render",
            "--width",
            "32",
            "--spp",
            "4",
            "-o",
            out.to_str().unwrap(),
        ])
        .env("ILLUM_VALIDATION", "1")
        .stderr(Stdio::piped())
        .spawn()
        .expect("running illum");
    drop(child.stderr.take()); // the reader is gone: every write to stderr fails (EPIPE)
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0));
    assert!(out.exists(), "the image was not written");
}
