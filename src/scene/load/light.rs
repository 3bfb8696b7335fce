//! Lights of a scene file: one geometry key, the common fields, and the checks that tie them to
//! the textures (a dome map's shape per convention).

use super::*;

impl Builder<'_> {
    pub(super) fn light(&self, name: &str, def: &LightDef) -> Result<Light> {
        let ctx = self.ctx;
        let f = format!("lights.{name}");
        let kind = one_of(
            ctx,
            &f,
            &[
                ("rect", def.rect.is_some()),
                ("disk", def.disk.is_some()),
                ("sphere", def.sphere.is_some()),
                ("dome", def.dome.is_some()),
                ("sun", def.sun.is_some()),
            ],
        )?;
        if def.two_sided && matches!(kind, "dome" | "sun") {
            return Err(ctx.err(
                format!("{f}.two_sided"),
                true,
                &format!("a {kind} light cannot be two-sided"),
            ));
        }
        if let (Some(v), true) = (def.shadows, matches!(kind, "dome" | "sun")) {
            return Err(ctx.err(
                format!("{f}.shadows"),
                v,
                &format!("a {kind} light has no surface to cast shadows"),
            ));
        }
        if kind == "sun" && def.texture.is_some() {
            return Err(SceneError::unsupported(
                ctx.file,
                format!("{f}.texture"),
                "a sun light takes no texture",
            ));
        }
        let g = format!("{f}.{kind}");
        let kind = if let Some(r) = &def.rect {
            let (center, u, v) = ctx.rect(&g, r, true)?;
            LightKind::Rect { center, u, v }
        } else if let Some(d) = &def.disk {
            let (center, normal, radius) = ctx.disk(&g, d, true)?;
            LightKind::Disk {
                center,
                normal,
                radius,
            }
        } else if let Some(s) = &def.sphere {
            let (center, radius) = ctx.sphere(&g, s, true)?;
            LightKind::Sphere { center, radius }
        } else if let Some(d) = &def.dome {
            LightKind::Dome {
                rotation_deg: ctx.finite(&format!("{g}.rotation"), d.rotation)?,
                convention: match d.convention {
                    DomeConventionDef::Illum => DomeConvention::Illum,
                    DomeConventionDef::Mitsuba => DomeConvention::Mitsuba,
                    DomeConventionDef::Pbrt => DomeConvention::Pbrt,
                },
            }
        } else {
            let s = def
                .sun
                .as_ref()
                .expect("one_of checked that a geometry is present");
            let field = format!("{g}.angular_diameter");
            if !(0.0..180.0).contains(&s.angular_diameter) {
                return Err(ctx.err(
                    field,
                    fmt_num(s.angular_diameter),
                    "must be in [0, 180) degrees",
                ));
            }
            LightKind::Sun {
                direction: ctx.direction(&format!("{g}.direction"), s.direction)?,
                angular_diameter_deg: s.angular_diameter,
            }
        };
        let light = Light {
            name: name.to_owned(),
            kind,
            color: ctx.nonneg_rgb(&format!("{f}.color"), def.color)?,
            intensity: ctx.nonneg_f32(&format!("{f}.intensity"), def.intensity)?,
            exposure: ctx.f32(&format!("{f}.exposure"), def.exposure)?,
            two_sided: def.two_sided,
            texture: def
                .texture
                .as_deref()
                .map(|t| self.texture_ref(&format!("{f}.texture"), t))
                .transpose()?,
            visible: def.visible,
            shadows: def.shadows.unwrap_or(true),
        };
        if !light.radiance().is_finite() {
            return Err(ctx.err(
                f,
                format!("{}", light.radiance()),
                "color · intensity · 2^exposure overflows 32-bit floats",
            ));
        }
        if let (LightKind::Dome { convention, .. }, Some(t)) = (&light.kind, light.texture) {
            let t = &self.parts.textures[t as usize];
            let size = format!("{}x{}", t.width, t.height);
            match convention {
                DomeConvention::Mitsuba if t.height < 2 => {
                    return Err(ctx.err(
                        format!("{f}.texture"),
                        size,
                        "a Mitsuba-convention dome map needs at least 2 rows (its first and last lie on the poles)",
                    ));
                }
                DomeConvention::Pbrt if t.width != t.height => {
                    return Err(ctx.err(
                        format!("{f}.texture"),
                        size,
                        "a pbrt-convention dome map is an equal-area square: width and height must be equal",
                    ));
                }
                _ => {}
            }
        }
        Ok(light)
    }
}
