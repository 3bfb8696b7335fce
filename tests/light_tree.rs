//! The light tree on the GPU (glsl/lights/light_tree.glsl through tests/kernels/light_tree_check.comp)
//! against the float64 twin of its PMF on the host (src/gpu_scene/light_tree.rs): the sampled
//! probability equals the one replayed from the light's trail bit for bit and the host's to float
//! rounding, the PMFs sum to one less the no-light share, and the frequencies of 2^20 draws at
//! fixed points pass a chi-square test against the host PMF (a draw of a PMF-0 light fails).

mod common;

use common::*;
use glam::{DVec3, Vec3};
use illum::gpu_scene::light_tree::{self, LightTree};
use illum::layout::*;
use std::f64::consts::PI;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TreeParams {
    tree: u64,
    trails: u64,
}

/// A point of the box around the lights, and a little beyond it.
fn point(g: &mut Rng) -> DVec3 {
    DVec3::new(
        g.uniform() * 24.0 - 12.0,
        g.uniform() * 6.0 - 1.0,
        g.uniform() * 24.0 - 12.0,
    )
}

/// Spheres, rects, disks and triangles (some two-sided) of varied power in a 20 × 4 × 20 box.
fn lights(n: usize, seed: u64) -> Vec<GpuLight> {
    let mut g = Rng::new(seed);
    (0..n)
        .map(|i| {
            let c = DVec3::new(
                g.uniform() * 20.0 - 10.0,
                g.uniform() * 4.0,
                g.uniform() * 20.0 - 10.0,
            );
            let r = 0.05 + 0.3 * g.uniform();
            let d = g.sphere();
            let t = d.any_orthonormal_vector();
            let kind = [LIGHT_SPHERE, LIGHT_RECT, LIGHT_DISK, LIGHT_TRIANGLE][i % 4];
            let mut l = GpuLight {
                kind,
                radiance: [(0.1 + 4.0 * g.uniform()) as f32, 1.0, 0.5],
                texture: NONE,
                shape: NONE,
                flags: if i % 5 == 0 { LIGHT_FLAG_TWO_SIDED } else { 0 },
                ..Default::default()
            };
            match kind {
                LIGHT_SPHERE => {
                    l.p0 = f4(c, r);
                    l.area = (4.0 * PI * r * r) as f32;
                }
                LIGHT_DISK => {
                    l.p0 = f4(c, r);
                    l.p1 = [d.x as f32, d.y as f32, d.z as f32];
                    l.p2 = f4(t, 0.0);
                    l.area = (PI * r * r) as f32;
                }
                _ => {
                    let (u, v) = (t * 2.0 * r, d.cross(t) * r);
                    l.p0 = f4(c, 0.0);
                    l.p1 = [u.x as f32, u.y as f32, u.z as f32];
                    l.p2 = f4(v, 0.0);
                    let half = if kind == LIGHT_TRIANGLE { 0.5 } else { 1.0 };
                    l.area = (u.cross(v).length() * half) as f32;
                }
            }
            l
        })
        .collect()
}

struct Setup {
    ctx: illum::vk::Context,
    kernel: Kernel,
    tree: LightTree,
    params: TreeParams,
    _buffers: [illum::vk::Buffer; 2],
}

fn setup(n: usize, seed: u64) -> Setup {
    let ctx = context();
    let ls = lights(n, seed);
    let tree = light_tree::build(&ls, &|_| Vec3::ONE).unwrap().unwrap();
    let storage = ash::vk::BufferUsageFlags::STORAGE_BUFFER;
    let nodes = ctx.upload("tree", &tree.nodes, storage).unwrap();
    let trails = ctx.upload("trails", &tree.trails, storage).unwrap();
    let params = TreeParams {
        tree: nodes.address,
        trails: trails.address,
    };
    let kernel = Kernel::new(
        &ctx,
        "light_tree_check",
        illum_test_kernels::LIGHT_TREE_CHECK_PLAIN,
    );
    Setup {
        ctx,
        kernel,
        tree,
        params,
        _buffers: [nodes, trails],
    }
}

fn point_inputs(pts: &[(DVec3, DVec3)]) -> Vec<[f32; 4]> {
    pts.iter()
        .flat_map(|(p, n)| [f4(*p, 0.0), f4(*n, 0.0)])
        .collect()
}

#[test]
fn sampled_pmf_is_the_replayed_pmf_and_the_host_pmf() {
    let s = setup(1000, 11);
    let mut g = Rng::new(3);
    let pts: Vec<(DVec3, DVec3)> = (0..8192).map(|_| (point(&mut g), g.sphere())).collect();
    let out: Vec<[u32; 4]> =
        s.kernel
            .run(&s.params, &point_inputs(&pts), 0, pts.len(), 17, pts.len());
    let (mut none, mut worst) = (0, 0.0f64);
    for (i, (o, (p, n))) in out.iter().zip(&pts).enumerate() {
        let (light, pmf, replay) = (o[0], f32::from_bits(o[1]), f32::from_bits(o[2]));
        if light == NONE {
            assert_eq!(pmf, 0.0);
            assert!(
                s.tree.pmf_none(*p, *n) > 0.0,
                "point {i}: no light where every path has one"
            );
            none += 1;
            continue;
        }
        assert_eq!(
            pmf.to_bits(),
            replay.to_bits(),
            "point {i}, light {light}: {pmf} vs {replay}"
        );
        let host = s.tree.pmf(*p, *n, light);
        assert!(host > 0.0, "point {i}: drew light {light} of host PMF 0");
        let rel = (f64::from(pmf) / host - 1.0).abs();
        worst = worst.max(rel);
        assert!(
            rel < 1e-3,
            "point {i}, light {light}: device {pmf} vs host {host}"
        );
    }
    eprintln!("largest relative PMF difference {worst:.2e}; {none} of 8192 draws found no light");
    assert!(none < pts.len() / 3, "culling must not end most descents");
    assert_no_validation_messages(&s.ctx);
}

/// Draws at fixed points: frequencies against the host PMF (chi-square, cells of expected count
/// < 5 pooled, plus a no-light cell), with a fresh uniform per level (mode 1) and with one
/// uniform rescaled through the top levels (mode 2, as stratified picks draw).
#[test]
fn draw_frequencies_match_the_pmf() {
    let s = setup(200, 12);
    let lights = s.tree.trails.len();
    // A floor point looking up, a point amid the lights, one near the box's edge facing sideways.
    let points = [
        (DVec3::new(0.0, -1.0, 0.0), DVec3::Y),
        (
            DVec3::new(3.0, 2.0, -2.0),
            DVec3::new(1.0, 1.0, 0.0).normalize(),
        ),
        (
            DVec3::new(-11.0, 0.5, 9.0),
            DVec3::new(0.0, 0.3, -1.0).normalize(),
        ),
    ];
    let cases = 2 * points.len() as u32;
    let alpha = 1.0 - (1.0 - 0.01f64).powf(1.0 / f64::from(cases));
    for (case, (mode, &(p, n))) in (0..cases).zip(
        [1u32, 2]
            .into_iter()
            .flat_map(|m| points.iter().map(move |x| (m, x))),
    ) {
        let count = 1usize << 20;
        let out: Vec<[u32; 4]> = s.kernel.run(
            &s.params,
            &point_inputs(&[(p, n)]),
            mode,
            count,
            100 + case,
            count,
        );
        let mut hist = vec![0u64; lights + 1];
        for o in &out {
            hist[if o[0] == NONE { lights } else { o[0] as usize }] += 1;
        }
        let mut expect: Vec<f64> = (0..lights as u32).map(|l| s.tree.pmf(p, n, l)).collect();
        expect.push(s.tree.pmf_none(p, n));
        let total: f64 = expect.iter().sum();
        assert!((total - 1.0).abs() < 1e-9, "PMF sums to {total}");
        let (mut chi2, mut cells, mut pooled_o, mut pooled_e) = (0.0, 0, 0.0, 0.0);
        for (o, e) in hist.iter().zip(&expect) {
            let (o, e) = (*o as f64, e * count as f64);
            assert!(
                e > 0.0 || o == 0.0,
                "case {case}: {o} draws of a light of PMF 0"
            );
            if e < 5.0 {
                pooled_o += o;
                pooled_e += e;
            } else {
                chi2 += (o - e) * (o - e) / e;
                cells += 1;
            }
        }
        if pooled_e > 0.0 {
            chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
            cells += 1;
        }
        let pv = chi2_sf(chi2, f64::from(cells - 1));
        eprintln!("case {case}: chi2 {chi2:.1} over {cells} cells, p = {pv:.3}");
        assert!(cells > 20, "case {case}: too few cells to test ({cells})");
        assert!(pv > alpha, "case {case}: p = {pv:.2e} < {alpha:.2e}");
    }
    assert_no_validation_messages(&s.ctx);
}
