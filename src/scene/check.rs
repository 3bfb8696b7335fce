//! Validation helpers shared by the scene file loader: each checks one value and, on failure,
//! returns a `SceneError` naming the file, the field path and the value.

use super::error::{SceneError, fmt_num, fmt_vec};
use super::format::{DiskDef, RectDef, SphereDef, V3};
use glam::{DVec3, Vec3};

type Result<T> = std::result::Result<T, SceneError>;

/// The largest coordinate or size a scene may hold: the device stores geometry in float32
/// relative to the camera, and bounds add a centre to an extent, so both must stay well inside
/// float32's range (3.4e38).
pub const MAX_COORDINATE: f64 = 1e30;
const TOO_LARGE: &str = "must be at most 1e30 in magnitude (geometry is float32 on the device)";

/// Which file is being checked; all helpers take the field path of the value they check.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub file: &'a str,
}

impl Ctx<'_> {
    pub fn err(&self, field: impl Into<String>, value: impl ToString, reason: &str) -> SceneError {
        SceneError::invalid(self.file, field, value.to_string(), reason)
    }

    pub fn finite(&self, field: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(field, fmt_num(v), "must be a finite number"))
        }
    }

    /// A size: positive, or also zero when `zero_ok` (lights may be of zero size: they emit nothing).
    pub fn size(&self, field: &str, v: f64, zero_ok: bool) -> Result<f64> {
        if zero_ok && v == 0.0 {
            return Ok(0.0);
        }
        if v.is_finite() && v > 0.0 && v <= MAX_COORDINATE {
            Ok(v)
        } else if v > MAX_COORDINATE {
            Err(self.err(field, fmt_num(v), TOO_LARGE))
        } else if zero_ok {
            Err(self.err(field, fmt_num(v), "must be a finite number >= 0"))
        } else {
            Err(self.err(field, fmt_num(v), "must be a positive finite number"))
        }
    }

    /// A value the renderer stores as f32: must stay finite after conversion.
    pub fn f32(&self, field: &str, v: f64) -> Result<f32> {
        let x = v as f32;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, fmt_num(v), "must be a finite 32-bit float"))
        }
    }

    pub fn nonneg_f32(&self, field: &str, v: f64) -> Result<f32> {
        let x = self.f32(field, v)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, fmt_num(v), "must be a finite number >= 0"))
        }
    }

    pub fn point(&self, field: &str, v: V3) -> Result<DVec3> {
        let p = DVec3::from_array(v);
        if !p.is_finite() {
            Err(self.err(field, fmt_vec(&v), "must be finite"))
        } else if p.abs().max_element() > MAX_COORDINATE {
            Err(self.err(field, fmt_vec(&v), TOO_LARGE))
        } else {
            Ok(p)
        }
    }

    /// A finite, non-zero vector, returned normalized.
    pub fn direction(&self, field: &str, v: V3) -> Result<DVec3> {
        self.direction_of(|| field.to_string(), v)
    }

    /// [`Ctx::direction`] with the field's name made only for the error (per-vertex data).
    pub fn direction_of(&self, field: impl FnOnce() -> String, v: V3) -> Result<DVec3> {
        let d = DVec3::from_array(v);
        // Divide by the largest component first so that huge or tiny vectors normalize too.
        let m = d.abs().max_element();
        let unit = (d / m).normalize_or_zero();
        if d.is_finite() && m > 0.0 && unit.is_normalized() {
            Ok(unit)
        } else {
            Err(self.err(field(), fmt_vec(&v), "must be a non-zero finite vector"))
        }
    }

    /// A colour/albedo/reflectance with each channel in [0, 1].
    pub fn unit_rgb(&self, field: &str, v: V3) -> Result<Vec3> {
        if v.iter().all(|c| (0.0..=1.0).contains(c)) {
            Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
        } else {
            Err(self.err(field, fmt_vec(&v), "each component must be in [0, 1]"))
        }
    }

    /// Each channel finite (as f32) and >= 0.
    pub fn nonneg_rgb(&self, field: &str, v: V3) -> Result<Vec3> {
        let x = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        if x.is_finite() && x.min_element() >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(
                field,
                fmt_vec(&v),
                "each component must be a finite number >= 0",
            ))
        }
    }

    /// Each channel finite (as f32) and > 0.
    pub fn positive_rgb(&self, field: &str, v: V3) -> Result<Vec3> {
        let x = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        if x.is_finite() && x.min_element() > 0.0 {
            Ok(x)
        } else {
            Err(self.err(
                field,
                fmt_vec(&v),
                "each component must be a finite number > 0",
            ))
        }
    }

    /// `zero_ok`: a radius of 0 is allowed (lights).
    pub fn sphere(&self, field: &str, s: &SphereDef, zero_ok: bool) -> Result<(DVec3, f64)> {
        Ok((
            self.point(&format!("{field}.center"), s.center)?,
            self.size(&format!("{field}.radius"), s.radius, zero_ok)?,
        ))
    }

    /// Returns (center, unit normal, radius).
    pub fn disk(&self, field: &str, d: &DiskDef, zero_ok: bool) -> Result<(DVec3, DVec3, f64)> {
        Ok((
            self.point(&format!("{field}.center"), d.center)?,
            self.direction(&format!("{field}.normal"), d.normal)?,
            self.size(&format!("{field}.radius"), d.radius, zero_ok)?,
        ))
    }

    /// Returns (center, u, v): full edge vectors with normalize(u × v) = normal.
    pub fn rect(&self, field: &str, r: &RectDef, zero_ok: bool) -> Result<(DVec3, DVec3, DVec3)> {
        let center = self.point(&format!("{field}.center"), r.center)?;
        let n = self.direction(&format!("{field}.normal"), r.normal)?;
        let su = self.size(&format!("{field}.size[0]"), r.size[0], zero_ok)?;
        let sv = self.size(&format!("{field}.size[1]"), r.size[1], zero_ok)?;
        let up = match r.up {
            Some(up) => self.direction(&format!("{field}.up"), up)?,
            None if n.y.abs() > 0.999 => DVec3::NEG_Z,
            None => DVec3::Y,
        };
        let v_dir = up - up.dot(n) * n;
        if v_dir.length() < 1e-6 {
            let up = r.up.unwrap_or_default();
            return Err(self.err(
                format!("{field}.up"),
                fmt_vec(&up),
                &format!("must not be parallel to the normal {}", fmt_vec(&r.normal)),
            ));
        }
        let v_dir = v_dir.normalize();
        let u_dir = v_dir.cross(n);
        Ok((center, su * u_dir, sv * v_dir))
    }
}
