//! `illum view` in a real window under Xvfb, on lavapipe with validation on: what it saves is
//! what `illum render` writes at the same spp, bit for bit, and the window shows the render's PNG
//! bytes; an edit of the scene file shows within frames, through a table update; a bad edit
//! keeps the last good image and shows its error; the mouse moves the camera and R brings it
//! back; without a display it says so and fails.

mod common;
use common::*;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

const SCENE: &str = r#"{"camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov_y": 40, "resolution": [64, 48]},
  "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6]}, "ball": {"diffuse": [0.7, 0.3, 0.2]}},
  "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
             "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "ball"}},
  "lights": {"key": {"rect": {"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]},
                     "intensity": 6, "color": [1, 1, 1]}}}"#;

/// A virtual X display for the test's windows.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        let which = Command::new("sh").args(["-c", "command -v Xvfb"]).output();
        assert!(
            which.is_ok_and(|o| o.status.success()),
            "Xvfb is not installed: run scripts/setup-debian.sh (Debian's xvfb package)"
        );
        // A display number of our own: the first free one from the process id on, each test
        // (thread) of the process taking others than the rest.
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let base = 100 + std::process::id() % 500;
        loop {
            let n = base + NEXT.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            assert!(n < base + 200, "no free X display number from {base}");
            if Path::new(&format!("/tmp/.X{n}-lock")).exists()
                || Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
            {
                continue;
            }
            let mut child = Command::new("Xvfb")
                .args([
                    &format!(":{n}"),
                    "-screen",
                    "0",
                    "1024x768x24",
                    "-nolisten",
                    "tcp",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("starting Xvfb");
            let t = Instant::now();
            while t.elapsed() < Duration::from_secs(10) {
                if child.try_wait().unwrap().is_some() {
                    break; // another server took the number first
                }
                if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                    return Xvfb {
                        child,
                        display: format!(":{n}"),
                    };
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A running `illum view` and its stderr, line by line.
struct Viewer {
    child: Child,
    lines: Receiver<String>,
    log: Vec<String>,
}

impl Viewer {
    fn start(x: &Xvfb, args: &[&str]) -> Viewer {
        Viewer::start_with(x, args, &[])
    }

    /// `start` with environment variables set.
    fn start_with(x: &Xvfb, args: &[&str], env: &[(&str, &str)]) -> Viewer {
        let mut command = illum_command();
        for (k, v) in env {
            command.env(k, v);
        }
        let mut child = command
            .env("DISPLAY", &x.display)
            .arg("view")
            .args(args)
            .stderr(Stdio::piped())
            .spawn()
            .expect("starting illum view");
        let (tx, lines) = channel();
        let stderr = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Viewer {
            child,
            lines,
            log: Vec::new(),
        }
    }

    /// The next line containing `what` (the view's log up to it on failure).
    fn wait_for(&mut self, what: &str) -> String {
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(240) {
            match self.lines.recv_timeout(Duration::from_millis(100)) {
                Ok(line) => {
                    self.log.push(line.clone());
                    assert!(
                        !line.contains("validation"),
                        "a validation message: {line}\n{}",
                        self.log.join("\n")
                    );
                    if line.contains(what) {
                        return line;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(_) => break,
            }
        }
        panic!("illum view never said {what:?}:\n{}", self.log.join("\n"));
    }

    /// Waits for the process to end: its exit code (the rest of its log read).
    fn wait(mut self) -> (i32, Vec<String>) {
        let status = self.child.wait().unwrap();
        while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(5)) {
            self.log.push(line);
        }
        (status.code().unwrap_or(-1), self.log)
    }

    fn terminate(self) -> (i32, Vec<String>) {
        // SAFETY: signalling our own child.
        unsafe { libc::kill(self.child.id() as i32, libc::SIGTERM) };
        self.wait()
    }
}

/// `illum view SCENE --spp 8 --scale 1 --save-at-exit -o SAVED [--screenshot SHOT] EXTRA...`.
fn saving_view(
    x: &Xvfb,
    scene: &Path,
    saved: &Path,
    shot: Option<&Path>,
    extra: &[&str],
) -> Viewer {
    saving_view_with(x, scene, saved, shot, extra, &[])
}

/// `saving_view` with environment variables set.
fn saving_view_with(
    x: &Xvfb,
    scene: &Path,
    saved: &Path,
    shot: Option<&Path>,
    extra: &[&str],
    env: &[(&str, &str)],
) -> Viewer {
    let (scene, saved) = (scene.to_str().unwrap(), saved.to_str().unwrap());
    let mut args = vec![
        scene,
        "--spp",
        "8",
        "--scale",
        "1",
        "--save-at-exit",
        "-o",
        saved,
    ];
    if let Some(shot) = shot {
        args.extend(["--screenshot", shot.to_str().unwrap()]);
    }
    args.extend(extra);
    Viewer::start_with(x, &args, env)
}

/// The beauty's red channel.
fn beauty(e: &illum::output::ExrImage) -> Vec<f32> {
    e.channels.iter().find(|c| c.0 == "R").unwrap().1.clone()
}

fn write_scene(path: &Path, json: &str) {
    // As editors save: a new file renamed over the old one.
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, json).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// `illum render SCENE --spp N` as EXR and PNG.
fn render(scene: &Path, spp: u32, name: &str) -> (illum::output::ExrImage, image::RgbImage) {
    let png = temp_path(&format!("{name}.png"));
    let spp = spp.to_string();
    let (code, log) = illum_cli(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        &spp,
        "-q",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    (
        read(&png.with_extension("exr")),
        image::open(&png).unwrap().to_rgb8(),
    )
}

fn read(path: &Path) -> illum::output::ExrImage {
    illum::output::read_exr(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Every channel of two EXRs, bit for bit (NaN equal to NaN).
fn assert_same_pixels(a: &illum::output::ExrImage, b: &illum::output::ExrImage, what: &str) {
    let names =
        |e: &illum::output::ExrImage| e.channels.iter().map(|c| c.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(a), names(b), "{what}: channels");
    for ((name, x), (_, y)) in a.channels.iter().zip(&b.channels) {
        let same = x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same, "{what}: channel {name} differs");
    }
}

/// The screenshot's image area (its top-left, at scale 1) against a PNG of the render.
fn assert_shows(shot: &Path, png: &image::RgbImage, what: &str) {
    let shot = image::open(shot).unwrap().to_rgb8();
    assert!(
        shot.width() >= png.width() && shot.height() > png.height(),
        "{what}: screenshot size"
    );
    for (x, y, p) in png.enumerate_pixels() {
        assert_eq!(shot.get_pixel(x, y), p, "{what}: pixel ({x}, {y})");
    }
}

fn scene_file(name: &str, json: &str) -> PathBuf {
    let p = temp_path(name);
    write_scene(&p, json);
    p
}

#[test]
fn without_a_display_the_view_says_so_and_fails() {
    let scene = scene_file("nodisplay.json", SCENE);
    let out = illum_command()
        .env_remove("DISPLAY")
        .args(["view", scene.to_str().unwrap(), "--frames", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("no display") && err.contains("Xvfb"), "{err}");
}

#[test]
fn the_view_saves_and_shows_what_render_writes() {
    let x = Xvfb::start();
    let scene = scene_file("converge.json", SCENE);
    let (saved, shot) = (
        temp_path("converge-view.exr"),
        temp_path("converge-view.png"),
    );
    let v = saving_view(&x, &scene, &saved, Some(&shot), &["--frames", "30"]);
    let (code, log) = v.wait();
    assert_eq!(code, 0, "{}", log.join("\n"));
    let (exr, png) = render(&scene, 8, "converge-render");
    assert_same_pixels(&read(&saved), &exr, "saved by the view");
    // The same header: every attribute render writes, the same spp.
    let keys = |e: &illum::output::ExrImage| {
        let mut k: Vec<String> = e.attributes.iter().map(|a| a.0.clone()).collect();
        k.sort();
        k
    };
    let view = read(&saved);
    assert_eq!(keys(&view), keys(&exr), "header attributes");
    let spp =
        |e: &illum::output::ExrImage| e.attributes.iter().find(|a| a.0 == "illum.spp").cloned();
    assert_eq!(spp(&view), spp(&exr));
    assert_shows(&shot, &png, "the converged frame");
}

/// The fast start (src/cli/fast_start/), made to wait for its second process: the first frame
/// is that process's one-sample image, shown before the view's own first frame; the view then
/// converges to what render writes, as without it.
#[test]
fn a_fast_start_shows_the_second_process_image_first() {
    let x = Xvfb::start();
    let scene = scene_file("fast-start.json", SCENE);
    let saved = temp_path("fast-start-view.exr");
    let mut v = saving_view_with(
        &x,
        &scene,
        &saved,
        None,
        &["--device", "llvmpipe", "--frames", "30"],
        &[("ILLUM_FAST_START", "wait")],
    );
    let first = v.wait_for("first frame");
    assert!(first.contains("from a second process"), "{first}");
    v.wait_for("own first frame");
    let (code, log) = v.wait();
    assert_eq!(code, 0, "{}", log.join("\n"));
    let (exr, _) = render(&scene, 8, "fast-start-render");
    assert_same_pixels(&read(&saved), &exr, "saved after a fast start");
}

#[test]
fn edits_show_at_once_and_a_bad_edit_keeps_the_last_good_image() {
    let x = Xvfb::start();
    let scene = scene_file("edit.json", SCENE);
    let (saved, shot) = (temp_path("edit-view.exr"), temp_path("edit-view.png"));
    let mut v = saving_view(&x, &scene, &saved, Some(&shot), &[]);
    v.wait_for("8 spp done");
    // A light's colour: one table rewritten, nothing prepared again.
    let edited = SCENE.replace(r#""color": [1, 1, 1]"#, r#""color": [0.2, 0.4, 1.0]"#);
    assert_ne!(edited, SCENE);
    write_scene(&scene, &edited);
    let applied = v.wait_for("applied the edit");
    assert!(applied.contains("rewrote the lights table"), "{applied}");
    v.wait_for("8 spp done");
    // A bad edit: the error is shown, the edited scene stays.
    write_scene(&scene, &edited[..edited.len() / 2]);
    let kept = v.wait_for("keeping the last good scene");
    assert!(kept.contains("edit.json"), "{kept}");
    let (code, log) = v.terminate();
    assert_eq!(code, 0, "{}", log.join("\n"));
    let good = scene_file("edit-good.json", &edited);
    let (exr, png) = render(&good, 8, "edit-render");
    assert_same_pixels(&read(&saved), &exr, "saved after the edits");
    assert_shows(&shot, &png, "the frame after the edits");
    // The status bar shows the error, in red.
    let shot = image::open(&shot).unwrap().to_rgb8();
    let red = shot
        .enumerate_pixels()
        .filter(|(_, y, p)| *y >= 48 && p[0] > 200 && p[1] < 150 && p[2] < 150)
        .count();
    assert!(red > 20, "{red} red pixels of error text in the status bar");
}

#[test]
fn the_mouse_orbits_and_r_brings_the_scene_camera_back() {
    let x = Xvfb::start();
    let scene = scene_file("orbit.json", SCENE);
    let saved = temp_path("orbit-view.exr");
    let mut v = Viewer::start(
        &x,
        &[
            "--spp",
            "8",
            "--scale",
            "4",
            "-o",
            saved.to_str().unwrap(),
            scene.to_str().unwrap(),
        ],
    );
    v.wait_for("8 spp done");
    let xdotool = |args: &[&str]| {
        let out = Command::new("xdotool")
            .env("DISPLAY", &x.display)
            .args(args)
            .output();
        let out = out.expect("xdotool is not installed: run scripts/setup-debian.sh");
        assert!(
            out.status.success(),
            "xdotool {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    };
    let id = xdotool(&["search", "--sync", "--name", "illum view"]);
    let id = id.lines().next().unwrap().to_string();
    // No window manager gives it the keyboard: the test does.
    xdotool(&["windowfocus", "--sync", &id]);
    // A drag with the left button held (XTEST: real input, to the window under the pointer).
    xdotool(&["mousemove", "--window", &id, "100", "100"]);
    xdotool(&["mousedown", "1"]);
    for k in 1..=6 {
        let to = (100 + 10 * k).to_string();
        xdotool(&["mousemove", "--window", &id, &to, "110"]);
    }
    xdotool(&["mouseup", "1"]);
    // Saves once the view holds all 8 samples of the camera it shows: a "done" line may be a late
    // one of the camera before (motion events can still arrive after it), and a key pressed then
    // saves a restarted accumulation.
    let save_complete = |v: &mut Viewer| {
        for _ in 0..10 {
            v.wait_for("8 spp done");
            xdotool(&["key", "s"]);
            if v.wait_for("saved").contains("(8 spp)") {
                return;
            }
        }
        panic!("never saved 8 spp:\n{}", v.log.join("\n"));
    };
    save_complete(&mut v);
    let (exr, _) = render(&scene, 8, "orbit-render");
    let moved = read(&saved);
    assert_ne!(beauty(&moved), beauty(&exr), "the orbit moved the camera");
    xdotool(&["key", "r"]);
    save_complete(&mut v);
    assert_same_pixels(&read(&saved), &exr, "saved after R");
    xdotool(&["key", "q"]);
    let (code, log) = v.wait();
    assert_eq!(code, 0, "{}", log.join("\n"));
}

/// The denoised preview shows what `render --denoise` writes as its Denoised layer (the same
/// planes into the same denoiser), while the saved beauty stays the render's.
#[test]
fn the_denoised_preview_shows_the_denoised_layer() {
    let x = Xvfb::start();
    let scene = scene_file("denoise-view.json", SCENE);
    let (saved, shot) = (temp_path("denoise-view.exr"), temp_path("denoise-view.png"));
    let v = saving_view(
        &x,
        &scene,
        &saved,
        Some(&shot),
        &["--frames", "30", "--denoise"],
    );
    let (code, log) = v.wait();
    assert_eq!(code, 0, "{}", log.join("\n"));
    assert!(
        log.iter().any(|l| l.contains("denoised preview on")),
        "{}",
        log.join("\n")
    );
    let out = temp_path("denoise-render.exr");
    let (code, log) = illum_cli(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "8",
        "--denoise",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    let exr = read(&out);
    let plane = |name: &str| &exr.channels.iter().find(|c| c.0 == name).unwrap().1;
    let enc = illum::output::SrgbEncoder::new();
    let (r, g, b) = (
        plane("Denoised.R"),
        plane("Denoised.G"),
        plane("Denoised.B"),
    );
    let png = image::RgbImage::from_fn(exr.width, exr.height, |x, y| {
        let i = (y * exr.width + x) as usize;
        image::Rgb([enc.encode(r[i]), enc.encode(g[i]), enc.encode(b[i])])
    });
    assert_shows(&shot, &png, "the denoised preview");
    // The saved beauty is the render's, not the preview.
    let view = read(&saved);
    assert_eq!(beauty(&view), beauty(&exr));
}

/// The files a scene names are watched too: a texture edited on disk shows, the scene prepared
/// again (a texture cannot be updated in place), and the result is the render of the new texture.
#[test]
fn an_edited_texture_shows() {
    let x = Xvfb::start();
    let dir = temp_path("texture-edit");
    std::fs::create_dir_all(&dir).unwrap();
    let texture = dir.join("albedo.png");
    let write_texture = |rgb: [u8; 3]| {
        let tmp = dir.join("albedo.tmp.png");
        image::RgbImage::from_pixel(4, 4, image::Rgb(rgb))
            .save(&tmp)
            .unwrap();
        std::fs::rename(&tmp, &texture).unwrap();
    };
    write_texture([200, 60, 40]);
    let json = SCENE
        .replace(
            r#""ball": {"diffuse": [0.7, 0.3, 0.2]}"#,
            r#""ball": {"diffuse": [1, 1, 1], "diffuse_texture": "albedo"}"#,
        )
        .replace(
            r#""materials""#,
            r#""textures": {"albedo": {"file": "albedo.png"}}, "materials""#,
        );
    let scene = dir.join("scene.json");
    write_scene(&scene, &json);
    let saved = dir.join("view.exr");
    let mut v = saving_view(&x, &scene, &saved, None, &[]);
    v.wait_for("8 spp done");
    write_texture([40, 90, 220]);
    let applied = v.wait_for("applied the edit");
    assert!(applied.contains("prepared the scene again"), "{applied}");
    v.wait_for("8 spp done");
    let (code, log) = v.terminate();
    assert_eq!(code, 0, "{}", log.join("\n"));
    let (exr, _) = render(&scene, 8, "texture-render");
    assert_same_pixels(&read(&saved), &exr, "saved after the texture edit");
}
