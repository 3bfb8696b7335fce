//! Materials of a scene file: Lambert plus lobes, or the metallic-roughness model, whose
//! scalar maps are packed into one texture the way glTF packs them (roughness in G, metallic in
//! B), so that the shader reads one texture whatever channels the file names.

use super::*;
use crate::scene::format::{ChannelDef, ChannelName, MetallicRoughnessDef};

impl Builder<'_> {
    pub(super) fn material(&mut self, name: &str, def: &MaterialDef) -> Result<Material> {
        let ctx = self.ctx;
        let f = format!("materials.{name}");
        if def.specular.len() > 2 {
            return Err(ctx.err(
                format!("{f}.specular"),
                format!("{} lobes", def.specular.len()),
                "at most 2 specular lobes are allowed",
            ));
        }
        if let Some(mr) = &def.metallic_roughness {
            return self.metallic_roughness(name, def, mr);
        }
        let specular = def
            .specular
            .iter()
            .enumerate()
            .map(|(i, lobe)| self.lobe(&format!("{f}.specular[{i}]"), lobe))
            .collect::<Result<Vec<_>>>()?;
        let opt_tex = |key: &str, t: &Option<String>| {
            t.as_deref()
                .map(|t| self.texture_ref(&format!("{f}.{key}"), t))
                .transpose()
        };
        Ok(Material {
            name: name.to_owned(),
            diffuse: ctx.unit_rgb(&format!("{f}.diffuse"), def.diffuse)?,
            diffuse_texture: opt_tex("diffuse_texture", &def.diffuse_texture)?,
            specular,
            metallic_roughness_texture: None,
            metallic_roughness: None,
            emission: ctx.nonneg_rgb(&format!("{f}.emission"), def.emission)?,
            emission_texture: opt_tex("emission_texture", &def.emission_texture)?,
            two_sided: def.two_sided,
            tangent_direction: def
                .tangent
                .map(|t| {
                    ctx.direction(&format!("{f}.tangent"), t)
                        .map(|d| d.as_vec3())
                })
                .transpose()?,
        })
    }

    fn lobe(&self, f: &str, lobe: &LobeDef) -> Result<SpecularLobe> {
        let ctx = self.ctx;
        let alpha = |field: String, a: f64| {
            if (0.0..=1.0).contains(&a) {
                Ok(a as f32)
            } else {
                Err(ctx.err(
                    field,
                    fmt_num(a),
                    "roughness must be in [0, 1] (0: a perfect mirror)",
                ))
            }
        };
        let alpha = match lobe.roughness {
            NumOrArray::One(a) => Vec2::splat(alpha(format!("{f}.roughness"), a)?),
            NumOrArray::Many([t, b]) => Vec2::new(
                alpha(format!("{f}.roughness[0]"), t)?,
                alpha(format!("{f}.roughness[1]"), b)?,
            ),
        };
        let fresnel = match &lobe.fresnel {
            FresnelDef::Constant(c) => {
                Fresnel::Constant(ctx.unit_rgb(&format!("{f}.fresnel.constant"), *c)?)
            }
            FresnelDef::Schlick(f0) => Fresnel::Schlick {
                f0: ctx.unit_rgb(&format!("{f}.fresnel.schlick"), *f0)?,
            },
            FresnelDef::Conductor { eta, k } => Fresnel::Conductor {
                eta: ctx.positive_rgb(&format!("{f}.fresnel.conductor.eta"), *eta)?,
                k: ctx.nonneg_rgb(&format!("{f}.fresnel.conductor.k"), *k)?,
            },
        };
        let distribution = match lobe.model {
            ModelDef::Dbrdf => Distribution::DBrdf,
            ModelDef::Beckmann => Distribution::BeckmannSmith,
            ModelDef::Ggx => Distribution::GgxSmith,
        };
        Ok(SpecularLobe {
            distribution,
            alpha,
            fresnel,
        })
    }

    fn metallic_roughness(
        &mut self,
        name: &str,
        def: &MaterialDef,
        mr: &MetallicRoughnessDef,
    ) -> Result<Material> {
        let ctx = self.ctx;
        let f = format!("materials.{name}");
        if !def.specular.is_empty() {
            return Err(ctx.err(
                format!("{f}.specular"),
                format!("{} lobes", def.specular.len()),
                "a metallic_roughness material derives its one lobe: leave specular out",
            ));
        }
        if let Some(t) = def.tangent {
            return Err(ctx.err(
                format!("{f}.tangent"),
                fmt_vec(&t),
                "a metallic_roughness lobe is isotropic: it takes no tangent",
            ));
        }
        let fm = format!("{f}.metallic_roughness");
        let unit = |field: &str, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(v as f32)
            } else {
                Err(ctx.err(format!("{fm}.{field}"), fmt_num(v), "must be in [0, 1]"))
            }
        };
        let metallic = unit("metallic", mr.metallic)?;
        let roughness = unit("roughness", mr.roughness)?;
        if !(mr.ior.is_finite() && mr.ior >= 1.0) {
            return Err(ctx.err(
                format!("{fm}.ior"),
                fmt_num(mr.ior),
                "must be a finite number >= 1",
            ));
        }
        let dielectric_f0 = ((mr.ior - 1.0) / (mr.ior + 1.0)).powi(2) as f32;
        let base = ctx.unit_rgb(&format!("{f}.diffuse"), def.diffuse)?;
        let diffuse_texture = def
            .diffuse_texture
            .as_deref()
            .map(|t| self.texture_ref(&format!("{f}.diffuse_texture"), t))
            .transpose()?;
        let metallic_roughness_texture = self.packed_texture(name, &fm, mr)?;
        let factors = MetallicRoughness {
            base_color: base,
            metallic,
            roughness,
            dielectric_f0,
        };
        Ok(Material {
            name: name.to_owned(),
            diffuse: factors.diffuse(),
            diffuse_texture,
            specular: vec![factors.lobe()],
            metallic_roughness_texture,
            metallic_roughness: Some(factors),
            emission: ctx.nonneg_rgb(&format!("{f}.emission"), def.emission)?,
            emission_texture: def
                .emission_texture
                .as_deref()
                .map(|t| self.texture_ref(&format!("{f}.emission_texture"), t))
                .transpose()?,
            two_sided: def.two_sided,
            tangent_direction: None,
        })
    }

    /// The texture whose G multiplies roughness and B metallic: the file's own where it names
    /// one texture's G and B, else one packed from the channels it names (1 where it names none).
    fn packed_texture(
        &mut self,
        name: &str,
        fm: &str,
        mr: &MetallicRoughnessDef,
    ) -> Result<Option<TextureId>> {
        let channel = |c: &ChannelDef, default: ChannelName| match c.channel.unwrap_or(default) {
            ChannelName::R => 0,
            ChannelName::G => 1,
            ChannelName::B => 2,
            ChannelName::A => 3,
        };
        let mut sources = Vec::new();
        for (field, def, default) in [
            ("roughness_texture", &mr.roughness_texture, ChannelName::G),
            ("metallic_texture", &mr.metallic_texture, ChannelName::B),
        ] {
            let Some(c) = def else {
                sources.push(None);
                continue;
            };
            let field = format!("{fm}.{field}");
            let id = self.texture_ref(&format!("{field}.texture"), &c.texture)?;
            sources.push(Some((field, id, channel(c, default))));
        }
        let (rough, metal) = (&sources[0], &sources[1]);
        match (rough, metal) {
            (None, None) => return Ok(None),
            (Some((_, r, 1)), Some((_, m, 2))) if r == m => return Ok(Some(*r)),
            _ => {}
        }
        // One size, filter and wrap for both sources (texel i of one is texel i of the other).
        let present: Vec<_> = sources.iter().flatten().collect();
        let first = &self.parts.textures[present[0].1 as usize];
        let (w, h, filter, wrap) = (first.width, first.height, first.filter, first.wrap);
        for (field, id, _) in &present[1..] {
            let t = &self.parts.textures[*id as usize];
            if (t.width, t.height) != (w, h) || t.filter != filter || t.wrap != wrap {
                return Err(self.ctx.err(
                    format!("{field}.texture"),
                    quoted(&t.name),
                    &format!(
                        "{}x{} ({:?}, {:?}), the roughness texture {}x{} ({filter:?}, {wrap:?}): \
                         the two maps must have one size, filter and wrap",
                        t.width, t.height, t.filter, t.wrap, w, h
                    ),
                ));
            }
        }
        let mut texels = vec![glam::Vec4::ONE; (w * h) as usize];
        for (slot, source) in [(1, rough), (2, metal)] {
            if let Some((_, id, c)) = source {
                let src = &self.parts.textures[*id as usize].texels;
                for (t, s) in texels.iter_mut().zip(src) {
                    t[slot] = s[*c];
                }
            }
        }
        let id = self.parts.textures.len() as TextureId;
        self.parts.textures.push(Texture {
            name: format!("{name}/metallic_roughness"),
            width: w,
            height: h,
            texels,
            filter,
            wrap,
        });
        Ok(Some(id))
    }
}
