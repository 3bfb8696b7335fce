use super::*;

/// A small deterministic generator (no dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn dir(&mut self) -> DVec3 {
        let z = 2.0 * self.next() - 1.0;
        let phi = 2.0 * PI * self.next();
        let s = (1.0 - z * z).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

fn f4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// Mixed finite lights scattered in a box, plus a dome (left out of the tree).
fn lights(n: usize, seed: u64) -> Vec<GpuLight> {
    let mut g = Lcg(seed);
    let mut out = Vec::new();
    for i in 0..n {
        let c = DVec3::new(
            g.next() * 20.0 - 10.0,
            g.next() * 4.0,
            g.next() * 20.0 - 10.0,
        );
        let r = 0.05 + 0.3 * g.next();
        let (u, v) = {
            let d = g.dir();
            let t = d.any_orthonormal_vector();
            (t * r * 2.0, d.cross(t) * r)
        };
        let kind = [LIGHT_SPHERE, LIGHT_RECT, LIGHT_DISK, LIGHT_TRIANGLE][i % 4];
        let mut l = GpuLight {
            kind,
            radiance: [1.0 + g.next() as f32, 2.0, 0.5],
            texture: NONE,
            shape: NONE,
            flags: if i % 7 == 0 { LIGHT_FLAG_TWO_SIDED } else { 0 },
            ..Default::default()
        };
        match kind {
            LIGHT_SPHERE => {
                l.p0 = f4(c, r);
                l.area = (4.0 * PI * r * r) as f32;
            }
            LIGHT_RECT | LIGHT_TRIANGLE => {
                l.p0 = f4(c, 0.0);
                l.p1 = [u.x as f32, u.y as f32, u.z as f32];
                l.p2 = f4(v, 0.0);
                l.area = (u.cross(v).length() * if kind == LIGHT_RECT { 1.0 } else { 0.5 }) as f32;
            }
            _ => {
                let d = g.dir();
                l.p0 = f4(c, r);
                l.p1 = [d.x as f32, d.y as f32, d.z as f32];
                l.p2 = f4(d.any_orthonormal_vector(), 0.0);
                l.area = (PI * r * r) as f32;
            }
        }
        out.push(l);
    }
    out.push(GpuLight {
        kind: LIGHT_DOME,
        radiance: [1.0; 3],
        ..Default::default()
    });
    out
}

fn no_texture(_: u32) -> Vec3 {
    Vec3::ONE
}

#[test]
fn every_light_has_one_leaf_and_its_trail_leads_there() {
    let ls = lights(301, 1);
    let t = build(&ls, &no_texture).unwrap().unwrap();
    assert_eq!(t.nodes.len(), 2 * 301 - 1);
    assert!(t.depth < LIGHT_TREE_MAX_DEPTH);
    let mut seen = vec![0; ls.len()];
    for n in &t.nodes {
        if n.link & LIGHT_TREE_LEAF != 0 {
            seen[(n.link & !LIGHT_TREE_LEAF) as usize] += 1;
        }
    }
    assert_eq!(&seen[..301], &[1; 301][..]);
    assert_eq!(seen[301], 0, "the dome is not in the tree");
    for (i, &trail) in t.trails[..301].iter().enumerate() {
        let (mut k, mut bits) = (0usize, trail);
        while t.nodes[k].link & LIGHT_TREE_LEAF == 0 {
            k = if bits & 1 != 0 {
                t.nodes[k].link as usize
            } else {
                k + 1
            };
            bits >>= 1;
        }
        assert_eq!(t.nodes[k].link & !LIGHT_TREE_LEAF, i as u32);
    }
}

/// Node indices of the leaves below node i.
fn leaves(t: &LightTree, i: usize, out: &mut Vec<usize>) {
    let n = &t.nodes[i];
    if n.link & LIGHT_TREE_LEAF != 0 {
        out.push(i);
    } else {
        leaves(t, i + 1, out);
        leaves(t, n.link as usize, out);
    }
}

#[test]
fn nodes_bound_their_emitters() {
    let ls = lights(200, 2);
    let t = build(&ls, &no_texture).unwrap().unwrap();
    assert!((t.nodes[0].power - 1.0).abs() < 1e-6);
    for (i, n) in t.nodes.iter().enumerate() {
        if n.link & LIGHT_TREE_LEAF != 0 {
            continue;
        }
        let (a, b) = (&t.nodes[i + 1], &t.nodes[n.link as usize]);
        assert!(((a.power + b.power) / n.power - 1.0).abs() < 1e-5);
        let axis = Vec3::from(n.axis).as_dvec3();
        let mut below = Vec::new();
        leaves(&t, i, &mut below);
        for c in below.iter().map(|&k| &t.nodes[k]) {
            assert!(Vec3::from(c.lo).cmpge(Vec3::from(n.lo)).all());
            assert!(Vec3::from(c.hi).cmple(Vec3::from(n.hi)).all());
            // Every emitter's normal cone lies inside the node's.
            let to = f64::from(n.cos_o).acos();
            let tc = f64::from(c.cos_o).acos();
            let d = axis.angle_between(Vec3::from(c.axis).as_dvec3());
            assert!(
                to >= PI - 1e-6 || d + tc <= to + 1e-6,
                "node {i}: {d} + {tc} > {to}"
            );
            assert!(n.flags & LIGHT_TREE_TWO_SIDED >= c.flags & LIGHT_TREE_TWO_SIDED);
        }
    }
}

#[test]
fn pmf_sums_to_one_with_the_no_light_share() {
    let ls = lights(150, 3);
    let t = build(&ls, &no_texture).unwrap().unwrap();
    let mut g = Lcg(9);
    let mut none_sum = 0.0;
    for _ in 0..50 {
        let p = DVec3::new(
            g.next() * 24.0 - 12.0,
            g.next() * 6.0 - 1.0,
            g.next() * 24.0 - 12.0,
        );
        let n = g.dir();
        let sum: f64 = (0..150).map(|i| t.pmf(p, n, i)).sum();
        let none = t.pmf_none(p, n);
        assert!((sum + none - 1.0).abs() < 1e-9, "{sum} + {none}");
        none_sum += none;
    }
    // Culling wastes some descents (I is not monotone), not most.
    assert!(
        none_sum / 50.0 < 0.3,
        "mean no-light share {}",
        none_sum / 50.0
    );
}

/// docs/techniques.md, "The light tree": importance is 0 only where provably nothing reaches p, so
/// every light that can light p (some of it above p's horizon and p on its emitting side) has
/// PMF > 0.
#[test]
fn every_light_that_can_reach_p_has_positive_pmf() {
    let ls = lights(120, 4);
    let t = build(&ls, &no_texture).unwrap().unwrap();
    let mut g = Lcg(5);
    let mut reached = 0;
    for _ in 0..60 {
        let p = DVec3::new(
            g.next() * 24.0 - 12.0,
            g.next() * 6.0 - 1.0,
            g.next() * 24.0 - 12.0,
        );
        let n = g.dir();
        for (i, l) in ls[..120].iter().enumerate() {
            let c = DVec3::new(l.p0[0].into(), l.p0[1].into(), l.p0[2].into());
            // A sufficient condition for reaching p: the centre well above p's horizon and (for
            // one-sided planar emitters) p well in front of it.
            let to = c - p;
            let above = n.dot(to.normalize()) > 0.05;
            let front = match l.kind {
                LIGHT_SPHERE => true,
                _ if l.flags & LIGHT_FLAG_TWO_SIDED != 0 => true,
                LIGHT_DISK => {
                    DVec3::new(l.p1[0].into(), l.p1[1].into(), l.p1[2].into()).dot(-to.normalize())
                        > 0.05
                }
                _ => {
                    let e1 = DVec3::new(l.p1[0].into(), l.p1[1].into(), l.p1[2].into());
                    let e2 = DVec3::new(l.p2[0].into(), l.p2[1].into(), l.p2[2].into());
                    let c = if l.kind == LIGHT_TRIANGLE {
                        c + (e1 + e2) / 3.0
                    } else {
                        c
                    };
                    e1.cross(e2).normalize().dot((p - c).normalize()) > 0.05
                }
            };
            if above && front {
                reached += 1;
                assert!(t.pmf(p, n, i as u32) > 0.0, "light {i} at {p} {n}");
            }
        }
    }
    assert!(reached > 1000);
}

#[test]
fn depth_stays_within_the_trail_for_adversarial_layouts() {
    // Exponentially spaced lights: an SAOH split peels one light per level.
    let ls: Vec<GpuLight> = (0..200)
        .map(|i| GpuLight {
            kind: LIGHT_SPHERE,
            p0: [1.5f32.powi(i.min(200)) * 1e-20, 0.0, 0.0, 1e-22],
            radiance: [1.0; 3],
            area: 1e-43,
            ..Default::default()
        })
        .collect();
    let t = build(&ls, &no_texture).unwrap().unwrap();
    assert!(t.depth < LIGHT_TREE_MAX_DEPTH, "depth {}", t.depth);
    // All lights at one point: only median splits.
    let same: Vec<GpuLight> = (0..1000).map(|_| ls[0]).collect();
    let t = build(&same, &no_texture).unwrap().unwrap();
    assert_eq!(t.depth, 10);
}

#[test]
fn orientation_measure_of_known_cones() {
    // M_Omega = pi for a one-sided Lambertian emitter, 4 pi for a point (docs/techniques.md,
    // "The light tree").
    let b = |theta_o| Bounds {
        lo: DVec3::ZERO,
        hi: DVec3::ONE,
        power: 1.0,
        axis: DVec3::Z,
        theta_o,
        theta_e: PI / 2.0,
        two_sided: false,
    };
    let area = 6.0;
    assert!((b(0.0).cost(1.0) / area - PI).abs() < 1e-12);
    assert!((b(PI).cost(1.0) / area - 4.0 * PI).abs() < 1e-12);
}

#[test]
fn textured_lights_count_at_their_mean() {
    let mut l = lights(1, 6)[0];
    let plain = light_bounds_of(&l, &no_texture).unwrap().power;
    l.texture = 0;
    let half = light_bounds_of(&l, &|_| Vec3::splat(0.5)).unwrap().power;
    assert!((half / plain - 0.5).abs() < 1e-12);
}
