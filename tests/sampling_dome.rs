//! Dome sampling: the tables of every map convention (src/gpu_scene/dome.rs) against independent
//! f64 weights and chi-square tests of the GPU sampler (glsl/lights/light_sampling.glsl through
//! tests/kernels/sample_light.comp; the harness is tests/common/lights.rs), and the table builder's
//! edge cases.

mod common;

use common::lights::*;
use common::*;
use glam::{DVec2, DVec3, Vec3, Vec4};
use illum::gpu_scene::dome;
use illum::layout::*;
use illum::scene::{DomeConvention, dome_map};
use std::f64::consts::PI;

fn texture(name: &str, w: u32, h: u32, f: impl Fn(u32, u32) -> Vec4) -> illum::scene::Texture {
    let mut texels = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            texels.push(f(i, j));
        }
    }
    illum::scene::Texture::new(name, w, h, texels)
}

/// Cell-aligned bins (`sub` × `sub` per sampling cell of src/gpu_scene/dome.rs) in map coordinates:
/// the sampler's density is constant in each, so the quadrature is exact.
fn dome_domain(conv: DomeConvention, w: u32, h: u32, sub: usize, rot_deg: f64) -> Domain {
    let (cw, ch) = dome::cells(conv, w, h);
    let off = if conv == DomeConvention::Mitsuba {
        0.5 / f64::from(w)
    } else {
        0.0
    };
    Domain {
        to_dir: Box::new(move |x, y| {
            let uv = DVec2::new((x + off).rem_euclid(1.0), y);
            Some(dome_map::direction(conv, rot_deg, uv))
        }),
        from_dir: Box::new(move |d| {
            let uv = dome_map::uv(conv, rot_deg, d);
            Some(((uv.x - off).rem_euclid(1.0), uv.y))
        }),
        nx: cw as usize * sub,
        ny: ch as usize * sub,
    }
}

#[allow(clippy::too_many_arguments)]
fn dome_case(
    g: &Lights,
    name: &str,
    tex: &illum::scene::Texture,
    tint: Vec3,
    rot_deg: f64,
    conv: DomeConvention,
    sub: usize,
    seed: u32,
    defensive: f32,
    corners: bool,
) {
    let mut table = dome::build(tex, tint, conv);
    table.texel_offset = corners.then_some(0);
    let data = g
        .ctx
        .upload_parts(
            "dome table",
            &table.parts(),
            ash::vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap();
    // With `corners`, the map's texels where a Mitsuba-convention sampler reads its cell's
    // corners (GpuDomeSampling.texels), under a light of the table's colour.
    let texels = g
        .ctx
        .upload(
            "dome texels",
            &tex.texels,
            ash::vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap();
    let mut l = dome_light(rot_deg);
    l.radiance = tint.to_array();
    l.flags |= match conv {
        DomeConvention::Illum => 0,
        DomeConvention::Mitsuba => LIGHT_FLAG_DOME_MITSUBA,
        DomeConvention::Pbrt => LIGHT_FLAG_DOME_PBRT,
    };
    let mut prm = LightParams {
        dome: table.gpu(data.address, texels.address),
        light: l,
        p: [0.0; 4],
    };
    // The uniform share that control variates mix in (glsl/lights/infinite_lights.glsl).
    prm.dome.defensive = defensive;
    let a = f64::from(defensive);
    let (w, h) = (tex.width, tex.height);
    let (cw, ch) = dome::cells(conv, w, h);

    // illum's table is the tent-filtered luminance times sin(theta), normalised (independent f64
    // check of the builder).
    if conv == DomeConvention::Illum {
        let lum = |i: i64, j: i64| {
            let t =
                tex.texels[(j.rem_euclid(h as i64) * w as i64 + i.rem_euclid(w as i64)) as usize];
            dome::luminance((tint * t.truncate()).as_dvec3()).max(0.0)
        };
        let k = [0.125, 0.75, 0.125];
        let mut weights = vec![0.0; (w * h) as usize];
        for j in 0..h as i64 {
            for i in 0..w as i64 {
                let mut s = 0.0;
                for b in 0..3 {
                    for a in 0..3 {
                        s += k[a] * k[b] * lum(i + a as i64 - 1, j + b as i64 - 1);
                    }
                }
                weights[(j * w as i64 + i) as usize] = s * (PI * (j as f64 + 0.5) / h as f64).sin();
            }
        }
        let total: f64 = weights.iter().sum();
        for j in 0..h {
            for i in 0..w {
                let p = table.texel_probability(i, j);
                let q = weights[(j * w + i) as usize] / total;
                // float32 CDFs: absolute error of a difference of two entries <= 2 ulp(1).
                assert!(
                    (p - q).abs() <= 1e-6 * q + 2.4e-7,
                    "{name}: texel ({i}, {j}): table {p} vs {q}"
                );
            }
        }
    }
    // The GPU pdf at two points of every cell is the table's probability over the cell's solid
    // angle times the lookup's luminance there over its mean in the cell (f64, from the texels:
    // illum's bilinear lookup is `Texture::lookup`, Mitsuba's the patch of the cell's four corner
    // texels; nearest and pbrt lookups are constant in a cell).
    let off = if conv == DomeConvention::Mitsuba {
        0.5 / f64::from(w)
    } else {
        0.0
    };
    // Texel luminance as the lookups wrap: Mitsuba's periodic in u (its rows are all inside the
    // map), illum's by the texture's wrap modes.
    let lum_at = |i: i64, j: i64| {
        let t = match conv {
            DomeConvention::Mitsuba => tex.texel(i.rem_euclid(w as i64), j),
            _ => tex.texel(i, j),
        };
        dome::luminance((tint * t.truncate()).as_dvec3()).max(0.0)
    };
    // Which cells are shaped is the builder's decision (the sign of a cell's first node, where
    // its luminance varies enough); the density inside those is checked here.
    let shaped = |i: i64, j: i64| {
        table.nodes_width > 0
            && table.nodes[((j + 1) * i64::from(table.nodes_width) + i + 1) as usize]
                .is_sign_negative()
    };
    let shape = |i: u32, j: u32, f: DVec2, uv: DVec2| -> f64 {
        let (i, j) = (i64::from(i), i64::from(j));
        if !shaped(i, j) {
            return 1.0;
        }
        match (conv, tex.filter) {
            (DomeConvention::Mitsuba, _) => {
                let c = [
                    lum_at(i, j),
                    lum_at(i + 1, j),
                    lum_at(i, j + 1),
                    lum_at(i + 1, j + 1),
                ];
                let mean = 0.25 * c.iter().sum::<f64>();
                let v = (c[0] * (1.0 - f.x) + c[1] * f.x) * (1.0 - f.y)
                    + (c[2] * (1.0 - f.x) + c[3] * f.x) * f.y;
                if mean > 0.0 { v / mean } else { 1.0 }
            }
            (DomeConvention::Illum, illum::scene::TextureFilter::Bilinear) => {
                let k = [0.125, 0.75, 0.125];
                let mut mean = 0.0;
                for (b, kb) in k.iter().enumerate() {
                    for (a, ka) in k.iter().enumerate() {
                        mean += ka * kb * lum_at(i + a as i64 - 1, j + b as i64 - 1);
                    }
                }
                let v =
                    dome::luminance((tint.as_dvec3() * tex.lookup(uv).truncate()).max(DVec3::ZERO));
                if mean > 0.0 { v / mean } else { 1.0 }
            }
            _ => 1.0,
        }
    };
    let mut centres = Vec::new();
    for j in 0..ch {
        for i in 0..cw {
            for f in [DVec2::new(0.5, 0.5), DVec2::new(0.2, 0.7)] {
                let uv = DVec2::new(
                    ((f64::from(i) + f.x) / f64::from(cw) + off).rem_euclid(1.0),
                    (f64::from(j) + f.y) / f64::from(ch),
                );
                let (dir, jacobian) = dome_map::direction(conv, rot_deg, uv);
                let pdf = a / (4.0 * PI)
                    + (1.0 - a)
                        * table.texel_probability(i, j)
                        * shape(i, j, f, uv)
                        * f64::from(cw * ch)
                        / jacobian;
                centres.push((f4(dir, 0.0), pdf));
            }
        }
    }
    let dirs: Vec<[f32; 4]> = centres.iter().map(|c| c.0).collect();
    let hits = g.hit(&prm, &dirs);
    for ((_, expected), got) in centres.iter().zip(&hits) {
        let got = f64::from(got[0]);
        assert!(
            (got - expected).abs() <= 1e-4 * expected + 1e-12,
            "{name}: GPU pdf {got} vs table {expected}"
        );
    }
    // Samples on a cell boundary (to float precision) may be attributed to the neighbour by pdf(),
    // and where the density inside a cell is steep (a hot texel's neighbours: 1e4 times its
    // luminance over one cell), pdf() of the direction, taken back to map coordinates in float32
    // (about 1e-6 off), reads it a little elsewhere. `ambiguous` gets the sample's map coordinates.
    let shape_at = |u: f64, v: f64| {
        let (x, y) = ((u - off).rem_euclid(1.0) * f64::from(cw), v * f64::from(ch));
        let (i, j) = ((x as u32).min(cw - 1), (y as u32).min(ch - 1));
        let f = DVec2::new(x - f64::from(i), y - f64::from(j));
        shape(i, j, f, DVec2::new(u, v))
    };
    let ambiguous = |(u, v): (f64, f64)| {
        let near = |x: f64| (x - x.round()).abs() < 1e-4;
        let s = shape_at(u, v);
        let steep = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            .iter()
            .any(|(a, b)| {
                let e = 2e-6;
                (shape_at((u + a * e).rem_euclid(1.0), (v + b * e).clamp(0.0, 1.0)) / s - 1.0).abs()
                    > 5e-4
            });
        near((u - off).rem_euclid(1.0) * f64::from(cw)) || near(v * f64::from(ch)) || steep
    };
    g.check(
        name,
        &prm,
        &dome_domain(conv, w, h, sub, rot_deg),
        seed,
        &ambiguous,
    );
    // A sampler that read its cell's corners returns the lookup's radiance there (f64, the
    // convention's own lookup); one that did not, none (light_radiance() then looks it up).
    let out = g.sample(&prm, 4096, seed + 1000);
    for i in (0..4096).filter(|&i| out.pdf(i) > 0.0) {
        let le = out.x(i);
        if !corners {
            assert!(
                le.x < 0.0,
                "{name}: sample {i} has a radiance {le} it did not read"
            );
            continue;
        }
        let (u, v) = out.uv(i);
        let expected = tint.as_dvec3()
            * dome_map::lookup(tex, conv, DVec2::new(u, v))
                .truncate()
                .max(DVec3::ZERO);
        assert!(
            (le - expected).abs().max_element() <= 1e-4 * expected.max_element() + 1e-6,
            "{name}: sample {i} at ({u}, {v}): radiance {le} against the lookup's {expected}"
        );
    }
    drop((data, texels));
}

#[test]
fn chi2_dome() {
    let g = Lights::new();
    // One hot texel over a dim background.
    let hot = texture("hot", 32, 16, |i, j| {
        if (i, j) == (21, 5) {
            Vec4::new(2000.0, 1500.0, 1000.0, 1.0)
        } else {
            Vec4::new(0.1, 0.1, 0.1, 1.0)
        }
    });
    dome_case(
        &g,
        "dome hot pixel",
        &hot,
        Vec3::ONE,
        30.0,
        DomeConvention::Illum,
        2,
        60,
        0.0,
        false,
    );
    dome_case(
        &g,
        "Mitsuba dome hot pixel",
        &hot,
        Vec3::ONE,
        30.0,
        DomeConvention::Mitsuba,
        2,
        63,
        0.0,
        false,
    );
    // The same, its corners read by the sampler for the cell's shape and the sample's radiance.
    dome_case(
        &g,
        "Mitsuba dome hot pixel, corners read",
        &hot,
        Vec3::new(1.0, 0.8, 0.6),
        30.0,
        DomeConvention::Mitsuba,
        2,
        66,
        0.0,
        true,
    );
    // A smooth sky: brighter toward the zenith and toward one azimuth, tinted.
    let sky = texture("sky", 64, 32, |i, j| {
        let theta = PI * (f64::from(j) + 0.5) / 32.0;
        let phi = 2.0 * PI * (f64::from(i) + 0.5) / 64.0;
        let s = 0.2 + (0.5 * theta).cos().powi(4) * (1.5 + phi.cos());
        Vec4::new(0.6 * s as f32, 0.8 * s as f32, s as f32, 1.0)
    });
    dome_case(
        &g,
        "dome sky",
        &sky,
        Vec3::new(1.0, 0.9, 0.7),
        -75.0,
        DomeConvention::Illum,
        2,
        61,
        0.0,
        false,
    );
    dome_case(
        &g,
        "Mitsuba dome sky, corners read",
        &sky,
        Vec3::new(1.0, 0.9, 0.7),
        -75.0,
        DomeConvention::Mitsuba,
        2,
        67,
        0.0,
        true,
    );
    // pbrt's equal-area square: a hot texel near a crease of the octahedral map, over a gradient.
    let square = texture("square", 16, 16, |i, j| {
        if (i, j) == (10, 4) {
            Vec4::new(800.0, 800.0, 800.0, 1.0)
        } else {
            let g = 0.2 + 0.05 * f64::from(i + j);
            Vec4::new(g as f32, g as f32, g as f32, 1.0)
        }
    });
    dome_case(
        &g,
        "pbrt dome",
        &square,
        Vec3::ONE,
        20.0,
        DomeConvention::Pbrt,
        2,
        64,
        0.0,
        false,
    );
    // The same with the uniform share of control variates: the equal-area square keeps both
    // parts' densities constant per bin, so the chi-square quadrature stays exact.
    dome_case(
        &g,
        "pbrt dome, uniform share 0.3",
        &square,
        Vec3::ONE,
        20.0,
        DomeConvention::Pbrt,
        2,
        65,
        0.3,
        false,
    );
    // No table: uniform over the sphere.
    let prm = params(dome_light(0.0), DVec3::ZERO);
    g.check(
        "dome uniform",
        &prm,
        &Domain::cone(DVec3::Y, 2.0, 16, 32),
        62,
        &never,
    );
    g.finish();
}

#[test]
fn dome_table_builder() {
    // All-black map: uniform in solid angle (sin theta per row), still a valid pdf.
    let black = texture("black", 8, 4, |_, _| Vec4::ZERO);
    let t = dome::build(&black, Vec3::ONE, DomeConvention::Illum);
    assert_eq!(t.marginal.len(), 5);
    assert_eq!(*t.marginal.last().unwrap(), 1.0);
    let sum: f64 = (0..4)
        .flat_map(|j| (0..8).map(move |i| (i, j)))
        .map(|(i, j)| t.texel_probability(i, j))
        .sum();
    assert!((sum - 1.0).abs() < 1e-6);
    // A zero row of the tint's channels: a red-only texture under a blue tint is black.
    let red = texture("red", 8, 4, |_, _| Vec4::new(1.0, 0.0, 0.0, 1.0));
    let t2 = dome::build(&red, Vec3::new(0.0, 0.0, 1.0), DomeConvention::Illum);
    assert_eq!(t2.marginal, t.marginal);
}
