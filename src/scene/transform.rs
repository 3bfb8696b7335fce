//! Object-to-world transforms of mesh and glTF shapes.

use super::check::Ctx;
use super::error::{SceneError, fmt_vec};
use super::format::{NumOrArray, TransformDef};
use glam::{DMat3, DMat4, DVec3, DVec4};

type Result<T> = std::result::Result<T, SceneError>;

/// M = T · Rz · Ry · Rx · S, or the given row-major matrix.
pub(crate) fn parse(ctx: Ctx, field: &str, t: &TransformDef) -> Result<DMat4> {
    let m = if let Some(rows) = &t.matrix {
        if t.translate.is_some() || t.rotate.is_some() || t.scale.is_some() {
            return Err(SceneError::unsupported(
                ctx.file,
                format!("{field}.matrix"),
                "give either \"matrix\" or \"translate\"/\"rotate\"/\"scale\", not both",
            ));
        }
        if !rows.iter().all(|x| x.is_finite()) {
            return Err(ctx.err(format!("{field}.matrix"), fmt_vec(rows), "must be finite"));
        }
        let m = DMat4::from_cols_array(rows).transpose();
        if m.row(3) != DVec4::W {
            return Err(ctx.err(
                format!("{field}.matrix"),
                fmt_vec(rows),
                "must be affine: last row [0, 0, 0, 1]",
            ));
        }
        m
    } else {
        let translate = match t.translate {
            Some(v) => ctx.point(&format!("{field}.translate"), v)?,
            None => DVec3::ZERO,
        };
        let rotate = match t.rotate {
            Some(v) => ctx.point(&format!("{field}.rotate"), v)?,
            None => DVec3::ZERO,
        };
        let scale = match t.scale {
            None => DVec3::ONE,
            Some(NumOrArray::One(s)) => DVec3::splat(ctx.finite(&format!("{field}.scale"), s)?),
            Some(NumOrArray::Many(s)) => ctx.point(&format!("{field}.scale"), s)?,
        };
        let r = rotate * (std::f64::consts::PI / 180.0);
        DMat4::from_translation(translate)
            * DMat4::from_rotation_z(r.z)
            * DMat4::from_rotation_y(r.y)
            * DMat4::from_rotation_x(r.x)
            * DMat4::from_scale(scale)
    };
    check_invertible(ctx, field, &m)?;
    Ok(m)
}

/// Rejects transforms the renderer cannot invert (zero scale, collapsed axes) or that
/// overflow.
pub(crate) fn check_invertible(ctx: Ctx, field: &str, m: &DMat4) -> Result<()> {
    if !m.is_finite() {
        return Err(ctx.err(field, "a non-finite matrix", "must be finite"));
    }
    let a = DMat3::from_mat4(*m);
    let det = a.determinant();
    // Relative to the size of the matrix, so that tiny-but-valid scales still pass.
    let size = a
        .x_axis
        .length()
        .max(a.y_axis.length())
        .max(a.z_axis.length());
    let well_conditioned = det.abs() > 1e-12 * size * size * size; // false for NaN too
    if !well_conditioned || !m.inverse().is_finite() {
        return Err(ctx.err(
            field,
            format!("determinant {det}"),
            "must be invertible (no zero scale or collapsed axes)",
        ));
    }
    Ok(())
}
