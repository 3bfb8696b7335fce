//! UsdShade materials: the material bound to a gprim (`material:binding` for the full purpose,
//! `bindMaterialAs` strength and collection bindings as openusd resolves them), its surface
//! followed through node graphs to a `UsdPreviewSurface`, mapped as illum maps glTF's
//! metallic-roughness materials: diffuse = diffuseColor·(1−metallic) and one GGX-Smith lobe of
//! alpha roughness² whose Schlick f0 mixes the dielectric's ((ior−1)/(ior+1))² toward
//! diffuseColor by metallic (the specular workflow: f0 = specularColor, diffuse = diffuseColor).

use super::{Reader, Result, value};
use crate::scene::format::{
    ChannelDef, FresnelDef, LobeDef, MaterialDef, MetallicRoughnessDef, ModelDef, NumOrArray,
};
use openusd::schemas::shade::MaterialBindingAPI;
use openusd::sdf::{self, Value};

/// UsdPreviewSurface's diffuseColor fallback, also the colour of unbound gprims without a
/// displayColor.
const FALLBACK_GREY: [f64; 3] = [0.18; 3];

/// Connections followed before a network is called cyclic.
const MAX_HOPS: usize = 32;

/// Where a shading input's value comes from, once connections through node graphs and
/// material interface inputs are followed.
pub(super) enum Source {
    Unset,
    Value(Value),
    /// An output of a Shader prim: (prim, output name).
    Shader(sdf::Path, String),
}

impl Reader {
    /// The name of the illum material for `gprim` (made on first use). `double_sided` makes an
    /// emissive material emit from both faces (`doubleSided`).
    pub(super) fn material(&mut self, gprim: &sdf::Path, double_sided: bool) -> Result<String> {
        let bound = self.bound_material(gprim)?;
        // Unbound: the display colour, read once (it may warn).
        let color = match &bound {
            Some(_) => None,
            None => Some(self.display_color(gprim)?),
        };
        let key = match (&bound, color) {
            (Some(m), _) => m.as_str().to_string(),
            (None, c) => format!("displayColor {:?}", c.unwrap_or(FALLBACK_GREY)),
        };
        let full_key = format!("{key}{}", if double_sided { " (double-sided)" } else { "" });
        if let Some(name) = self.materials.get(&full_key) {
            return Ok(name.clone());
        }
        self.texcoords = None;
        let mut def = match &bound {
            Some(m) => self.preview_surface(m)?,
            None => lambert(color.unwrap_or(FALLBACK_GREY)),
        };
        let texcoords = self.texcoords.take();
        def.two_sided = double_sided && def.emission.iter().any(|&e| e > 0.0);
        let name = if def.two_sided || !double_sided {
            full_key.clone()
        } else {
            key
        };
        if !self.out.materials.0.contains_key(&name) {
            self.out.materials.0.insert(name.clone(), def);
        }
        if let Some(t) = texcoords {
            self.texcoord_of.insert(name.clone(), t);
        }
        self.materials.insert(full_key, name.clone());
        Ok(name)
    }

    /// The material bound for rendering: resolved from the nearest prim (the gprim or an
    /// ancestor) that has MaterialBindingAPI, which walks on up from there.
    fn bound_material(&mut self, gprim: &sdf::Path) -> Result<Option<sdf::Path>> {
        let mut p = Some(gprim.clone());
        while let Some(path) = p {
            if path == sdf::Path::abs_root() {
                break;
            }
            let api = MaterialBindingAPI::get(&self.stage, path.clone())
                .map_err(|e| self.read_error(&path, "material:binding", e))?;
            if let Some(api) = api {
                return api
                    .compute_bound_material("full")
                    .map_err(|e| self.read_error(&path, "material:binding", e));
            }
            p = path.parent();
        }
        Ok(None)
    }

    /// `primvars:displayColor` (its first value), else the fallback grey. A colour that varies
    /// over the gprim is a warning (illum has no per-vertex colour).
    fn display_color(&mut self, gprim: &sdf::Path) -> Result<[f64; 3]> {
        let attr = "primvars:displayColor";
        let Some(v) = self.attr(gprim, attr)? else {
            return Ok(FALLBACK_GREY);
        };
        let all = value::vec3_array(&v).or_else(|| value::vec3(&v).map(|c| vec![c]));
        let Some(&first) = all.as_ref().and_then(|a| a.first()) else {
            return Err(self.invalid(gprim, attr, value::show(&v), "expected color3f[]"));
        };
        if all.is_some_and(|a| a.iter().any(|c| *c != first)) {
            self.warn(
                gprim,
                attr,
                "varies over the prim: rendered in its first colour (illum has no per-vertex colour)",
            );
        }
        Ok(first.map(|x| x.clamp(0.0, 1.0)))
    }

    /// The source of `prim.attr`: its value, or what its connections lead to through node
    /// graph and material inputs and outputs.
    pub(super) fn source(&mut self, prim: &sdf::Path, attr: &str) -> Result<Source> {
        let (mut prim, mut attr) = (prim.clone(), attr.to_string());
        for _ in 0..MAX_HOPS {
            let path = prim
                .append_property(attr.as_str())
                .map_err(|e| self.read_error(&prim, &attr, e))?;
            let sources = self
                .stage
                .attribute(path)
                .connections()
                .map_err(|e| self.read_error(&prim, &attr, e))?;
            let Some(src) = sources.first() else {
                return Ok(match self.attr(&prim, &attr)? {
                    Some(v) => Source::Value(v),
                    None => Source::Unset,
                });
            };
            let (p, a) = src.as_str().rsplit_once('.').unwrap_or((src.as_str(), ""));
            let p = sdf::path(p).map_err(|e| self.read_error(&prim, &attr, e))?;
            let kind = self
                .stage
                .prim(p.clone())
                .type_name()
                .map_err(|e| self.read_error(&p, "", e))?
                .map(|t| t.as_str().to_string())
                .unwrap_or_default();
            if kind == "Shader" {
                return Ok(Source::Shader(p, a.to_string()));
            }
            (prim, attr) = (p, a.to_string());
        }
        Err(self.invalid(
            &prim,
            &attr,
            "a connection loop",
            "shading connections must end",
        ))
    }

    pub(super) fn shader_id(&mut self, shader: &sdf::Path) -> Result<String> {
        self.token(shader, "info:id", "")
    }

    fn preview_surface(&mut self, material: &sdf::Path) -> Result<MaterialDef> {
        let shader = match self.source(material, "outputs:surface")? {
            Source::Shader(p, _) if self.shader_id(&p)? == "UsdPreviewSurface" => p,
            _ => {
                self.warn(
                    material,
                    "outputs:surface",
                    "not a UsdPreviewSurface (MaterialX, MDL and other networks are not read): \
                     rendered with UsdPreviewSurface's fallback grey",
                );
                return Ok(lambert(FALLBACK_GREY));
            }
        };
        let diffuse_in = self.color_input(&shader, "diffuseColor", FALLBACK_GREY)?;
        let emission_in = self.color_input(&shader, "emissiveColor", [0.0; 3])?;
        let specular = self.plain_color(&shader, "specularColor", [0.0; 3])?;
        let (metallic, metallic_tex) = self.number_input(&shader, "metallic", 0.0)?;
        let (roughness, roughness_tex) = self.number_input(&shader, "roughness", 0.5)?;
        let ior = self.plain_number(&shader, "ior", 1.5)?;
        let opacity = self.plain_number(&shader, "opacity", 1.0)?;
        if opacity != 1.0 {
            return Err(self.invalid(
                &shader,
                "inputs:opacity",
                opacity,
                "illum renders opaque surfaces only",
            ));
        }
        let clearcoat = self.plain_number(&shader, "clearcoat", 0.0)?;
        if clearcoat != 0.0 {
            return Err(self.invalid(
                &shader,
                "inputs:clearcoat",
                clearcoat,
                "illum has no clearcoat lobe yet (0 renders exactly)",
            ));
        }
        for (input, what) in [
            (
                "normal",
                "normal maps are not rendered (the surface's own normals shade it)",
            ),
            ("occlusion", "ignored (not a physical quantity)"),
            ("displacement", "displacement is not rendered"),
        ] {
            let attr = format!("inputs:{input}");
            if !matches!(self.source(&shader, &attr)?, Source::Unset) {
                self.warn(&shader, &attr, what);
            }
        }
        let specular_workflow = self.plain_number(&shader, "useSpecularWorkflow", 0.0)? != 0.0;
        // A textured colour is the texture times its `scale`, which illum's constant carries.
        let (base, diffuse_tex) = diffuse_in;
        let (emission, emission_tex) = emission_in;
        let textured_scalar = metallic_tex.is_some() || roughness_tex.is_some();
        if specular_workflow && textured_scalar {
            let input = if roughness_tex.is_some() {
                "roughness"
            } else {
                "metallic"
            };
            return Err(self.unsupported(
                &shader,
                &format!("inputs:{input}"),
                "a textured roughness or metallic is read in the metallic workflow only \
                 (useSpecularWorkflow 0)",
            ));
        }
        if !specular_workflow && (textured_scalar || diffuse_tex.is_some() && metallic > 0.0) {
            // Per texel: glTF's metallic-roughness model, which illum's shader derives.
            if !(ior.is_finite() && ior >= 1.0) {
                return Err(self.invalid(&shader, "inputs:ior", ior, "must be >= 1"));
            }
            return Ok(MaterialDef {
                diffuse: base.map(|c| c.clamp(0.0, 1.0)),
                diffuse_texture: diffuse_tex,
                emission,
                emission_texture: emission_tex,
                metallic_roughness: Some(MetallicRoughnessDef {
                    metallic,
                    metallic_texture: metallic_tex,
                    roughness,
                    roughness_texture: roughness_tex,
                    ior,
                }),
                ..Default::default()
            });
        }
        let (diffuse, f0) = if specular_workflow {
            (base, specular)
        } else {
            let dielectric = ((ior - 1.0) / (ior + 1.0)).powi(2);
            (
                base.map(|c| c * (1.0 - metallic)),
                base.map(|c| dielectric + (c - dielectric) * metallic),
            )
        };
        Ok(MaterialDef {
            diffuse: diffuse.map(|c| c.clamp(0.0, 1.0)),
            diffuse_texture: diffuse_tex,
            specular: vec![LobeDef {
                model: ModelDef::Ggx,
                roughness: NumOrArray::One(roughness * roughness),
                fresnel: FresnelDef::Schlick(f0.map(|c| c.clamp(0.0, 1.0))),
            }],
            emission,
            emission_texture: emission_tex,
            two_sided: false,
            tangent: None,
            metallic_roughness: None,
        })
    }

    /// A number input in [0, 1] that may be a texture's channel: (constant, channel). The
    /// constant of a textured input is the texture's `scale` of that channel.
    fn number_input(
        &mut self,
        shader: &sdf::Path,
        input: &str,
        fallback: f64,
    ) -> Result<(f64, Option<ChannelDef>)> {
        let attr = format!("inputs:{input}");
        let (value, channel) = match self.source(shader, &attr)? {
            Source::Shader(tex, output) => {
                let c = match super::texture::output_channel(&output) {
                    Some(c) => c,
                    None => {
                        return Err(self.unsupported(
                            shader,
                            &attr,
                            format!(
                                "connected to {}.{output}: a number input reads one channel of \
                                 a UsdUVTexture (outputs:r, g, b or a)",
                                tex.as_str()
                            ),
                        ));
                    }
                };
                let (name, scale) = self.uv_texture(shader, &attr, &tex, &output)?;
                let k = c as usize;
                let channel = name.map(|texture| ChannelDef {
                    texture,
                    channel: Some(c),
                });
                (scale[k], channel)
            }
            Source::Unset => return Ok((fallback, None)),
            Source::Value(v) => match value::scalar(&v) {
                Some(x) if x.is_finite() => (x.clamp(0.0, 1.0), None),
                _ => {
                    return Err(self.invalid(
                        shader,
                        &attr,
                        value::show(&v),
                        "expected a finite number",
                    ));
                }
            },
        };
        if !(0.0..=1.0).contains(&value) {
            return Err(self.invalid(
                shader,
                &attr,
                value,
                "the texture's scale must keep the input in [0, 1]",
            ));
        }
        Ok((value, channel))
    }

    /// A colour input that may be textured: (constant, texture name).
    fn color_input(
        &mut self,
        shader: &sdf::Path,
        input: &str,
        fallback: [f64; 3],
    ) -> Result<([f64; 3], Option<String>)> {
        let attr = format!("inputs:{input}");
        match self.source(shader, &attr)? {
            Source::Shader(tex, output) => {
                if output != "outputs:rgb" {
                    return Err(self.unsupported(
                        shader,
                        &attr,
                        format!(
                            "connected to {}.{output}: a colour input reads a UsdUVTexture's \
                             outputs:rgb",
                            tex.as_str()
                        ),
                    ));
                }
                let (name, s) = self.uv_texture(shader, &attr, &tex, &output)?;
                Ok(([s[0], s[1], s[2]], name))
            }
            other => Ok((self.color_of(shader, &attr, other, fallback)?, None)),
        }
    }

    fn color_of(
        &self,
        shader: &sdf::Path,
        attr: &str,
        source: Source,
        fallback: [f64; 3],
    ) -> Result<[f64; 3]> {
        match source {
            Source::Unset => Ok(fallback),
            Source::Value(v) => match value::vec3(&v) {
                Some(c) if c.iter().all(|x| x.is_finite()) => Ok(c),
                _ => Err(self.invalid(shader, attr, value::show(&v), "expected a finite color3f")),
            },
            Source::Shader(p, o) => Err(self.unsupported(
                shader,
                attr,
                format!(
                    "connected to {}.{o}: textures are read on diffuseColor, emissiveColor, metallic and roughness only",
                    p.as_str()
                ),
            )),
        }
    }

    /// A colour input that must be a value (or unset).
    fn plain_color(
        &mut self,
        shader: &sdf::Path,
        input: &str,
        fallback: [f64; 3],
    ) -> Result<[f64; 3]> {
        let attr = format!("inputs:{input}");
        let source = self.source(shader, &attr)?;
        self.color_of(shader, &attr, source, fallback)
    }

    /// A number input that must be a value (or unset).
    fn plain_number(&mut self, shader: &sdf::Path, input: &str, fallback: f64) -> Result<f64> {
        let attr = format!("inputs:{input}");
        match self.source(shader, &attr)? {
            Source::Unset => Ok(fallback),
            Source::Value(v) => match value::scalar(&v) {
                Some(x) if x.is_finite() => Ok(x),
                _ => Err(self.invalid(shader, &attr, value::show(&v), "expected a finite number")),
            },
            Source::Shader(p, o) => Err(self.unsupported(
                shader,
                &attr,
                format!(
                    "connected to {}.{o}: textures are read on diffuseColor, emissiveColor, metallic and roughness only",
                    p.as_str()
                ),
            )),
        }
    }

    /// A value input of a node, through interface connections: its value or `fallback`.
    pub(super) fn node_value(&mut self, node: &sdf::Path, attr: &str) -> Result<Option<Value>> {
        match self.source(node, attr)? {
            Source::Unset => Ok(None),
            Source::Value(v) => Ok(Some(v)),
            Source::Shader(p, o) => Err(self.unsupported(
                node,
                attr,
                format!("connected to {}.{o}: illum reads a value here", p.as_str()),
            )),
        }
    }

    pub(super) fn node_token(
        &mut self,
        node: &sdf::Path,
        attr: &str,
        fallback: &str,
    ) -> Result<String> {
        match self.node_value(node, attr)? {
            None => Ok(fallback.to_string()),
            Some(v) => value::token(&v)
                .map(str::to_string)
                .ok_or_else(|| self.invalid(node, attr, value::show(&v), "expected a token")),
        }
    }
}

fn lambert(diffuse: [f64; 3]) -> MaterialDef {
    MaterialDef {
        diffuse,
        ..Default::default()
    }
}
