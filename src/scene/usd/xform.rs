//! `UsdGeomXformable`: the ops of `xformOpOrder` composed into one local-to-parent matrix, in
//! double precision (illum's far-from-origin exactness stays). illum's matrices act on column
//! vectors; USD's on row vectors, so a USD matrix is read transposed and the first op listed is
//! the outermost.

use super::{Reader, Result, value};
use glam::{DMat4, DQuat, DVec3};
use openusd::sdf::{self, Value};

impl Reader {
    /// The prim's local transform, and whether it resets the parent's (`!resetXformStack!`).
    pub(super) fn local_transform(&mut self, prim: &sdf::Path) -> Result<(DMat4, bool)> {
        let Some(order) = self.attr(prim, "xformOpOrder")? else {
            return Ok((DMat4::IDENTITY, false));
        };
        let order = value::token_array(&order).ok_or_else(|| {
            self.invalid(
                prim,
                "xformOpOrder",
                value::show(&order),
                "expected token[]",
            )
        })?;
        let mut m = DMat4::IDENTITY;
        let mut reset = false;
        for (i, op) in order.iter().enumerate() {
            if op == "!resetXformStack!" {
                if i != 0 {
                    return Err(self.invalid(
                        prim,
                        "xformOpOrder",
                        op,
                        "!resetXformStack! may only come first",
                    ));
                }
                reset = true;
                continue;
            }
            m *= self.op(prim, op)?;
        }
        if !m.is_finite() {
            return Err(self.invalid(
                prim,
                "xformOpOrder",
                format!("{order:?}"),
                "the composed transform is not finite",
            ));
        }
        Ok((m, reset))
    }

    /// One op's matrix (`!invert!` ops inverted).
    fn op(&mut self, prim: &sdf::Path, op: &str) -> Result<DMat4> {
        let (inverted, name) = match op.strip_prefix("!invert!") {
            Some(n) => (true, n),
            None => (false, op),
        };
        let Some(v) = self.attr(prim, name)? else {
            return Err(self.invalid(
                prim,
                "xformOpOrder",
                op,
                "names an op with no value on the prim",
            ));
        };
        let kind = name
            .strip_prefix("xformOp:")
            .and_then(|k| k.split(':').next())
            .unwrap_or("");
        let bad = |what: &str| self.invalid(prim, name, value::show(&v), what);
        let v3 = || value::vec3(&v).ok_or_else(|| bad("expected 3 numbers"));
        let s = || value::scalar(&v).ok_or_else(|| bad("expected a number"));
        let rad = |d: f64| d.to_radians();
        let axis = |c: u8, deg: f64| match c {
            b'X' => DMat4::from_rotation_x(rad(deg)),
            b'Y' => DMat4::from_rotation_y(rad(deg)),
            _ => DMat4::from_rotation_z(rad(deg)),
        };
        let m = match kind {
            "translate" => DMat4::from_translation(DVec3::from(v3()?)),
            "translateX" => DMat4::from_translation(DVec3::new(s()?, 0.0, 0.0)),
            "translateY" => DMat4::from_translation(DVec3::new(0.0, s()?, 0.0)),
            "translateZ" => DMat4::from_translation(DVec3::new(0.0, 0.0, s()?)),
            "scale" => DMat4::from_scale(DVec3::from(v3()?)),
            "scaleX" => DMat4::from_scale(DVec3::new(s()?, 1.0, 1.0)),
            "scaleY" => DMat4::from_scale(DVec3::new(1.0, s()?, 1.0)),
            "scaleZ" => DMat4::from_scale(DVec3::new(1.0, 1.0, s()?)),
            "rotateX" | "rotateY" | "rotateZ" => axis(kind.as_bytes()[6], s()?),
            "rotateXYZ" | "rotateXZY" | "rotateYXZ" | "rotateYZX" | "rotateZXY" | "rotateZYX" => {
                let a = v3()?;
                let order = &kind.as_bytes()[6..];
                // The first axis named turns first (innermost).
                let angle = |c: u8| a[usize::from(c - b'X')];
                axis(order[2], angle(order[2]))
                    * axis(order[1], angle(order[1]))
                    * axis(order[0], angle(order[0]))
            }
            "orient" => {
                let q = match &v {
                    Value::Quatd(q) => [q.x, q.y, q.z, q.w],
                    Value::Quatf(q) => [q.x, q.y, q.z, q.w].map(f64::from),
                    Value::Quath(q) => [q.x, q.y, q.z, q.w].map(|c| f64::from(c.to_f32())),
                    _ => return Err(bad("expected a quaternion")),
                };
                let q = DQuat::from_array(q);
                if !(q.is_finite() && q.length() > 0.0) {
                    return Err(bad("must be a finite, non-zero quaternion"));
                }
                DMat4::from_quat(q.normalize())
            }
            "transform" => match &v {
                // Row-major for row vectors = column-major for column vectors.
                // Row vectors: the last column must be (0, 0, 0, 1).
                Value::Matrix4d(m)
                    if [m.0[3], m.0[7], m.0[11], m.0[15]] == [0.0, 0.0, 0.0, 1.0] =>
                {
                    DMat4::from_cols_array(&m.0)
                }
                Value::Matrix4d(_) => {
                    return Err(bad(
                        "must be affine (its last column (0, 0, 0, 1)): illum has no projective transforms",
                    ));
                }
                _ => return Err(bad("expected a matrix4d")),
            },
            _ => {
                return Err(self.unsupported(
                    prim,
                    name,
                    format!("unknown xformOp kind {kind:?} in xformOpOrder"),
                ));
            }
        };
        if !m.is_finite() {
            return Err(bad("must be finite"));
        }
        if !inverted {
            return Ok(m);
        }
        if m.determinant().abs() < 1e-300 {
            return Err(bad("is singular, so !invert! cannot invert it"));
        }
        Ok(m.inverse())
    }
}

/// A matrix as the scene format's `matrix` (row-major, column vectors).
pub(super) fn row_major(m: DMat4) -> [f64; 16] {
    m.transpose().to_cols_array()
}
