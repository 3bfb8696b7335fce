//! An independent float64 reference for the glossy stress cases: the reflected radiance at a point
//! of the floor, L_o(p, v) = Σ_lights ∫ f(l, v) L_e(l) (n·l) dω_l, by composite Gauss-Legendre
//! quadrature over each light, with the BRDF written here from its formulas (docs/techniques.md,
//! "The D-BRDF" and "Cook-Torrance lobes"; Walter et al. 2007; Heitz 2014; pbrt-v4's
//! height-correlated GGX), not ported from `glsl/scene/microfacet.glsl`.
//!
//! Each domain is parameterised so that its edges, the horizon included, are coordinate lines
//! and the integrand is smooth inside: a rect light over its area, a sphere light or the sun
//! cone in (elevation, azimuth) about the normal (the horizon is elevation 0, and elevation is
//! substituted e = β + ρ sin τ so that the cone's √ edges become smooth), the dome over the
//! upper hemisphere. The quadrature error is then the panels' resolution of the BRDF lobe,
//! checked against a quadrature with twice the panels in every direction
//! (`glossy_reference_quadrature_is_converged`).

use glam::DVec3;
use illum::scene::{Distribution, Fresnel, LightKind, Scene};
use std::f64::consts::PI;

/// One specular lobe: D-BRDF (Beckmann, no shadowing) or Cook-Torrance GGX with the
/// height-correlated Smith G2; alphas along the tangent and the bitangent; constant Fresnel.
#[derive(Clone, Copy, Debug)]
pub struct Lobe {
    pub ggx: bool,
    pub alpha: (f64, f64),
    pub fresnel: f64,
}

/// A Lambert + specular material in a shading frame (t, b, n).
#[derive(Clone, Debug)]
pub struct Brdf {
    pub diffuse: f64,
    pub lobes: Vec<Lobe>,
    pub t: DVec3,
    pub b: DVec3,
    pub n: DVec3,
}

impl Brdf {
    /// f(l, v) (n·l); zero unless both directions are above the surface.
    pub fn f_cos(&self, v: DVec3, l: DVec3) -> f64 {
        let (nv, nl) = (self.n.dot(v), self.n.dot(l));
        if nv <= 0.0 || nl <= 0.0 {
            return 0.0;
        }
        let mut f = self.diffuse / PI;
        let h = (v + l).normalize();
        let (ht, hb, hn) = (self.t.dot(h), self.b.dot(h), self.n.dot(h));
        let vh = v.dot(h);
        for lobe in &self.lobes {
            let (a1, a2) = lobe.alpha;
            if lobe.ggx {
                // Trowbridge-Reitz: D = 1 / (π a1 a2 ((h·t/a1)² + (h·b/a2)² + (h·n)²)²).
                let q = (ht / a1).powi(2) + (hb / a2).powi(2) + hn * hn;
                let d = 1.0 / (PI * a1 * a2 * q * q);
                // Λ(w) = (√(1 + α_w² tan²θ_w) − 1) / 2, α_w² tan²θ_w = ((w·t a1)² + (w·b a2)²)/(w·n)².
                let lambda = |w: DVec3| {
                    let wn = self.n.dot(w);
                    let s =
                        ((self.t.dot(w) * a1).powi(2) + (self.b.dot(w) * a2).powi(2)) / (wn * wn);
                    0.5 * ((1.0 + s).sqrt() - 1.0)
                };
                let g2 = 1.0 / (1.0 + lambda(v) + lambda(l));
                f += lobe.fresnel * d * g2 / (4.0 * nl * nv);
            } else {
                // Beckmann: D = exp(−((h·t/a1)² + (h·b/a2)²)/(h·n)²) / (π a1 a2 (h·n)⁴);
                // the course's f = F D (n·h) / (4 (n·l)(v·h)).
                let e = ((ht / a1).powi(2) + (hb / a2).powi(2)) / (hn * hn);
                let d = (-e).exp() / (PI * a1 * a2 * hn.powi(4));
                f += lobe.fresnel * d * hn / (4.0 * nl * vh);
            }
        }
        f * nl
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton's method on P_n).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Quadrature resolution: `panels` composite panels of a 6-point Gauss-Legendre rule along each
/// dimension of each light's domain.
#[derive(Clone, Copy, Debug)]
pub struct Quadrature {
    pub panels: usize,
}

const NODES: usize = 6;

/// ∫_a^b g by `panels` panels of the Gauss-Legendre rule `gl`.
fn composite(
    gl: &[(f64, f64)],
    panels: usize,
    a: f64,
    b: f64,
    mut g: impl FnMut(f64) -> f64,
) -> f64 {
    let w = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let c = a + (p as f64 + 0.5) * w;
        for &(x, wt) in gl {
            sum += wt * 0.5 * w * g(c + 0.5 * w * x);
        }
    }
    sum
}

/// An orthonormal frame (x, y, z = n).
fn frame(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = a.cross(n).normalize();
    (x, n.cross(x))
}

/// ∫ over the cone of half-angle `rho` about `axis`, clipped at the horizon of `n`, of g(l) dω.
fn cone(
    q: Quadrature,
    gl: &[(f64, f64)],
    n: DVec3,
    axis: DVec3,
    rho: f64,
    g: &dyn Fn(DVec3) -> f64,
) -> f64 {
    let beta = n.dot(axis).clamp(-1.0, 1.0).asin();
    assert!(beta + rho < 0.5 * PI - 1e-6, "the cone contains the pole");
    // Azimuth measured from the axis's own azimuth.
    let (x, y) = {
        let p = axis - n * n.dot(axis);
        if p.length() > 1e-12 {
            let x = p.normalize();
            (x, n.cross(x))
        } else {
            frame(n)
        }
    };
    if beta + rho <= 0.0 {
        return 0.0;
    }
    // e = β + ρ sin τ, τ ∈ [τ0, π/2], τ0 where e = max(0, β − ρ).
    let tau0 = if beta - rho >= 0.0 {
        -0.5 * PI
    } else {
        (-beta / rho).asin()
    };
    let (cr, sb, cb) = (rho.cos(), beta.sin(), beta.cos());
    composite(gl, q.panels, tau0, 0.5 * PI, |tau| {
        let e = beta + rho * tau.sin();
        let (se, ce) = e.sin_cos();
        let c = ((cr - se * sb) / (ce * cb)).clamp(-1.0, 1.0);
        let half = c.acos();
        let jac = rho * tau.cos() * ce;
        // φ = half · sin σ: nodes dense toward the cone's edge, where the azimuth range ends
        // with a square-root profile in e.
        jac * composite(gl, q.panels, -0.5 * PI, 0.5 * PI, |s| {
            let phi = half * s.sin();
            let l = ce * (phi.cos() * x + phi.sin() * y) + se * n;
            half * s.cos() * g(l)
        })
    })
}

/// The reflected radiance at `p` (floor point, material `brdf`) toward `v` from every light of
/// `scene`, with nothing occluded: the floor is one plane, and the area lights must be
/// `"shadows": false` (as the stress scenes make them), so that none hides another or the dome.
pub fn radiance(scene: &Scene, brdf: &Brdf, p: DVec3, v: DVec3, q: Quadrature) -> f64 {
    let gl = gauss_legendre(NODES);
    let n = brdf.n;
    let mut total = 0.0;
    for light in &scene.lights {
        let c =
            light.color.as_dvec3() * f64::from(light.intensity) * f64::from(light.exposure).exp2();
        assert!(c.x == c.y && c.y == c.z, "{}: grey lights only", light.name);
        assert!(
            light.texture.is_none(),
            "{}: untextured lights only",
            light.name
        );
        let le = c.x;
        assert!(
            !light.shadows || matches!(light.kind, LightKind::Dome { .. } | LightKind::Sun { .. }),
            "{}: an opaque area light would hide the lights behind it; the reference has no occlusion",
            light.name
        );
        total += match &light.kind {
            LightKind::Rect { center, u, v: ev } => {
                let ln = u.cross(*ev).normalize();
                let area = u.cross(*ev).length();
                let corner = *center - 0.5 * *u - 0.5 * *ev;
                assert!(
                    ln.dot(p - *center) > 0.0,
                    "{}: faces away from the point",
                    light.name
                );
                le * area
                    * composite(&gl, q.panels, 0.0, 1.0, |s| {
                        composite(&gl, q.panels, 0.0, 1.0, |t| {
                            let d = corner + s * *u + t * *ev - p;
                            let r2 = d.length_squared();
                            let l = d / r2.sqrt();
                            let cos_light = -ln.dot(l);
                            if cos_light <= 0.0 {
                                return 0.0;
                            }
                            brdf.f_cos(v, l) * cos_light / r2
                        })
                    })
            }
            LightKind::Sphere { center, radius } => {
                let d = *center - p;
                let rho = (radius / d.length()).asin();
                le * cone(q, &gl, n, d.normalize(), rho, &|l| brdf.f_cos(v, l))
            }
            LightKind::Sun {
                direction,
                angular_diameter_deg,
            } => {
                let rho = 0.5 * angular_diameter_deg.to_radians();
                assert!(rho > 0.0, "a delta sun has no cone");
                // Irradiance E at normal incidence from a uniform cone: E = π sin²ρ L.
                let l_sun = le / (PI * rho.sin().powi(2));
                l_sun * cone(q, &gl, n, direction.normalize(), rho, &|l| brdf.f_cos(v, l))
            }
            LightKind::Dome { .. } => {
                let (x, y) = frame(n);
                le * composite(&gl, q.panels, 0.0, 1.0, |ct| {
                    let st = (1.0 - ct * ct).sqrt();
                    composite(&gl, 2 * q.panels, 0.0, 2.0 * PI, |phi| {
                        brdf.f_cos(v, st * (phi.cos() * x + phi.sin() * y) + ct * n)
                    })
                })
            }
            LightKind::Disk { .. } => panic!("{}: no disk lights in these cases", light.name),
        };
    }
    total
}

/// The floor material at `p` in the glossy stress scenes: rect `left` (x < 0) is material
/// `dbrdf`, `right` (x > 0) is `ggx`, both in the plane y = 0 facing +y, tangent +x.
pub fn floor_brdf(scene: &Scene, p: DVec3) -> Brdf {
    let name = if p.x < 0.0 { "dbrdf" } else { "ggx" };
    let m = scene
        .materials
        .iter()
        .find(|m| m.name == name)
        .expect("material");
    assert!(m.diffuse.x == m.diffuse.y && m.diffuse.y == m.diffuse.z);
    let lobes = m
        .specular
        .iter()
        .map(|l| {
            let fresnel = match l.fresnel {
                Fresnel::Constant(c) => {
                    assert!(c.x == c.y && c.y == c.z);
                    f64::from(c.x)
                }
                _ => panic!("{name}: constant Fresnel only"),
            };
            Lobe {
                ggx: match l.distribution {
                    Distribution::DBrdf => false,
                    Distribution::GgxSmith => true,
                    d => panic!("{name}: {d:?} has no reference here"),
                },
                alpha: (f64::from(l.alpha.x), f64::from(l.alpha.y)),
                fresnel,
            }
        })
        .collect();
    let t = m
        .tangent_direction
        .map_or(DVec3::X, |t| t.as_dvec3().normalize());
    assert!((t - DVec3::X).length() < 1e-12, "{name}: tangent +x");
    Brdf {
        diffuse: f64::from(m.diffuse.x),
        lobes,
        t,
        b: DVec3::Z,
        n: DVec3::Y,
    }
}
