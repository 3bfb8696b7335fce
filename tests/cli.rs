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

#[test]
fn renders_the_default_scene_to_exr_and_png() {
    let png = common::temp_path("default.png");
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
    assert_eq!(img.width, 48);
    assert!(img.channel("Albedo.R").is_some());
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
