//! Faults injected into the command line, each a defect found by a hostile probe: signals at any
//! point of a render or its write (`timeout`'s two SIGTERMs, a second Ctrl-C, SIGKILL), outputs
//! that would replace inputs, write-protected targets, sample counts past the 32-bit range. The
//! rule throughout: the previous file is intact or the new one is whole, no temporary file
//! survives the next run, and the exit status says whether the image was written (128 + signal:
//! written; 1: not).

mod common;
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::Duration;

use common::{illum_cli as run, illum_command as illum};

fn fresh_dir(name: &str) -> PathBuf {
    let d = common::temp_path(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn temp_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".illum-tmp-"))
        .collect()
}

/// A long render of the default scene into `out` (stderr piped).
fn long_render(out: &Path, extra: &[&str]) -> Child {
    illum()
        .args([
            "render",
            "--integrator",
            "direct",
            "--spp",
            "1000000",
            "--quiet",
        ])
        .args(["-o", out.to_str().unwrap()])
        .args(extra)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn signal(child: &Child, sig: i32) {
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, sig) };
}

fn finish(child: Child) -> (i32, String) {
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A long render into `out`, sent `sig` 1.5 s in and again `gap_ms` later: (exit status, stderr).
fn signal_twice(out: &Path, width: &str, sig: i32, gap_ms: u64) -> (i32, String) {
    let child = long_render(out, &["--width", width]);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, sig);
    std::thread::sleep(Duration::from_millis(gap_ms));
    signal(&child, sig);
    finish(child)
}

/// `timeout` sends SIGTERM to its child and then to the child's process group, microseconds
/// apart: that was taken as "quit at once" and lost the image (8 of 12 runs with the signals 1 ms
/// apart). Now a repeat within 200 ms is the same request, and SIGTERM never quits at once.
#[test]
fn repeated_sigterms_keep_the_image() {
    let dir = fresh_dir("sigterm-twice");
    for (k, gap_ms) in [0u64, 1, 5, 400].into_iter().enumerate() {
        let out = dir.join(format!("t{k}.exr"));
        let (code, err) = signal_twice(&out, "32", libc::SIGTERM, gap_ms);
        assert_eq!(code, 143, "gap {gap_ms} ms: stderr:\n{err}");
        let img = illum::output::read_exr(&out).unwrap_or_else(|e| panic!("gap {gap_ms} ms: {e}"));
        assert_eq!(img.attribute("illum.interrupted"), Some("true"));
    }
    assert_eq!(temp_files(&dir), Vec::<String>::new());
}

/// A second Ctrl-C (past the repeat window) quits at once, at whatever point it comes: the exit
/// status is 130 with a whole image, or 1 with no image and no temporary file.
#[test]
fn a_second_ctrl_c_leaves_a_whole_image_or_none() {
    let dir = fresh_dir("sigint-twice");
    for (k, gap_ms) in [250u64, 300, 400, 600].into_iter().enumerate() {
        let out = dir.join(format!("i{k}.png"));
        let (code, err) = signal_twice(&out, "512", libc::SIGINT, gap_ms);
        let exr = out.with_extension("exr");
        match code {
            130 => {
                let img = illum::output::read_exr(&exr).unwrap();
                assert_eq!(img.attribute("illum.interrupted"), Some("true"));
                image::open(&out).expect("the PNG reads back");
            }
            1 => {
                assert!(err.contains("quit"), "{err}");
                assert!(!exr.exists() || illum::output::read_exr(&exr).is_ok());
            }
            c => panic!("gap {gap_ms} ms: exit {c}, stderr:\n{err}"),
        }
        assert_eq!(
            temp_files(&dir),
            Vec::<String>::new(),
            "gap {gap_ms} ms: {err}"
        );
    }
}

/// SIGKILL at points spread over set-up, rendering and writing: the previous image stays
/// whole or is replaced whole, and the next write to the folder removes what the killed process
/// left.
#[test]
fn sigkill_never_leaves_a_broken_file_for_long() {
    let dir = fresh_dir("sigkill");
    let out = dir.join("k.exr");
    let (code, err) = run(&[
        "render",
        "--integrator",
        "direct",
        "--width",
        "64",
        "--spp",
        "1",
    ]
    .iter()
    .copied()
    .chain(["--quiet", "-o", out.to_str().unwrap()])
    .collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    for delay_ms in [200u64, 700, 1200, 1700, 2300] {
        let child = illum()
            .args([
                "render",
                "--integrator",
                "direct",
                "--width",
                "64",
                "--spp",
                "64",
                "--quiet",
            ])
            .args(["-o", out.to_str().unwrap()])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        signal(&child, libc::SIGKILL);
        let _ = finish(child);
        illum::output::read_exr(&out)
            .unwrap_or_else(|e| panic!("killed after {delay_ms} ms: the image is broken: {e}"));
    }
    // Whatever the kills left is gone after the next write into the folder.
    let (code, err) = run(&[
        "render",
        "--integrator",
        "direct",
        "--width",
        "16",
        "--spp",
        "1",
        "--quiet",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(temp_files(&dir), Vec::<String>::new());
}

/// An interrupted part job writes nothing, says so when the signal comes, and exits 1.
#[test]
fn an_interrupted_part_says_it_writes_nothing() {
    let dir = fresh_dir("part-int");
    let out = dir.join("part-0.exr");
    let child = long_render(&out, &["--width", "32", "--part", "0/2"]);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, libc::SIGTERM);
    let (code, err) = finish(child);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("writes nothing"), "{err}");
    assert!(!err.contains("to save the samples"), "{err}");
    assert!(!out.exists());
    assert_eq!(temp_files(&dir), Vec::<String>::new());
}

/// Outputs that would replace an input or each other fail before any work, naming both.
#[test]
fn outputs_never_replace_inputs() {
    let dir = fresh_dir("clash");
    let p = |n: &str| dir.join(n).to_str().unwrap().to_string();
    let (code, err) = run(&[
        "render",
        "--spp",
        "1",
        "--width",
        "16",
        "--quiet",
        "-o",
        &p("r.exr"),
    ]);
    assert_eq!(code, 0, "{err}");
    let before = std::fs::read(dir.join("r.exr")).unwrap();
    for (args, needles) in [
        (
            vec!["render", "-o", &p("x.exr"), "--report", &p("x.exr")],
            vec!["report output would replace the image output"],
        ),
        (
            vec![
                "render",
                "--width",
                "16",
                "-o",
                &p("r.exr"),
                "--reference",
                &p("r.exr"),
            ],
            vec!["would replace the reference"],
        ),
        (
            // -o r.png writes r.exr beside it: the reference.
            vec![
                "render",
                "--width",
                "16",
                "-o",
                &p("r.png"),
                "--reference",
                &p("r.exr"),
            ],
            vec!["image output would replace the reference"],
        ),
        (
            vec!["merge", &p("r.exr"), &p("s.exr"), "-o", &p("r.exr")],
            vec!["would replace the part"],
        ),
        (
            vec!["render", "-o", &p("y.exr"), "--report-plot", &p("plot.jpg")],
            vec!["plot.jpg", ".png"],
        ),
    ] {
        let (code, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: stderr lacks {n:?}:\n{err}");
        }
    }
    assert_eq!(
        std::fs::read(dir.join("r.exr")).unwrap(),
        before,
        "an input was replaced"
    );
    assert!(!dir.join("x.exr").exists() && !dir.join("y.exr").exists());
}

/// A write-protected target is refused (it was replaced, 0444 becoming 0644); a link is written
/// through and stays a link; a replaced file keeps its mode.
#[test]
fn existing_outputs_keep_their_kind_and_protection() {
    use std::os::unix::fs::PermissionsExt;
    let dir = fresh_dir("protect");
    let ro = dir.join("ro.exr");
    std::fs::write(&ro, "keep").unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).unwrap();
    let (code, err) = run(&["render", "--spp", "1", "-o", ro.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("write-protected"), "{err}");
    assert_eq!(std::fs::read_to_string(&ro).unwrap(), "keep");

    let real = dir.join("real.exr");
    std::fs::write(&real, "old").unwrap();
    std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o600)).unwrap();
    let link = dir.join("link.exr");
    std::os::unix::fs::symlink("real.exr", &link).unwrap();
    let (code, err) = run(&[
        "render",
        "--spp",
        "1",
        "--width",
        "16",
        "--quiet",
        "-o",
        link.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    illum::output::read_exr(&real).expect("the link's target holds the image");
    let mode = std::fs::metadata(&real).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
}

/// Sample counts whose 256-sample blocks pass 2^32 are refused (they wrapped: an all-NaN image
/// with exit 0, a partial whose header said 4294967290..0, "sample range 0..0").
#[test]
fn sample_counts_past_32_bits_are_refused() {
    let dir = fresh_dir("spp-overflow");
    let out = dir.join("x.exr");
    let o = out.to_str().unwrap();
    for args in [
        vec!["render", "--spp", "4294967041", "-o", o],
        vec![
            "render",
            "--spp",
            "4294967295",
            "--samples",
            "4294967290..4294967295",
            "-o",
            o,
        ],
        vec!["render", "--spp", "4294967295", "--part", "0/1", "-o", o],
    ] {
        let (code, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains("4294967040"), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote an image");
    }
}

/// A film that cannot fit the memory budget is refused before any work, with the figures (a
/// 4096^2 render once grew to 15 GB and was killed, or crashed inside the driver).
#[test]
fn a_film_over_the_memory_limit_is_refused_before_it_starts() {
    let dir = fresh_dir("memory-limit");
    let out = dir.join("big.exr");
    let (code, err) = run(&[
        "render",
        "--integrator",
        "direct",
        "--width",
        "1024",
        "--height",
        "1024",
        "--spp",
        "1",
        "--memory-limit",
        "100M",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    // 656 B a pixel for a direct film: 687.9 MB for 1024^2.
    assert!(
        err.contains("1024x1024 film needs about 687.9 MB")
            && err.contains("--memory-limit")
            && err.contains("100.0 MB"),
        "{err}"
    );
    assert!(!out.exists());
    let (code, err) = run(&[
        "render",
        "--memory-limit",
        "lots",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("lots"), "{err}");
}

/// Under an address-space limit (`ulimit -v`) the film is sized to what the process may still
/// map: the frame renders in bands, or is refused naming the limit, and never aborts on a failed
/// allocation (a 2048^2 render under 3 GB once ended with exit 134, or 139 inside the driver).
#[test]
fn an_address_space_limit_bands_or_refuses_the_render_and_never_aborts() {
    use std::os::unix::process::CommandExt;
    let dir = fresh_dir("address-space");
    let out = dir.join("limited.exr");
    let mut cmd = illum();
    cmd.args([
        "render",
        "--integrator",
        "direct",
        "--width",
        "1024",
        "--height",
        "512",
        "--spp",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    // SAFETY: setrlimit is async-signal-safe; the child calls nothing else before exec.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 1_500_000 * 1024,
                rlim_max: 1_500_000 * 1024,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let o = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    match o.status.code() {
        // Whole or in bands ("rendered in N bands"): how much the driver maps first differs
        // between machines (CI rendered this frame whole, a 2-core VM in 3 bands).
        Some(0) => assert!(out.exists(), "{err}"),
        Some(1) => assert!(
            err.contains("address-space limit") && !out.exists(),
            "{err}"
        ),
        c => {
            use std::os::unix::process::ExitStatusExt;
            panic!(
                "exit {c:?} (signal {:?}) under an address-space limit: {err}",
                o.status.signal()
            )
        }
    }
}
