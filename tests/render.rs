//! Rendering with analytic expectations: depth, normals, directly seen emitters, AOV layers.

mod common;
use common::*;
use glam::DVec3;

/// Camera ray direction through film position (fx, fy) in pixels, as the kernel builds it.
fn camera_dir(pos: DVec3, look: DVec3, fov_deg: f64, w: u32, h: u32, fx: f64, fy: f64) -> DVec3 {
    let f = (look - pos).normalize();
    let r = f.cross(DVec3::Y).normalize();
    let u = r.cross(f);
    let t = (fov_deg.to_radians() / 2.0).tan();
    let a = f64::from(w) / f64::from(h);
    let nx = 2.0 * fx / f64::from(w) - 1.0;
    let ny = 2.0 * fy / f64::from(h) - 1.0;
    (f + nx * r * t * a - ny * u * t).normalize()
}

#[test]
fn camera_inside_a_sphere_sees_its_radius_everywhere() {
    let out = render(
        r#"{"camera": {"position": [10, -4, 3], "look_at": [11, -4, 3], "fov_y": 90, "resolution": [24, 16]},
            "materials": {"m": {"diffuse": [1, 1, 1]}},
            "shapes": {"s": {"sphere": {"center": [10, -4, 3], "radius": 2.5}, "material": "m"}}}"#,
        4,
    );
    for (i, &z) in out.film.depth.iter().enumerate() {
        assert!((z - 2.5).abs() < 2.5e-5, "pixel {i}: Z = {z}, expected 2.5");
        let n = out.film.normal[i];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        // Outward normals of the sphere, averaged over the pixel's samples.
        assert!(len > 0.99 && len < 1.0 + 1e-5, "pixel {i}: |N| = {len}");
        assert_eq!(out.film.albedo[i], [1.0, 1.0, 1.0], "pixel {i}");
    }
    assert_eq!(out.stats.non_finite_samples, 0);
}

/// A ground sphere of radius R under a camera 1.5 above it, looking straight down (up to 1e15,
/// where f64 still resolves 1.5 at R), and cameras inside spheres of radius 1e20 and 1e29: the
/// f32 form f.f - r^2 put the ground 40% too far at 1e7, let rays pass through it from 1e8 and
/// lost the spheres from 1e20 (f32 overflow).
#[test]
fn huge_spheres_are_hit_where_they_are() {
    let ctx = context();
    for r in [1e3, 1e7, 1e8, 1e12, 1e15] {
        let json = format!(
            r#"{{"camera": {{"position": [0, 1.5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov_y": 20, "resolution": [9, 9]}},
               "materials": {{"m": {{"diffuse": [0.5, 0.5, 0.5]}}}},
               "shapes": {{"ground": {{"sphere": {{"center": [0, {}, 0], "radius": {r:e}}}, "material": "m"}}}},
               "lights": {{"sky": {{"dome": {{}}, "color": [1, 1, 1]}}}}}}"#,
            -r
        );
        let out = render_with(&ctx, &scene(&json), 64, 0);
        // The centre pixel spans 2.2 degrees about straight down: depth 1.5 to 1.5 (1 + 3e-4).
        let z = f64::from(out.film.depth[4 * 9 + 4]);
        assert!(
            (z - 1.5).abs() < 1.5e-3,
            "R = {r:e}: depth {z}, expected 1.5"
        );
        // Lit by the sky above: half the albedo (Lambert under a unit dome), not the dome seen
        // through the ground.
        let b = out.film.beauty[4 * 9 + 4];
        eprintln!("R = {r:e}: depth {z}, beauty {b:?}");
        assert!(
            (f64::from(b[0]) - 0.5).abs() < 0.05,
            "R = {r:e}: beauty {b:?}"
        );
    }
    for r in [1e20, 1e29] {
        let inside = format!(
            r#"{{"camera": {{"position": [3, 4, 0], "look_at": [3, 5, 1], "fov_y": 60, "resolution": [8, 6]}},
               "materials": {{"m": {{"diffuse": [0.5, 0.5, 0.5]}}}},
               "shapes": {{"sky": {{"sphere": {{"center": [0, 0, 0], "radius": {r:e}}}, "material": "m"}}}}}}"#
        );
        let out = render_with(&ctx, &scene(&inside), 2, 0);
        for (i, &z) in out.film.depth.iter().enumerate() {
            let rel = (f64::from(z) / r - 1.0).abs();
            assert!(rel < 1e-5, "R = {r:e}, pixel {i}: Z = {z}, expected R");
        }
    }
    let big = r#"{"camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [4, 4]},
        "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
        "shapes": {"s": {"sphere": {"center": [0, 0, 0], "radius": 1e39}, "material": "m"}}}"#;
    let e = illum::scene::from_json_str(big, "big.json", std::path::Path::new("."))
        .expect_err("a radius of 1e39 is refused")
        .to_string();
    assert!(
        e.contains("shapes.s.sphere.radius") && e.contains("1e30"),
        "{e}"
    );
    assert_no_validation_messages(&ctx);
}

#[test]
fn depth_of_a_quad_at_a_known_distance() {
    let (w, h, fov, spp) = (32u32, 24u32, 40.0, 64u32);
    let out = render(
        r#"{"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 40, "resolution": [32, 24]},
            "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
            "shapes": {"q": {"rect": {"center": [0, 0, -3], "normal": [0, 0, 1], "size": [100, 100]}, "material": "m"}}}"#,
        spp,
    );
    let (pos, look) = (DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0));
    for y in 0..h {
        for x in 0..w {
            // Z is the mean of t = 3 / cos over the pixel; integrate it on an 8x8 grid and allow
            // 5 standard errors of the 64-sample mean (t varies by at most its range in a pixel).
            let mut ts = Vec::new();
            for j in 0..8 {
                for i in 0..8 {
                    let d = camera_dir(
                        pos,
                        look,
                        fov,
                        w,
                        h,
                        f64::from(x) + (f64::from(i) + 0.5) / 8.0,
                        f64::from(y) + (f64::from(j) + 0.5) / 8.0,
                    );
                    ts.push(3.0 / -d.z);
                }
            }
            let mean = ts.iter().sum::<f64>() / ts.len() as f64;
            let range = ts.iter().cloned().fold(f64::MIN, f64::max)
                - ts.iter().cloned().fold(f64::MAX, f64::min);
            let tol = 5.0 * range / f64::from(spp).sqrt() + 1e-5 * mean;
            let z = f64::from(out.film.depth[(y * w + x) as usize]);
            assert!(
                (z - mean).abs() <= tol,
                "pixel ({x},{y}): Z = {z}, expected {mean} ± {tol}"
            );
            let n = out.film.normal[(y * w + x) as usize];
            assert!(
                (n[2] - 1.0).abs() < 1e-6 && n[0].abs() < 1e-6 && n[1].abs() < 1e-6,
                "N = {n:?}"
            );
        }
    }
}

#[test]
fn normals_of_a_sphere_point_away_from_its_centre() {
    let (w, h, fov) = (32u32, 32u32, 30.0);
    let pos = DVec3::new(0.0, 0.0, 5.0);
    let c = DVec3::new(0.2, -0.1, 0.0);
    let out = render(
        r#"{"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 30, "resolution": [32, 32]},
            "materials": {"m": {"diffuse": [1, 1, 1]}},
            "shapes": {"s": {"sphere": {"center": [0.2, -0.1, 0], "radius": 1}, "material": "m"}}}"#,
        16,
    );
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            // Only pixels whose every sample hit the sphere (albedo 1 = all samples hit).
            if out.film.albedo[i] != [1.0, 1.0, 1.0] {
                continue;
            }
            let d = camera_dir(
                pos,
                DVec3::ZERO,
                fov,
                w,
                h,
                f64::from(x) + 0.5,
                f64::from(y) + 0.5,
            );
            let f = pos - c;
            let b = -f.dot(d);
            let disc = 1.0 - (f + b * d).length_squared();
            if disc < 0.05 {
                continue; // near the silhouette the normal varies a lot within a pixel
            }
            let t = b - disc.sqrt();
            let expected = (pos + t * d - c).normalize();
            let n = DVec3::new(
                out.film.normal[i][0].into(),
                out.film.normal[i][1].into(),
                out.film.normal[i][2].into(),
            );
            assert!(
                n.normalize().dot(expected) > 0.998,
                "pixel ({x},{y}): N = {n}, expected {expected}"
            );
            let z = f64::from(out.film.depth[i]);
            assert!(
                (z - t).abs() < 0.05 * t,
                "pixel ({x},{y}): Z = {z}, expected about {t}"
            );
            checked += 1;
        }
    }
    assert!(checked > 300, "only {checked} pixels checked");
}

#[test]
fn directly_seen_emitters_give_exactly_their_radiance() {
    // A rect light filling the view, seen from its front: every sample returns its radiance
    // color * intensity * 2^exposure = (0.5, 1, 2) * 3 * 2 exactly, in beauty and Emission.
    let out = render(
        r#"{"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 30, "resolution": [16, 16]},
            "lights": {"l": {"rect": {"center": [0, 0, -2], "normal": [0, 0, 1], "size": [50, 50]},
                             "color": [0.5, 1, 2], "intensity": 3, "exposure": 1}}}"#,
        4,
    );
    for i in 0..out.film.beauty.len() {
        assert_eq!(out.film.beauty[i], [3.0, 6.0, 12.0], "pixel {i}");
        assert_eq!(out.film.emission[i], [3.0, 6.0, 12.0], "pixel {i}");
    }
    // The same from behind: one-sided, so black; and an emissive material does the same.
    let back = render(
        r#"{"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 30, "resolution": [8, 8]},
            "lights": {"l": {"rect": {"center": [0, 0, -2], "normal": [0, 0, -1], "size": [50, 50]}, "intensity": 3}}}"#,
        2,
    );
    assert!(back.film.beauty.iter().all(|p| *p == [0.0, 0.0, 0.0]));
    let glow = render(
        r#"{"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 30, "resolution": [8, 8]},
            "materials": {"g": {"diffuse": [0, 0, 0], "emission": [0.25, 4, 7]}},
            "shapes": {"q": {"rect": {"center": [0, 0, -2], "normal": [0, 0, 1], "size": [50, 50]}, "material": "g"}}}"#,
        2,
    );
    assert!(glow.film.beauty.iter().all(|p| *p == [0.25, 4.0, 7.0]));
}

#[test]
fn a_constant_dome_is_seen_exactly_and_lights_lambert_as_albedo_times_radiance() {
    let sky = render(
        r#"{"camera": {"position": [0, 0, 0], "look_at": [0, 1, -1], "fov_y": 60, "resolution": [8, 8]},
            "lights": {"sky": {"dome": {}, "color": [0.2, 0.4, 0.8], "intensity": 2}}}"#,
        2,
    );
    for p in &sky.film.beauty {
        for (c, e) in p.iter().zip([0.4f32, 0.8, 1.6]) {
            assert!((c - e).abs() <= 1e-6 * e, "{p:?}");
        }
    }
    // An unoccluded Lambert plane under a uniform dome reflects exactly albedo * L.
    let plane = render_batches(
        r#"{"camera": {"position": [0, 1, 0], "look_at": [0, 0, -1], "fov_y": 40, "resolution": [8, 8]},
            "materials": {"m": {"diffuse": [0.5, 0.25, 1]}},
            "shapes": {"floor": {"disk": {"center": [0, 0, -1], "normal": [0, 1, 0], "radius": 1000}, "material": "m"}},
            "lights": {"sky": {"dome": {}, "color": [1, 1, 1], "intensity": 2}}}"#,
        64,
        0,
    );
    assert_matches_expectation(&plane, |_| [1.0, 0.5, 2.0], 0.01);
}

#[test]
fn same_seed_same_image_other_seed_other_noise() {
    let json = r#"{"camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_y": 40, "resolution": [16, 12]},
        "materials": {"m": {"diffuse": [0.7, 0.7, 0.7]}},
        "shapes": {"s": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "m"},
                   "f": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "m"}},
        "lights": {"l": {"sphere": {"center": [1, 2, 1], "radius": 0.3}, "intensity": 10}}}"#;
    let ctx = context();
    let s = scene(json);
    let a = render_with(&ctx, &s, 4, 7);
    let b = render_with(&ctx, &s, 4, 7);
    let c = render_with(&ctx, &s, 4, 8);
    assert_eq!(a.film.beauty, b.film.beauty);
    assert_ne!(a.film.beauty, c.film.beauty);
    assert_no_validation_messages(&ctx);
}

#[test]
fn exr_has_the_aov_layers_and_metadata() {
    let out = render(
        r#"{"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 6]},
            "materials": {"m": {}},
            "shapes": {"s": {"sphere": {"center": [0, 0, 0], "radius": 1}, "material": "m"}},
            "lights": {"sky": {"dome": {}}}}"#,
        2,
    );
    let path = temp_path("aovs.exr");
    let meta = illum::output::ImageMetadata {
        spp: 2,
        render_seconds: out.stats.render_seconds,
        setup_seconds: out.stats.setup_seconds,
        device: "test".into(),
        seed: 0,
        extra: vec![],
    };
    illum::output::write_exr(&path, &out.film, &meta).unwrap();
    let img = illum::output::read_exr(&path).unwrap();
    let mut names: Vec<&str> = img.channels.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    for want in EXR_CHANNELS {
        assert!(names.contains(&want), "missing channel {want} in {names:?}");
    }
    assert_eq!(img.attribute("illum.spp"), Some("2"));
    assert!(img.attribute("illum.renderSeconds").is_some());
    assert!(img.attribute("illum.device").is_some());
    assert!(img.attribute("illum.seed").is_some());
    std::fs::remove_file(&path).ok();
}

/// Uploads larger than the staging buffer go through it in pieces: parts land one after the
/// other, and a write across a piece boundary lands where it was aimed.
#[test]
fn large_uploads_land_whole_through_a_bounded_staging_buffer() {
    use ash::vk;
    let ctx = context();
    let words = |n: usize, seed: u32| -> Vec<u32> {
        (0..n as u32)
            .map(|k| (k ^ seed).wrapping_mul(2_654_435_761))
            .collect()
    };
    let big = words(illum::vk::STAGING_BYTES / 4 + 3, 7);
    let (head, tail) = (words(25, 1), words(10, 2));
    let parts: [&[u8]; 3] = [
        bytemuck::cast_slice(&head),
        bytemuck::cast_slice(&big),
        bytemuck::cast_slice(&tail),
    ];
    let buf = ctx
        .upload_parts(
            "large upload",
            &parts,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
        )
        .unwrap();
    let mut want: Vec<u32> = [&head[..], &big[..], &tail[..]].concat();
    let patch = words(illum::vk::STAGING_BYTES / 4 + 1, 9);
    ctx.write(&buf, 4 * 30, &patch).unwrap();
    want[30..30 + patch.len()].copy_from_slice(&patch);
    let got: Vec<u32> = ctx.download(&buf, want.len()).unwrap();
    assert!(got == want, "the uploaded words differ");
}

/// Iterations glsl/render/loop_probe.comp counts in a nest of `outer` × `inner` loops (a direct
/// measurement, with other loop shapes than the probe's 2 × 40000).
fn loop_count(ctx: &illum::vk::Context, outer: u32, inner: u32) -> u32 {
    use ash::vk;
    let data = ctx
        .upload(
            "loop count",
            &[1u32, 1, 0],
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
        )
        .unwrap();
    let pipeline = illum::vk::ComputePipeline::new(
        ctx,
        "loop count",
        illum::shaders::LOOP_PROBE_PLAIN,
        &[(0, vk::DescriptorType::STORAGE_BUFFER)],
        8,
        &[],
    )
    .unwrap();
    pipeline.bind_buffer(0, vk::DescriptorType::STORAGE_BUFFER, &data);
    ctx.one_shot(|cmd| pipeline.dispatch(cmd, bytemuck::bytes_of(&[outer, inner]), [1, 1, 1]))
        .unwrap();
    let out: Vec<u32> = ctx.download(&data, 3).unwrap();
    out[2]
}

/// The loop-limiter probe (src/render/probe.rs) agrees, on every driver, with direct
/// measurements: loop nests below 65535 iterations in total always run in full; nests above it
/// (one loop of 100000, four of 50000) run in full exactly when the probe says loops are not
/// capped, and all fall short when it says they are. On llvmpipe it also knows the versions:
/// Debian's stock Mesa 22.3 caps loops (it would silently drop samples of long dispatches),
/// Mesa 25 does not.
#[test]
fn loop_limiter_probe_agrees_with_a_direct_measurement() {
    let ctx = context();
    let renderer = illum::render::Renderer::new(ctx.clone());
    let limited = renderer.loop_limited().unwrap();
    let driver = ctx.info().driver.clone();
    for (outer, inner) in [(1, 60_000), (3, 20_000)] {
        let n = loop_count(&ctx, outer, inner);
        assert_eq!(
            n,
            outer * inner,
            "{driver}: a nest of {outer} x {inner} ran {n} iterations"
        );
    }
    let long: Vec<(u32, u32)> = [(1, 100_000), (4, 50_000)]
        .iter()
        .map(|&(outer, inner)| (outer * inner, loop_count(&ctx, outer, inner)))
        .collect();
    eprintln!("{driver}: loops capped: {limited}; iterations asked and run: {long:?}");
    for &(asked, ran) in &long {
        assert!(ran <= asked, "{driver}: {ran} of {asked} iterations");
        assert_eq!(
            limited,
            ran < asked,
            "{driver}: the probe says loops are capped: {limited}, but a nest of {asked} iterations ran {ran}"
        );
    }
    if ctx.info().driver_id == ash::vk::DriverId::MESA_LLVMPIPE {
        if driver.contains("Mesa 22.") {
            assert!(limited, "{driver}");
        }
        if driver.contains("Mesa 25.") {
            assert!(!limited, "{driver}");
        }
    }
    assert_no_validation_messages(&ctx);
}

/// `Renderer::render_seeds` (one pipeline for several independent renders, as the statistical
/// tests use it) gives, seed for seed, exactly the images of separate renders.
#[test]
fn render_seeds_equals_separate_renders() {
    let ctx = context();
    let renderer = illum::render::Renderer::new(ctx.clone());
    let s = scene(
        r#"{"camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_y": 40, "resolution": [8, 6]},
            "materials": {"m": {"diffuse": [0.7, 0.6, 0.5], "specular": [{"model": "ggx", "roughness": 0.3}]}},
            "shapes": {"s": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "m"},
                       "f": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "m"}},
            "lights": {"l": {"sphere": {"center": [1, 2, 1], "radius": 0.3}, "intensity": 10}}}"#,
    );
    let settings = illum::render::RenderSettings {
        spp: 5,
        trace: trace_mode(),
        ..Default::default()
    };
    let seeds = [5u64, 9, 5];
    let many = renderer
        .render_seeds(&s, &settings, &seeds, &mut |_, _| {})
        .unwrap();
    assert_eq!(many.len(), 3);
    for (out, &seed) in many.iter().zip(&seeds) {
        let one = renderer
            .render(
                &s,
                &illum::render::RenderSettings {
                    seed,
                    ..settings.clone()
                },
                &mut |_, _| {},
            )
            .unwrap();
        assert_eq!(out.stats.spp, 5);
        assert_eq!(out.film.beauty, one.film.beauty, "seed {seed}");
        assert_eq!(out.film.variance, one.film.variance, "seed {seed}");
    }
    assert_ne!(many[0].film.beauty, many[1].film.beauty);
    assert_no_validation_messages(&ctx);
}

/// A metallic-roughness material whose metallic and roughness come from two textures (packed
/// into one on load) renders each texel as the plain Lambert + GGX material that the model's
/// formulas give for it: a card of two texels (nearest, clamped) against two half-cards of
/// constant lobes. Same random numbers, so the halves agree to float rounding.
#[test]
fn metallic_roughness_maps_render_texel_by_texel_as_their_constant_lobes() {
    let dir = temp_path("mr-maps");
    std::fs::create_dir_all(&dir).unwrap();
    // Left texel: metallic 0, roughness 0.9; right: metallic 1, roughness 0.3 (R of each map;
    // the other channels would give other images).
    for (file, l, r) in [("metal.exr", 0.0, 1.0), ("rough.exr", 0.9, 0.3)] {
        exr::prelude::write_rgba_file(dir.join(file), 2, 1, |x, _| {
            let v = if x == 0 { l } else { r };
            (v, 0.5, 0.25, 1.0)
        })
        .unwrap();
    }
    let (base, f0_d) = ([0.9, 0.5, 0.2], 0.04);
    let frame = r#""camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 30, "resolution": [32, 16]},
        "lights": {"key": {"rect": {"center": [0.5, 1, 2], "normal": [-0.2, -0.5, -1], "size": [0.5, 0.5]}, "intensity": 8},
                   "sky": {"dome": {}, "color": [0.3, 0.3, 0.3]}}"#;
    let textured = format!(
        r#"{{{frame},
        "textures": {{"metal": {{"file": "metal.exr", "filter": "nearest", "wrap": "clamp"}},
                      "rough": {{"file": "rough.exr", "filter": "nearest", "wrap": "clamp"}}}},
        "materials": {{"card": {{"diffuse": {base:?}, "metallic_roughness": {{"metallic": 1, "roughness": 1,
            "metallic_texture": {{"texture": "metal", "channel": "r"}},
            "roughness_texture": {{"texture": "rough", "channel": "r"}}}}}}}},
        "shapes": {{"card": {{"rect": {{"center": [0, 0, 0], "normal": [0, 0, 1], "size": [2, 1]}}, "material": "card"}}}}}}"#
    );
    let lobe = |m: f64, r: f64| {
        let d: Vec<f64> = base.iter().map(|c| c * (1.0 - m)).collect();
        let f0: Vec<f64> = base.iter().map(|c| f0_d + (c - f0_d) * m).collect();
        format!(
            r#"{{"diffuse": {d:?}, "specular": [{{"model": "ggx", "roughness": {}, "fresnel": {{"schlick": {f0:?}}}}}]}}"#,
            r * r
        )
    };
    let halves = format!(
        r#"{{{frame},
        "materials": {{"left": {}, "right": {}}},
        "shapes": {{"l": {{"rect": {{"center": [-0.5, 0, 0], "normal": [0, 0, 1], "size": [1, 1]}}, "material": "left"}},
                    "r": {{"rect": {{"center": [0.5, 0, 0], "normal": [0, 0, 1], "size": [1, 1]}}, "material": "right"}}}}}}"#,
        lobe(0.0, 0.9),
        lobe(1.0, 0.3)
    );
    let ctx = context();
    let load = |json: &str| illum::scene::from_json_str(json, "<test scene>", &dir).unwrap();
    let a = render_with(&ctx, &load(&textured), 16, 5);
    let b = render_with(&ctx, &load(&halves), 16, 5);
    // Mean luminance of each half's pixels inside the card (rows 5..11), off the seam.
    let half = |out: &illum::render::RenderOutput, cols: std::ops::Range<usize>| {
        let mut sum = 0.0;
        let mut n = 0.0;
        for y in 5..11 {
            for x in cols.clone() {
                sum += luminance(out.film.beauty[y * 32 + x]);
                n += 1.0;
            }
        }
        sum / n
    };
    for cols in [9..15, 17..23] {
        let (ta, tb) = (half(&a, cols.clone()), half(&b, cols.clone()));
        assert!(
            (ta - tb).abs() <= 1e-4 * tb,
            "columns {cols:?}: textured {ta}, constant lobes {tb}"
        );
    }
    // The test sees a map that is not applied: the factors alone (metallic 1, roughness 1
    // everywhere) give another image.
    let factors = halves
        .replace(&lobe(0.0, 0.9), &lobe(1.0, 1.0))
        .replace(&lobe(1.0, 0.3), &lobe(1.0, 1.0));
    let c = render_with(&ctx, &load(&factors), 16, 5);
    for cols in [9..15, 17..23] {
        let (ta, tc) = (half(&a, cols.clone()), half(&c, cols.clone()));
        assert!(
            (ta - tc).abs() > 0.1 * tc,
            "columns {cols:?}: {ta} against {tc}"
        );
    }
    assert_no_validation_messages(&ctx);
}
