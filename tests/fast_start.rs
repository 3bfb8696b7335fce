//! Fast start (src/cli/fast_start/): on lavapipe a second process renders the image with the
//! driver's unoptimised kernels while the first compiles the optimised ones. Its premise is that
//! both give the same pixels; these tests check it on kernels of different features, then check
//! the second process's result taking the outputs' places, and a race left to the clock.

mod common;
use common::{illum_command, temp_path};
use std::path::Path;

/// Runs illum with `env` set: (exit code, stderr).
fn run(args: &[&str], env: &[(&str, &str)]) -> (i32, String) {
    let mut c = illum_command();
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().expect("running illum");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Every channel of two EXRs, compared bit for bit.
fn assert_same_pixels(a: &Path, b: &Path, what: &str) {
    let (a, b) = (
        illum::output::read_exr(a).expect("first image"),
        illum::output::read_exr(b).expect("second image"),
    );
    assert_eq!(a.channels.len(), b.channels.len(), "{what}: channel lists");
    for ((na, va), (nb, vb)) in a.channels.iter().zip(&b.channels) {
        assert_eq!(na, nb, "{what}: channel names");
        let differ = va
            .iter()
            .zip(vb)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(differ, 0, "{what}: {differ} samples of {na} differ");
    }
}

/// The premise: LLVM's optimisations (off with GALLIVM_PERF=nopt) change no pixel. Kernels of
/// different features: the radiosity cache and caustic paths (`full`), path tracing, direct
/// lighting with many lights and a dome, and a USD stage's meshes and textures.
#[test]
fn unoptimised_kernels_render_the_same_pixels() {
    let scenes = [
        ("default-full", "scenes/default.json", "full"),
        ("interior-path", "scenes/interior.json", "path"),
        ("veach-direct", "scenes/veach.json", "direct"),
        ("lookdev-full", "scenes/lookdev.usda", "full"),
    ];
    for (name, scene, integrator) in scenes {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
        let mut images = Vec::new();
        for perf in ["", "nopt"] {
            let out = temp_path(&format!("fast-start-{name}-{perf}.exr"));
            let o = out.to_str().unwrap().to_string();
            let args = [
                "render",
                "--device",
                "llvmpipe",
                scene.to_str().unwrap(),
                "--integrator",
                integrator,
                "--width",
                "48",
                "--height",
                "32",
                "--spp",
                "4",
                "--quiet",
                "-o",
                &o,
            ];
            let (code, err) = run(&args, &[("ILLUM_FAST_START", "0"), ("GALLIVM_PERF", perf)]);
            assert_eq!(code, 0, "{name} with GALLIVM_PERF={perf:?}:\n{err}");
            images.push(out);
        }
        assert_same_pixels(&images[0], &images[1], name);
    }
}

/// `ILLUM_FAST_START=wait` makes the second process give the result every time: its EXR and PNG
/// take the places asked for (the PNG through a symbolic link, which stays), the staging folder
/// is gone, the summary names the files asked for, and the pixels are those of a render without
/// a fast start.
#[test]
fn the_second_process_result_takes_the_outputs_places() {
    let target = temp_path("fast-start-wait-target.png");
    let png = temp_path("fast-start-wait.png");
    std::fs::write(&target, b"old").unwrap();
    std::os::unix::fs::symlink(&target, &png).unwrap();
    let plain = temp_path("fast-start-plain.exr");
    let p = png.to_str().unwrap();
    let common = [
        "render", "--device", "llvmpipe", "--width", "64", "--height", "32", "--spp", "2",
    ];
    // A Mesa cache of its own, to see the optimised kernels reach it after the command ended.
    let cache = temp_path("fast-start-mesa-cache");
    std::fs::create_dir_all(&cache).unwrap();
    let mut child = illum_command();
    child
        .args(common)
        .args(["-o", p])
        .env("ILLUM_FAST_START", "wait")
        .env("MESA_SHADER_CACHE_DIR", &cache)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let spawned = child.spawn().expect("running illum");
    let pid = spawned.id();
    let out = spawned.wait_with_output().expect("illum ran");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("fast start: this image is the second process's"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "wrote {} and {p}",
            png.with_extension("exr").display()
        )),
        "{err}"
    );
    assert!(png.is_symlink(), "the PNG's link was replaced");
    assert_ne!(
        std::fs::read(&target).unwrap(),
        b"old",
        "the PNG was not written"
    );
    for f in [&png, &png.with_extension("exr")] {
        assert!(f.is_file(), "{} was not written:\n{err}", f.display());
    }
    let prefix = format!("illum-fast-start-{pid}-");
    let left: Vec<_> = std::fs::read_dir(std::env::temp_dir())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .collect();
    assert!(left.is_empty(), "staging folders left behind: {left:?}");
    // The optimised kernels, never compiled by the command (the second process won), are
    // compiled by a process it left in the background: the cache grows once more after it ends.
    let cached = folder_bytes(&cache);
    let background = background_compile(p);
    assert!(
        background.is_some(),
        "no background compile of the optimised kernels"
    );
    let t = std::time::Instant::now();
    while background.as_ref().is_some_and(|b| running(b)) && t.elapsed().as_secs() < 240 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert!(
        folder_bytes(&cache) > cached,
        "the background compile added nothing to Mesa's cache ({cached} bytes)"
    );
    let exr = illum::output::read_exr(&png.with_extension("exr")).unwrap();
    assert!(
        exr.attributes.iter().any(|(k, _)| k == "illum.fastStart"),
        "the header does not say whose image it is"
    );

    let (code, err) = run(
        &[&common[..], &["--quiet", "-o", plain.to_str().unwrap()]].concat(),
        &[("ILLUM_FAST_START", "0")],
    );
    assert_eq!(code, 0, "{err}");
    assert_same_pixels(
        &png.with_extension("exr"),
        &plain,
        "fast start against none",
    );
}

/// Left to the clock (`ILLUM_FAST_START=1`: on whatever the load), either process may give the
/// image; it is the same image. Under --time there is no second process (the two would render
/// different sample counts), nor with --report (its times would be the unoptimised kernels'),
/// nor with a bad setting, which is named.
#[test]
fn a_race_gives_the_same_image_and_time_budgets_take_none() {
    let raced = temp_path("fast-start-race.exr");
    let plain = temp_path("fast-start-race-plain.exr");
    let args = [
        "render", "--device", "llvmpipe", "--width", "40", "--height", "24", "--spp", "3",
        "--quiet", "-o",
    ];
    for (out, mode) in [(&raced, "1"), (&plain, "0")] {
        let a = [&args[..], &[out.to_str().unwrap()]].concat();
        let (code, err) = run(&a, &[("ILLUM_FAST_START", mode)]);
        assert_eq!(code, 0, "ILLUM_FAST_START={mode}:\n{err}");
    }
    assert_same_pixels(&raced, &plain, "a race against none");

    let timed = temp_path("fast-start-timed.exr");
    let csv = temp_path("fast-start-report.csv");
    let csv = csv.to_str().unwrap();
    for (extra, what) in [
        (&["--time", "0.2"][..], "a time budget"),
        (&["--spp", "2", "--report", csv][..], "a measured render"),
    ] {
        let common = [
            "render", "--device", "llvmpipe", "--width", "32", "--height", "16",
        ];
        let o = ["-o", timed.to_str().unwrap()];
        let (code, err) = run(
            &[&common[..], extra, &o].concat(),
            &[("ILLUM_FAST_START", "wait")],
        );
        assert_eq!(code, 0, "{err}");
        assert!(
            !err.contains("fast start"),
            "{what} took a second process:\n{err}"
        );
    }

    let (code, err) = run(
        &["render", "--spp", "1", "-o", timed.to_str().unwrap()],
        &[("ILLUM_FAST_START", "maybe")],
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("ILLUM_FAST_START=\"maybe\""), "{err}");
}

/// Bytes of the files under a folder.
fn folder_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .map(|e| match e.file_type() {
                    Ok(t) if t.is_dir() => folder_bytes(&e.path()),
                    _ => e.metadata().map_or(0, |m| m.len()),
                })
                .sum()
        })
        .unwrap_or(0)
}

/// The /proc folder of the background compile a fast start left for the render writing `out`.
fn background_compile(out: &str) -> Option<std::path::PathBuf> {
    std::fs::read_dir("/proc")
        .ok()?
        .filter_map(|e| e.ok())
        .find_map(|e| {
            let environ = std::fs::read(e.path().join("environ")).ok()?;
            let cmdline = std::fs::read(e.path().join("cmdline")).ok()?;
            let has = |hay: &[u8], needle: &[u8]| hay.windows(needle.len()).any(|w| w == needle);
            (has(&environ, b"ILLUM_FAST_START_COMPILE=1") && has(&cmdline, out.as_bytes()))
                .then(|| e.path())
        })
}

/// Whether the process of a /proc folder still runs (a zombie, not yet reaped, does not).
fn running(proc_dir: &Path) -> bool {
    std::fs::read_to_string(proc_dir.join("stat"))
        .ok()
        .and_then(|s| s.rsplit_once(") ").map(|(_, rest)| !rest.starts_with('Z')))
        .unwrap_or(false)
}

/// Kernels compiled with LLVM's optimisations are noted in illum's cache folder, so that a later
/// start does not race for them: the note is keyed by what decides the kernels, so another
/// output file reads the same key and another scene file does not.
#[test]
fn optimised_kernels_are_noted_by_what_decides_them() {
    let dir = temp_path("fast-start-illum-cache");
    std::fs::create_dir_all(&dir).unwrap();
    let notes = dir.join("warm-kernels.txt");
    let keys = || {
        std::fs::read_to_string(&notes)
            .unwrap_or_default()
            .lines()
            .map(String::from)
            .collect::<Vec<_>>()
    };
    let env = [
        ("ILLUM_FAST_START", "0"),
        ("ILLUM_CACHE_DIR", dir.to_str().unwrap()),
    ];
    let render = |out: &str, scene: Option<&Path>| {
        let o = temp_path(out);
        let mut args = vec![
            "render", "--width", "32", "--height", "16", "--spp", "1", "--quiet",
        ];
        let s = scene.map(|p| p.to_str().unwrap().to_string());
        if let Some(s) = &s {
            args.push(s);
        }
        args.extend(["-o", o.to_str().unwrap()]);
        let (code, err) = run(&args, &env);
        assert_eq!(code, 0, "{err}");
    };
    render("fast-start-note-a.exr", None);
    assert_eq!(keys().len(), 1, "{:?}", keys());
    render("fast-start-note-b.exr", None);
    assert_eq!(keys().len(), 1, "another output, another key: {:?}", keys());
    let veach = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/veach.json");
    render("fast-start-note-c.exr", Some(&veach));
    assert_eq!(keys().len(), 2, "another scene, the same key: {:?}", keys());
}
