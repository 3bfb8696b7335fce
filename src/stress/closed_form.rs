//! Closed-form reference images, in float64 on the host, for scenes whose answer is known: one
//! plane of receivers (rects and mesh triangles, all coplanar, Lambert plus optional mirror-like
//! lobes) lit, without occlusion, by lights on its front side. Each pixel averages S×S stratified
//! positions of the box pixel filter that `primary.comp` integrates.
//!
//! Irradiance formulas (docs/techniques.md, "Analytic unshadowed irradiance"): sphere and sun cone
//! by Snyder's formula with the horizon crossing; rects and emissive triangles by the Lambert
//! polygon formula clipped at the horizon; a delta sun as E⊥ max(0, n·s); a constant dome as π L; a
//! textured dome by Gauss-Legendre quadrature over the cells of its bilinear interpolant. These are
//! independent of the GLSL (which samples; it never evaluates these integrals for the image).
//!
//! Anything outside that class is an error that names what is unsupported, so a closed form is
//! never silently wrong.

use crate::scene::{
    Distribution, DomeConvention, Fresnel, Light, LightKind, Scene, ShapeGeometry, SpecularLobe,
    Texture, dome_map,
};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// Positions per pixel along each axis.
const SUBPIXELS: u32 = 8;
/// Below this alpha along both axes the closed form takes a lobe for a mirror of albedo F (the
/// renderer samples it as a lobe down to 1e-4): at most this, its directional albedo under a
/// constant dome differs from F by < 2e-5 for
/// n·v >= 0.2 (GGX Smith: Λ ≈ α² tan²θ / 4); the D-BRDF has no shadowing term, its albedo is F
/// while the reflected lobe stays above the horizon (exp(-cot²θ / α²) ≈ 0).
const MIRROR_ALPHA: f32 = 1e-3;

struct Receiver {
    /// Polygon corners (world space, counter-clockwise seen from the front).
    corners: Vec<DVec3>,
    diffuse: DVec3,
    /// Constant Fresnel of mirror-like lobes (summed).
    mirror: DVec3,
}

struct Plane {
    n: DVec3,
    d: f64,
}

/// The image of `scene` at its camera's resolution, row-major RGB.
pub fn image(scene: &Scene) -> Result<Vec<[f32; 3]>, String> {
    let setup = Setup::new(scene)?;
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let forward = (cam.look_at - cam.position).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let tan_half = (cam.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = f64::from(w) / f64::from(h);
    let (right, up) = (right * tan_half * aspect, up * tan_half);
    let mut out = Vec::with_capacity((w * h) as usize);
    let s = f64::from(SUBPIXELS);
    for y in 0..h {
        for x in 0..w {
            let mut acc = DVec3::ZERO;
            for j in 0..SUBPIXELS {
                for i in 0..SUBPIXELS {
                    let u = (f64::from(x) + (f64::from(i) + 0.5) / s) / f64::from(w);
                    let v = (f64::from(y) + (f64::from(j) + 0.5) / s) / f64::from(h);
                    let (nx, ny) = (2.0 * u - 1.0, 2.0 * v - 1.0);
                    let d = (forward + nx * right - ny * up).normalize();
                    acc += setup.radiance(cam.position, d)?;
                }
            }
            let p = acc / (s * s);
            out.push([p.x as f32, p.y as f32, p.z as f32]);
        }
    }
    Ok(out)
}

struct Setup<'a> {
    /// The scene's lights that emit something (the renderer leaves the others out).
    lights: Vec<&'a Light>,
    receivers: Vec<Receiver>,
    plane: Plane,
    /// Emissive triangles (world corners, radiance, two-sided).
    emitters: Vec<([DVec3; 3], DVec3, bool)>,
    /// Constant radiance of an untextured dome, or the textured dome's irradiance on the plane.
    dome_constant: Option<DVec3>,
    dome_irradiance: DVec3,
    dome_visible: bool,
}

fn v3(v: glam::Vec3) -> DVec3 {
    v.as_dvec3()
}

impl<'a> Setup<'a> {
    fn new(scene: &'a Scene) -> Result<Setup<'a>, String> {
        let mut receivers = Vec::new();
        let mut emitters = Vec::new();
        let material = |m: u32, what: &str| -> Result<Option<(DVec3, DVec3)>, String> {
            let m = &scene.materials[m as usize];
            if m.emission.max_element() > 0.0 {
                return Ok(None);
            }
            if m.diffuse_texture.is_some() || m.metallic_roughness.is_some() {
                return Err(format!("{what}: textured or glTF material"));
            }
            let mut mirror = DVec3::ZERO;
            for l in &m.specular {
                mirror += mirror_lobe(l).ok_or_else(|| {
                    format!(
                        "{what}: a specular lobe other than a mirror-like one with constant Fresnel"
                    )
                })?;
            }
            Ok(Some((v3(m.diffuse), mirror)))
        };
        for s in &scene.shapes {
            let ShapeGeometry::Rect { center, u, v } = s.geometry else {
                return Err(format!("shape {}: only rects and meshes", s.name));
            };
            let Some((diffuse, mirror)) = material(s.material, &s.name)? else {
                return Err(format!("shape {}: emissive shapes", s.name));
            };
            let c = center - 0.5 * u - 0.5 * v;
            receivers.push(Receiver {
                corners: vec![c, c + u, c + u + v, c + v],
                diffuse,
                mirror,
            });
        }
        for inst in &scene.instances {
            let mesh = &scene.meshes[inst.mesh as usize];
            let p = |i: u32| {
                inst.transform
                    .transform_point3(mesh.positions[i as usize].as_dvec3())
            };
            let mat = material(mesh.material, &inst.name)?;
            for t in mesh.indices.chunks_exact(3) {
                let tri = [p(t[0]), p(t[1]), p(t[2])];
                match mat {
                    Some((diffuse, mirror)) => receivers.push(Receiver {
                        corners: tri.to_vec(),
                        diffuse,
                        mirror,
                    }),
                    None => {
                        let m = &scene.materials[mesh.material as usize];
                        if m.emission_texture.is_some() {
                            return Err(format!("{}: emission texture", inst.name));
                        }
                        emitters.push((tri, v3(m.emission), m.two_sided));
                    }
                }
            }
        }
        // One plane: the normal of the largest receiver polygon.
        let area = |c: &[DVec3]| polygon_normal(c).length();
        let big = receivers
            .iter()
            .max_by(|a, b| area(&a.corners).total_cmp(&area(&b.corners)))
            .ok_or("no receiver (rect or mesh) in the scene")?;
        let n = polygon_normal(&big.corners).normalize();
        let plane = Plane {
            n,
            d: n.dot(big.corners[0]),
        };
        let scale = receivers
            .iter()
            .flat_map(|r| r.corners.iter())
            .fold(1.0f64, |m, p| m.max(p.abs().max_element()));
        for r in &receivers {
            for p in &r.corners {
                if (n.dot(*p) - plane.d).abs() > 1e-9 * scale {
                    return Err("receivers are not coplanar (occlusion would matter)".into());
                }
            }
        }
        let (mut dome_constant, mut dome_irradiance, mut dome_visible) = (None, DVec3::ZERO, false);
        let mut others = 0;
        // The lights the renderer uploads: those that emit something.
        let lights: Vec<&Light> = scene.lights.iter().filter(|l| !l.emits_nothing()).collect();
        for l in &lights {
            if l.texture.is_some() && !matches!(l.kind, LightKind::Dome { .. }) {
                return Err(format!("light {}: textured area lights", l.name));
            }
            match &l.kind {
                LightKind::Dome {
                    rotation_deg,
                    convention,
                } => {
                    dome_visible = l.visible;
                    match l.texture {
                        None => dome_constant = Some(v3(l.radiance())),
                        Some(t) => {
                            dome_irradiance = v3(l.radiance())
                                * dome_irradiance_quadrature(
                                    &scene.textures[t as usize],
                                    *rotation_deg,
                                    *convention,
                                    n,
                                );
                        }
                    }
                }
                _ => others += 1,
            }
            if matches!(l.kind, LightKind::Rect { .. } | LightKind::Sphere { .. }) && l.visible {
                return Err(format!("light {}: visible area lights", l.name));
            }
            if l.shadows
                && lights.len() > 1
                && !matches!(l.kind, LightKind::Dome { .. } | LightKind::Sun { .. })
            {
                return Err(format!(
                    "light {}: an area light that casts shadows on the scene's other lights",
                    l.name
                ));
            }
        }
        let has_mirror = receivers.iter().any(|r| r.mirror != DVec3::ZERO);
        if has_mirror && (others > 0 || !emitters.is_empty() || dome_constant.is_none()) {
            return Err("mirror-like lobes are supported under a constant dome only".into());
        }
        if !emitters.is_empty() && !lights.is_empty() {
            return Err(
                "emissive geometry must be the only light (it could occlude others)".into(),
            );
        }
        Ok(Setup {
            lights,
            receivers,
            plane,
            emitters,
            dome_constant,
            dome_irradiance,
            dome_visible,
        })
    }

    fn radiance(&self, o: DVec3, d: DVec3) -> Result<DVec3, String> {
        let n = self.plane.n;
        let dn = d.dot(n);
        let t = (self.plane.d - n.dot(o)) / dn;
        let background = || {
            if !self.dome_visible {
                return DVec3::ZERO;
            }
            self.dome_constant.unwrap_or(DVec3::ZERO)
        };
        if !(t > 0.0 && t.is_finite()) {
            return self.miss(o, d, background());
        }
        let x = o + t * d;
        let Some(r) = self.receivers.iter().find(|r| inside(&r.corners, n, x)) else {
            return self.miss(o, d, background());
        };
        if dn >= 0.0 {
            return Err("the camera sees the back of the receiver plane".into());
        }
        for (tri, _, _) in &self.emitters {
            if ray_triangle(o, d, tri).is_some_and(|te| te < t) {
                return Err("the camera sees emissive geometry".into());
            }
        }
        let e = self.irradiance(x, n)?;
        let mut l = r.diffuse * e / PI;
        if r.mirror != DVec3::ZERO {
            l += r.mirror * self.dome_constant.unwrap_or(DVec3::ZERO);
        }
        Ok(l)
    }

    fn miss(&self, o: DVec3, d: DVec3, background: DVec3) -> Result<DVec3, String> {
        for (tri, _, _) in &self.emitters {
            if ray_triangle(o, d, tri).is_some() {
                return Err("the camera sees emissive geometry".into());
            }
        }
        if self.dome_visible && self.dome_constant.is_none() && self.dome_irradiance != DVec3::ZERO
        {
            return Err("the camera sees a textured dome".into());
        }
        Ok(background)
    }

    /// Irradiance at x on the receiver plane (normal n), unoccluded.
    fn irradiance(&self, x: DVec3, n: DVec3) -> Result<DVec3, String> {
        let mut e = self.dome_irradiance;
        if let Some(l) = self.dome_constant {
            e += PI * l;
        }
        for l in &self.lights {
            let radiance = v3(l.radiance());
            e += match &l.kind {
                LightKind::Sphere { center, radius } => {
                    let q = *center - x;
                    let d2 = q.length_squared();
                    if d2 <= radius * radius {
                        return Err(format!("light {}: receiver inside the sphere", l.name));
                    }
                    radiance * sphere_irradiance(n.dot(q) / d2.sqrt(), radius * radius / d2)
                }
                LightKind::Sun {
                    direction,
                    angular_diameter_deg,
                } => {
                    let s = direction.normalize();
                    let half = (angular_diameter_deg * 0.5).to_radians();
                    if half == 0.0 {
                        radiance * n.dot(s).max(0.0)
                    } else {
                        // L = E⊥ / (π sin²θs) (docs/scene-format.md).
                        let s2 = half.sin().powi(2);
                        radiance / (PI * s2) * sphere_irradiance(n.dot(s), s2)
                    }
                }
                LightKind::Rect { center, u, v } => {
                    let c = *center - 0.5 * *u - 0.5 * *v;
                    let corners = [c, c + *u, c + *u + *v, c + *v];
                    radiance * emitter_irradiance(&corners, x, n, l.two_sided)
                }
                LightKind::Disk {
                    center,
                    normal,
                    radius,
                } => {
                    let e =
                        disk_irradiance(*center - x, normal.normalize(), *radius, n, l.two_sided)
                            .map_err(|e| format!("light {}: {e}", l.name))?;
                    radiance * e
                }
                // The dome's part is above.
                LightKind::Dome { .. } => DVec3::ZERO,
            };
        }
        for (tri, radiance, two_sided) in &self.emitters {
            e += *radiance * emitter_irradiance(tri, x, n, *two_sided);
        }
        Ok(e)
    }
}

/// Constant Fresnel of a mirror-like lobe, or None.
fn mirror_lobe(l: &SpecularLobe) -> Option<DVec3> {
    let Fresnel::Constant(f) = l.fresnel else {
        return None;
    };
    let ok = l.alpha.max_element() <= MIRROR_ALPHA
        && matches!(l.distribution, Distribution::DBrdf | Distribution::GgxSmith);
    ok.then(|| v3(f))
}

/// Unnormalized polygon normal (Newell): its length is twice the area.
fn polygon_normal(c: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for i in 0..c.len() {
        n += c[i].cross(c[(i + 1) % c.len()]);
    }
    n
}

/// Whether x (on the plane of the convex polygon) lies inside it.
fn inside(c: &[DVec3], n: DVec3, x: DVec3) -> bool {
    let pn = polygon_normal(c);
    if pn.length_squared() == 0.0 {
        return false;
    }
    let s = pn.dot(n).signum();
    (0..c.len()).all(|i| {
        let (a, b) = (c[i], c[(i + 1) % c.len()]);
        s * (b - a).cross(x - a).dot(n) >= 0.0
    })
}

fn ray_triangle(o: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - t[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let tt = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0).then_some(tt)
}

/// E / L of a uniform spherical cap whose axis makes cosθ = `ct` with the normal and whose angular
/// radius σ has sin²σ = `s2`, the horizon crossing included (Snyder 1996; docs/techniques.md,
/// "Analytic unshadowed irradiance").
pub fn sphere_irradiance(ct: f64, s2: f64) -> f64 {
    if ct * ct >= s2 {
        return PI * s2 * ct.max(0.0);
    }
    let st = (1.0 - ct * ct).sqrt().max(1e-300);
    let x = (1.0 / s2 - 1.0).max(0.0).sqrt();
    let y = (-x * ct / st).clamp(-1.0, 1.0);
    let z = st * (1.0 - y * y).sqrt();
    ((ct * y.acos() - x * z) * s2 + z.atan2(x)).max(0.0)
}

/// E / L at a point with normal n of a uniform planar polygon (vertices relative to the point,
/// either winding), clipped at n's horizon: Lambert's formula with atan2 edge angles
/// (docs/techniques.md, "Analytic unshadowed irradiance"). Which side emits is the caller's
/// business.
pub fn polygon_irradiance(n: DVec3, verts: &[DVec3]) -> f64 {
    let mut clipped = Vec::with_capacity(verts.len() + 1);
    for i in 0..verts.len() {
        let (a, b) = (verts[i], verts[(i + 1) % verts.len()]);
        let (da, db) = (a.dot(n), b.dot(n));
        if da >= 0.0 {
            clipped.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            clipped.push(a + (da / (da - db)) * (b - a));
        }
    }
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut e = 0.0;
    for i in 0..clipped.len() {
        let (a, b) = (
            clipped[i].normalize(),
            clipped[(i + 1) % clipped.len()].normalize(),
        );
        let c = a.cross(b);
        let len = c.length();
        if len > 1e-300 {
            e += len.atan2(a.dot(b)) * n.dot(c) / len;
        }
    }
    0.5 * e.abs()
}

/// E / L at x (normal n) of a uniform polygon in world space that emits toward its normal
/// (counter-clockwise winding) only, unless `two_sided`; zero-area polygons emit nothing.
fn emitter_irradiance(corners: &[DVec3], x: DVec3, n: DVec3, two_sided: bool) -> f64 {
    let pn = polygon_normal(corners);
    if pn.length_squared() == 0.0 || (!two_sided && pn.dot(x - corners[0]) <= 0.0) {
        return 0.0;
    }
    let rel: Vec<DVec3> = corners.iter().map(|c| *c - x).collect();
    polygon_irradiance(n, &rel)
}

/// E / L at a point with normal n of a uniform disk (centre c relative to the point, unit normal
/// nd, radius r): the closed-form vector irradiance (docs/techniques.md,
/// "Analytic unshadowed irradiance"), valid while the whole disk
/// is above n's horizon (an error otherwise: no closed form). One-sided disks emit toward nd.
pub fn disk_irradiance(
    c: DVec3,
    nd: DVec3,
    r: f64,
    n: DVec3,
    two_sided: bool,
) -> Result<f64, String> {
    // The point's height above the disk's plane, on the emitting side.
    let h = -c.dot(nd);
    if h == 0.0 || (h < 0.0 && !two_sided) {
        return Ok(0.0);
    }
    let tangential = n - n.dot(nd) * nd;
    if n.dot(c) - r * tangential.length() <= 0.0 {
        return Err("the disk crosses the receiver's horizon (no closed form)".into());
    }
    let (h, axial) = if h > 0.0 { (h, -nd) } else { (-h, nd) };
    // Radial offset of the point from the axis, and the unit vector toward the axis.
    let off = -c - (-c).dot(nd) * nd;
    let a = off.length();
    let s = h * h + a * a + r * r;
    let q = (s * s - 4.0 * a * a * r * r).max(0.0).sqrt();
    let ez = 0.5 * PI * (1.0 - (h * h + a * a - r * r) / q);
    let mut e = ez * n.dot(axial);
    if a > 0.0 {
        let er = 0.5 * PI * (h / a) * (s / q - 1.0);
        e += er * n.dot(-off / a);
    }
    Ok(e.max(0.0))
}

/// ∫ T(ω) max(0, n·ω) dω of a dome map T as the renderer reads it under `convention`
/// (src/scene/dome_map.rs), by 6-point Gauss-Legendre in map coordinates on a 4 x 4 split of every
/// sampling cell (src/gpu_scene/dome.rs): the splits fall on the texel centres, where a bilinear
/// lookup has its kinks. Returns RGB.
pub fn dome_irradiance_quadrature(
    t: &Texture,
    rotation_deg: f64,
    convention: DomeConvention,
    n: DVec3,
) -> DVec3 {
    const X: [f64; 6] = [
        -0.932_469_514_203_152,
        -0.661_209_386_466_264_5,
        -0.238_619_186_083_196_9,
        0.238_619_186_083_196_9,
        0.661_209_386_466_264_5,
        0.932_469_514_203_152,
    ];
    const W: [f64; 6] = [
        0.171_324_492_379_170_3,
        0.360_761_573_048_138_6,
        0.467_913_934_572_691,
        0.467_913_934_572_691,
        0.360_761_573_048_138_6,
        0.171_324_492_379_170_3,
    ];
    const SPLIT: u32 = 4;
    let (cw, ch) = crate::gpu_scene::dome::cells(convention, t.width, t.height);
    let offset = if convention == DomeConvention::Mitsuba {
        0.5 / f64::from(t.width)
    } else {
        0.0
    };
    let (du, dv) = (1.0 / f64::from(cw * SPLIT), 1.0 / f64::from(ch * SPLIT));
    let mut e = DVec3::ZERO;
    for j in 0..ch * SPLIT {
        for i in 0..cw * SPLIT {
            let (u0, v0) = (offset + f64::from(i) * du, f64::from(j) * dv);
            for (xa, wa) in X.iter().zip(W) {
                for (xb, wb) in X.iter().zip(W) {
                    let u = u0 + du * 0.5 * (xa + 1.0);
                    let uv = DVec2::new(u.rem_euclid(1.0), v0 + dv * 0.5 * (xb + 1.0));
                    let (dir, jacobian) = dome_map::direction(convention, rotation_deg, uv);
                    let cos = n.dot(dir);
                    if cos <= 0.0 {
                        continue;
                    }
                    let value = dome_map::lookup(t, convention, uv).truncate();
                    e += value * cos * jacobian * 0.25 * du * dv * wa * wb;
                }
            }
        }
    }
    e
}

#[cfg(test)]
#[path = "closed_form_tests.rs"]
mod tests;
