//! The C API from C: tests/capi/embed_test.c is compiled with `cc` against the
//! committed include/illum.h and libillum.a (the lib target's staticlib), then run; it checks its
//! own results and the validation layers' silence, and exits 0 only if all hold.

use std::path::Path;
use std::process::Command;

#[path = "common/scratch.rs"]
mod scratch;

/// Compiles the C program `source` (relative to the repository) against include/illum.h,
/// examples/embed_host.h and libillum.a into a temporary directory; returns the executable.
fn compile(source: &str, name: &str) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // target/<profile>/deps/capi-… → target/<profile>
    let exe = std::env::current_exe().unwrap();
    let profile = exe.parent().and_then(Path::parent).unwrap();
    let lib = profile.join("libillum.a");
    assert!(
        lib.exists(),
        "{} is missing: `cargo test` does not link the staticlib; run `cargo build --release --lib` \
         first (scripts/test.sh does)",
        lib.display()
    );
    let dir = scratch::scratch_root();
    let program = dir.join(name);
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let compiled = Command::new(&cc)
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Wno-missing-field-initializers",
            "-Werror",
            "-I",
        ])
        .arg(root.join("include"))
        .arg("-I")
        .arg(root.join("examples"))
        .arg(root.join(source))
        .arg(&lib)
        .args(["-lvulkan", "-lm", "-ldl", "-lpthread", "-lgcc_s", "-o"])
        .arg(&program)
        .output()
        .expect("running the C compiler");
    assert!(
        compiled.status.success(),
        "{cc} failed on {source}:\n{}",
        String::from_utf8_lossy(&compiled.stderr)
    );
    program
}

#[test]
fn the_c_program_builds_against_the_header_and_passes() {
    let program = compile("tests/capi/embed_test.c", "embed_test");
    let run = Command::new(&program).output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr),
    );
    assert!(
        run.status.success() && stdout.contains("capi: ok"),
        "the C test failed ({:?}):\n{stdout}\n{stderr}",
        run.status
    );
}

/// examples/embed.c, the C host, on a tiny image with validation on (any message fails it): ten
/// passes, each update and pass timed, and a PFM of the image with the header and size it says.
#[test]
fn the_c_example_runs() {
    let program = compile("examples/embed.c", "embed");
    let out = program.with_extension("pfm");
    let run = Command::new(&program)
        .arg(&out)
        .args(["12", "8", "4"])
        .env("ILLUM_VALIDATION", "1")
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr),
    );
    assert!(
        run.status.success(),
        "examples/embed.c failed ({:?}):\n{stdout}\n{stderr}",
        run.status
    );
    for line in [
        "pass 9: samples [1, 4)",
        "update: camera",
        "illum_render (blocking)",
    ] {
        assert!(stdout.contains(line), "no {line:?} in:\n{stdout}");
    }
    let pfm = std::fs::read(&out).unwrap();
    let header = b"PF\n12 8\n-1.0\n";
    assert!(pfm.starts_with(header), "{:?}", &pfm[..16.min(pfm.len())]);
    assert_eq!(pfm.len(), header.len() + 12 * 8 * 3 * 4);
}

/// The committed header is what cbindgen makes of src/capi/ (where cbindgen is installed:
/// scripts/gen-header.sh; without it, the C program above still compiles against the header).
#[test]
fn the_committed_header_is_current() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fresh = scratch::scratch_root().join("illum.h");
    let Ok(out) = Command::new("cbindgen")
        .current_dir(root)
        .args([
            "--config",
            "cbindgen.toml",
            "--crate",
            "illum",
            "--quiet",
            "--output",
        ])
        .arg(&fresh)
        .output()
    else {
        eprintln!("cbindgen is not installed: header freshness not checked");
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let committed = std::fs::read_to_string(root.join("include/illum.h")).unwrap();
    assert!(
        std::fs::read_to_string(&fresh).unwrap() == committed,
        "include/illum.h is stale: run scripts/gen-header.sh"
    );
}
