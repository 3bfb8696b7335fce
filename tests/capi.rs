//! The C API from C (issue 14): tests/capi/embed_test.c is compiled with `cc` against the
//! committed include/illum.h and libillum.a (the lib target's staticlib), then run; it checks its
//! own results and the validation layers' silence, and exits 0 only if all hold.

use std::path::Path;
use std::process::Command;

#[test]
fn the_c_program_builds_against_the_header_and_passes() {
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
    let dir = std::env::temp_dir().join(format!("illum-capi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("embed_test");
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
        .arg(root.join("tests/capi/embed_test.c"))
        .arg(&lib)
        .args(["-lvulkan", "-lm", "-ldl", "-lpthread", "-lgcc_s", "-o"])
        .arg(&program)
        .output()
        .expect("running the C compiler");
    assert!(
        compiled.status.success(),
        "{cc} failed:\n{}",
        String::from_utf8_lossy(&compiled.stderr)
    );
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

/// The committed header is what cbindgen makes of src/capi.rs (where cbindgen is installed:
/// scripts/gen-header.sh; without it, the C program above still compiles against the header).
#[test]
fn the_committed_header_is_current() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fresh = std::env::temp_dir().join(format!("illum-{}.h", std::process::id()));
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
