//! Outputs of the command line: Ctrl-C keeps the work, bad output paths fail before any
//! rendering, no temporary file is ever left behind, and the first compile is announced.

mod common;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use common::{illum_cli as run, illum_command as illum};

/// Fails when `dir` holds a temporary file of illum's.
fn assert_no_temp_files(dir: &Path) {
    let left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".illum-tmp-"))
        .collect();
    assert!(
        left.is_empty(),
        "temporary files left in {}: {left:?}",
        dir.display()
    );
}

fn fresh_dir(name: &str) -> std::path::PathBuf {
    let d = common::temp_path(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// SIGINT during a render: exit status 130, and the EXR and PNG exist, read back, and hold
/// exactly the samples their header claims: the beauty equals that of a separate render of that
/// many samples (same seed, so the same samples) to float32 summation order, and a render of one
/// sample more or less differs by far more.
#[test]
fn sigint_keeps_the_samples_done_so_far() {
    let dir = fresh_dir("sigint");
    let png = dir.join("int.png");
    let child = illum()
        .args([
            "render",
            "--integrator",
            "direct",
            "-o",
            png.to_str().unwrap(),
            "--width",
            "16",
            "--spp",
            "1000000",
        ])
        .args(["--seed", "7", "--quiet"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Whenever the signal comes (set-up included), the render stops after a whole round of
    // dispatches, so at least one sample per pixel.
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: sending a signal to our own child.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "stderr:\n{err}");
    assert!(err.contains("interrupted by SIGINT"), "{err}");
    assert!(png.exists(), "no PNG; stderr:\n{err}");
    let exr = illum::output::read_exr(&png.with_extension("exr")).unwrap();
    assert_eq!(exr.attribute("illum.interrupted"), Some("true"));
    assert_eq!(exr.attribute("illum.sppRequested"), Some("1000000"));
    let spp: u32 = exr.attribute("illum.spp").unwrap().parse().unwrap();
    assert!((1..1000000).contains(&spp), "spp {spp}");
    eprintln!("interrupted at {spp} spp");
    image::open(&png).expect("the PNG reads back");
    assert_no_temp_files(&dir);

    let beauty_at = |n: u32| {
        let p = dir.join(format!("n{n}.exr"));
        let (code, err) = run(&[
            "render",
            "--integrator",
            "direct",
            "-o",
            p.to_str().unwrap(),
            "--width",
            "16",
            "--spp",
            &n.to_string(),
            "--seed",
            "7",
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
        let img = illum::output::read_exr(&p).unwrap();
        assert_eq!(img.attribute("illum.interrupted"), None);
        img.rgb().unwrap()
    };
    let interrupted = exr.rgb().unwrap();
    let max_rel = |other: &[[f32; 3]]| {
        interrupted
            .iter()
            .zip(other)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / a[c].abs().max(1e-3)))
            .fold(0.0f32, f32::max)
    };
    let same = max_rel(&beauty_at(spp));
    assert!(
        same < 1e-4,
        "the image is not {spp} spp: max relative difference {same}"
    );
    if spp > 1 {
        let fewer = max_rel(&beauty_at(spp - 1));
        assert!(
            fewer > 10.0 * same.max(1e-6),
            "{spp} vs {} spp: {fewer}",
            spp - 1
        );
    }
    let more = max_rel(&beauty_at(spp + 1));
    assert!(
        more > 10.0 * same.max(1e-6),
        "{spp} vs {} spp: {more}",
        spp + 1
    );
}

/// Output, PNG, report and plot paths in a missing or unwritable folder, or naming a folder,
/// fail in under a second with the path named, before any rendering (a million samples per
/// pixel asked for).
#[test]
fn bad_output_paths_fail_before_rendering() {
    let dir = fresh_dir("paths");
    let ok = dir.join("ok.exr");
    let ok = ok.to_str().unwrap();
    let missing = "/no/such/folder/out.exr";
    // /sys refuses new files even to root; a read-only folder would not stop root.
    let unwritable = "/sys/out.exr";
    let folder = dir.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (vec!["-o", missing], missing, "does not exist"),
        (vec!["-o", unwritable], unwritable, "cannot create a file"),
        (vec!["-o", folder], folder, "is a folder"),
        (
            vec!["-o", "/no/such/folder/out.png"],
            "/no/such/folder/out.png",
            "does not exist",
        ),
        (
            vec!["-o", ok, "--report", "/no/such/r.csv"],
            "/no/such/r.csv",
            "does not exist",
        ),
        (
            vec!["-o", ok, "--report-plot", "/sys/p.png"],
            "/sys/p.png",
            "cannot create",
        ),
    ];
    for (args, named, why) in cases {
        let start = Instant::now();
        let mut all = vec!["render", "--integrator", "direct", "--spp", "1000000"];
        all.extend(&args);
        let (code, err) = run(&all);
        let t = start.elapsed().as_secs_f64();
        eprintln!("{args:?}: failed in {:.3} s", t);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(named) && err.contains(why), "{args:?}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("compiling"),
            "{err}"
        );
        assert!(t < 1.0, "{args:?} took {t:.3} s to fail");
    }
    assert!(
        !dir.join("ok.exr").exists(),
        "rendered although a path was bad"
    );
    assert_no_temp_files(&dir);
    let (code, err) = run(&["compare", "-o", "/no/such/folder/cmp", "--time", "100"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("/no/such/folder/cmp-") && err.contains("does not exist"),
        "{err}"
    );
    let (code, err) = run(&["stress", "-o", "/no/such/folder/stress.md"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("/no/such/folder/stress.md"), "{err}");
}

/// A finished render replaces an existing file whole, and with its report and plot leaves only
/// its files.
#[test]
fn outputs_replace_files_whole_and_leave_no_temporaries() {
    let dir = fresh_dir("atomic");
    let exr = dir.join("a.exr");
    std::fs::write(&exr, "not an image yet").unwrap();
    let csv = dir.join("a.csv");
    let plot = dir.join("a-plot.png");
    let (code, err) = run(&[
        "render",
        "--integrator",
        "direct",
        "-o",
        exr.to_str().unwrap(),
        "--png",
        "--spp",
        "2",
        "--width",
        "16",
        "--quiet",
        "--report",
        csv.to_str().unwrap(),
        "--report-plot",
        plot.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    illum::output::read_exr(&exr).expect("the EXR replaced the old file");
    for p in [exr.with_extension("png"), csv, plot] {
        assert!(p.exists(), "{} missing", p.display());
    }
    assert_no_temp_files(&dir);
}

/// The first render of a feature combination says that it compiles kernels (forced here by
/// turning Mesa's shader cache off); --quiet keeps it silent.
#[test]
fn first_compile_is_announced() {
    let dir = fresh_dir("compile");
    let out = dir.join("c.exr");
    for quiet in [false, true] {
        let mut c = illum();
        c.args([
            "render",
            "--integrator",
            "direct",
            "-o",
            out.to_str().unwrap(),
            "--spp",
            "1",
            "--width",
            "8",
        ])
        .env("MESA_SHADER_CACHE_DISABLE", "true");
        if quiet {
            c.arg("--quiet");
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{err}");
        let said = err.contains("compiling kernels for this scene's features");
        assert_eq!(said, !quiet, "quiet: {quiet}, stderr:\n{err}");
    }
}

/// A report that cannot be written (its name taken by a folder made after the check, during
/// the render) never loses the image: the EXR is written first, then the error names the report.
#[test]
fn failing_report_keeps_the_image() {
    let dir = fresh_dir("report-fails");
    let exr = dir.join("kept.exr");
    let csv = dir.join("r.csv");
    let child = illum()
        .args([
            "render",
            "--integrator",
            "direct",
            "-o",
            exr.to_str().unwrap(),
            "--width",
            "16",
            "--spp",
            "1000000",
        ])
        .args(["--report", csv.to_str().unwrap(), "--quiet"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    std::fs::create_dir(&csv).unwrap();
    // SAFETY: sending a signal to our own child.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("r.csv") && err.contains("wrote"), "{err}");
    let img = illum::output::read_exr(&exr).expect("the image was kept");
    assert_eq!(img.attribute("illum.interrupted"), Some("true"));
    assert_no_temp_files(&dir);
}
