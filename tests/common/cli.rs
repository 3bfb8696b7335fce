//! The illum binary and the files the CLI tests write.

/// The illum binary, with validation on and no fast start (src/cli/fast_start/: a second
/// process racing each render; tests/fast_start.rs turns it on where it tests it).
pub fn illum_command() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_illum"));
    c.env("ILLUM_VALIDATION", "1");
    c.env("ILLUM_FAST_START", "0");
    c
}

/// Runs the illum binary with validation on: (exit code, stderr).
pub fn illum_cli(args: &[&str]) -> (i32, String) {
    let out = illum_command().args(args).output().expect("running illum");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A unique path in this process's scratch folder (scratch.rs).
pub fn temp_path(name: &str) -> std::path::PathBuf {
    super::scratch::scratch_root().join(name)
}
