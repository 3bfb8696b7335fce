//! UsdShade materials: the material bound to a gprim (`material:binding` for the full purpose,
//! `bindMaterialAs` strength and collection bindings as openusd resolves them) read as a
//! `UsdPreviewSurface`, mapped as illum maps glTF's metallic-roughness materials: diffuse =
//! diffuseColor·(1−metallic) and one GGX-Smith lobe of alpha roughness² whose Schlick f0 mixes
//! the dielectric's ((ior−1)/(ior+1))² toward diffuseColor by metallic (the specular workflow:
//! f0 = specularColor, diffuse = diffuseColor).

use super::{Reader, Result, value};
use crate::scene::format::{
    FilterDef, FresnelDef, LobeDef, MaterialDef, ModelDef, NumOrArray, TextureDef, WrapDef,
};
use openusd::schemas::shade::{self, Channel, MaterialBindingAPI, ReadPreviewSurface};
use openusd::sdf;

/// UsdPreviewSurface's diffuseColor fallback, also the colour of unbound gprims without a
/// displayColor.
const FALLBACK_GREY: [f64; 3] = [0.18; 3];

impl Reader {
    /// The name of the illum material for `gprim` (made on first use). `double_sided` makes an
    /// emissive material emit from both faces (`doubleSided`).
    pub(super) fn material(&mut self, gprim: &sdf::Path, double_sided: bool) -> Result<String> {
        let bound = self.bound_material(gprim)?;
        let key = match &bound {
            Some(m) => m.as_str().to_string(),
            None => {
                let c = self.display_color(gprim)?;
                format!("displayColor {c:?}")
            }
        };
        let full_key = format!("{key}{}", if double_sided { " (double-sided)" } else { "" });
        if let Some(name) = self.materials.get(&full_key) {
            return Ok(name.clone());
        }
        let mut def = match &bound {
            Some(m) => self.preview_surface(m)?,
            None => lambert(self.display_color(gprim)?),
        };
        def.two_sided = double_sided && def.emission.iter().any(|&e| e > 0.0);
        let name = if def.two_sided || !double_sided {
            full_key.clone()
        } else {
            key
        };
        if !self.out.materials.0.contains_key(&name) {
            self.out.materials.0.insert(name.clone(), def);
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

    /// `primvars:displayColor` (its first value), else the fallback grey.
    fn display_color(&mut self, gprim: &sdf::Path) -> Result<[f64; 3]> {
        let attr = "primvars:displayColor";
        let Some(v) = self.attr(gprim, attr)? else {
            return Ok(FALLBACK_GREY);
        };
        let c = value::vec3_array(&v)
            .and_then(|a| a.first().copied())
            .or_else(|| value::vec3(&v));
        match c {
            Some(c) => Ok(c.map(|x| x.clamp(0.0, 1.0))),
            None => Err(self.invalid(gprim, attr, value::show(&v), "expected color3f[]")),
        }
    }

    fn preview_surface(&mut self, material: &sdf::Path) -> Result<MaterialDef> {
        let read = shade::read_preview_surface(&self.stage, material)
            .map_err(|e| self.read_error(material, "outputs:surface", e))?;
        let Some(ps) = read else {
            self.warn(
                material,
                "outputs:surface",
                "not a UsdPreviewSurface (MaterialX, MDL and other networks are not read): \
                 rendered with UsdPreviewSurface's fallback grey",
            );
            return Ok(lambert(FALLBACK_GREY));
        };
        let shader = sdf::path(&ps.shader).map_err(|e| self.read_error(material, "", e))?;
        self.no_textures(&shader, &ps)?;
        self.no_other_connections(&shader, &ps)?;
        let diffuse_tex = match ps.diffuse_color.texture() {
            Some(_) => Some(self.uv_texture(&shader, "diffuseColor")?),
            None => None,
        };
        let emission_tex = match ps.emissive_color.texture() {
            Some(_) => Some(self.uv_texture(&shader, "emissiveColor")?),
            None => None,
        };
        let v3 = |c: &Channel<openusd::gf::Vec3f>, fallback: [f64; 3]| {
            c.value()
                .map_or(fallback, |v| [v.x, v.y, v.z].map(f64::from))
        };
        let s = |c: &Channel<f32>, fallback: f64| c.value().map_or(fallback, |&v| f64::from(v));
        let opacity = s(&ps.opacity, 1.0);
        if opacity != 1.0 {
            return Err(self.invalid(
                &shader,
                "inputs:opacity",
                opacity,
                "illum renders opaque surfaces only",
            ));
        }
        let clearcoat = s(&ps.clearcoat, 0.0);
        if clearcoat != 0.0 {
            return Err(self.invalid(
                &shader,
                "inputs:clearcoat",
                clearcoat,
                "illum has no clearcoat lobe yet (0 renders exactly)",
            ));
        }
        if ps.occlusion.is_set() {
            self.warn(
                &shader,
                "inputs:occlusion",
                "ignored (not a physical quantity)",
            );
        }
        // A textured colour is the texture times its `scale`, which illum's constant carries.
        let base = match &diffuse_tex {
            Some((_, scale)) => *scale,
            None => v3(&ps.diffuse_color, FALLBACK_GREY),
        };
        let roughness = s(&ps.roughness, 0.5).clamp(0.0, 1.0);
        let emission = match &emission_tex {
            Some((_, scale)) => *scale,
            None => v3(&ps.emissive_color, [0.0; 3]),
        };
        let specular_workflow = self.number(&shader, "inputs:useSpecularWorkflow", 0.0)? != 0.0;
        let (diffuse, f0) = if specular_workflow {
            (base, v3(&ps.specular_color, [0.0; 3]))
        } else {
            let metallic = s(&ps.metallic, 0.0).clamp(0.0, 1.0);
            if diffuse_tex.is_some() && metallic > 0.0 {
                return Err(self.invalid(
                    &shader,
                    "inputs:metallic",
                    metallic,
                    "with a textured diffuseColor, the metallic f0 would need a texture of its \
                     own: illum renders textured dielectrics (metallic 0) only",
                ));
            }
            let ior = s(&ps.ior, 1.5);
            let dielectric = ((ior - 1.0) / (ior + 1.0)).powi(2);
            (
                base.map(|c| c * (1.0 - metallic)),
                base.map(|c| dielectric + (c - dielectric) * metallic),
            )
        };
        Ok(MaterialDef {
            diffuse: diffuse.map(|c| c.clamp(0.0, 1.0)),
            diffuse_texture: diffuse_tex.map(|t| t.0),
            specular: vec![LobeDef {
                model: ModelDef::Ggx,
                roughness: NumOrArray::One(roughness * roughness),
                fresnel: FresnelDef::Schlick(f0.map(|c| c.clamp(0.0, 1.0))),
            }],
            emission,
            emission_texture: emission_tex.map(|t| t.0),
            two_sided: false,
            tangent: None,
        })
    }

    /// The `UsdUVTexture` that `shader.inputs:<input>` connects to, as a texture of the scene
    /// (its name) and its `scale`. Its `st` must come from a `UsdPrimvarReader_float2` of
    /// `st`, the primvar meshes give; `bias`, a `black` wrap and unequal wraps are errors.
    fn uv_texture(&mut self, shader: &sdf::Path, input: &str) -> Result<(String, [f64; 3])> {
        let attr = format!("inputs:{input}");
        let source = self.connection(shader, &attr)?;
        let (tex_path, output) = source
            .as_str()
            .rsplit_once('.')
            .map(|(p, o)| (p.to_string(), o.to_string()))
            .unwrap_or_default();
        let tex = sdf::path(&tex_path).map_err(|e| self.read_error(shader, &attr, e))?;
        if output != "outputs:rgb" {
            return Err(self.unsupported(
                shader,
                &attr,
                format!(
                    "connected to {}: a colour input reads a texture's outputs:rgb",
                    source.as_str()
                ),
            ));
        }
        let Some(file) = self.attr(&tex, "inputs:file")? else {
            return Err(self.invalid(&tex, "inputs:file", "none", "a UsdUVTexture needs a file"));
        };
        let sdf::Value::AssetPath(a) = &file else {
            return Err(self.invalid(
                &tex,
                "inputs:file",
                value::show(&file),
                "expected an asset path",
            ));
        };
        let file = a.resolved_path().unwrap_or(a.as_str()).to_string();
        let wrap = |r: &mut Self, attr: &str| -> Result<WrapDef> {
            Ok(match r.token(&tex, attr, "useMetadata")?.as_str() {
                // The file's own wrap metadata is not read: repeat, the usual default.
                "repeat" | "useMetadata" => WrapDef::Repeat,
                "clamp" => WrapDef::Clamp,
                "mirror" => WrapDef::Mirror,
                other => {
                    return Err(r.invalid(
                        &tex,
                        attr,
                        other,
                        "illum wraps repeat, clamp or mirror",
                    ));
                }
            })
        };
        let (s, t) = (wrap(self, "inputs:wrapS")?, wrap(self, "inputs:wrapT")?);
        if std::mem::discriminant(&s) != std::mem::discriminant(&t) {
            return Err(self.unsupported(
                &tex,
                "inputs:wrapT",
                "differs from inputs:wrapS: illum wraps both axes alike",
            ));
        }
        let srgb = match self
            .token(&tex, "inputs:sourceColorSpace", "auto")?
            .as_str()
        {
            "auto" => None,
            "sRGB" => Some(true),
            "raw" => Some(false),
            other => {
                return Err(self.invalid(
                    &tex,
                    "inputs:sourceColorSpace",
                    other,
                    "expected auto, sRGB or raw",
                ));
            }
        };
        let four = |r: &mut Self, attr: &str, fallback: [f64; 4]| -> Result<[f64; 4]> {
            Ok(match r.attr(&tex, attr)? {
                None => fallback,
                Some(sdf::Value::Vec4f(v)) => [v.x, v.y, v.z, v.w].map(f64::from),
                Some(sdf::Value::Vec4d(v)) => [v.x, v.y, v.z, v.w],
                Some(v) => return Err(r.invalid(&tex, attr, value::show(&v), "expected float4")),
            })
        };
        let scale = four(self, "inputs:scale", [1.0; 4])?;
        let bias = four(self, "inputs:bias", [0.0; 4])?;
        if bias[..3].iter().any(|&b| b != 0.0) {
            return Err(self.invalid(
                &tex,
                "inputs:bias",
                format!("{bias:?}"),
                "illum's textures take a scale only (bias 0)",
            ));
        }
        // Texture coordinates: the mesh's `st`, through a primvar reader.
        let st = self.connection(&tex, "inputs:st")?;
        let reader = st.prim_path();
        let id = self.token(&reader, "info:id", "")?;
        let var = self.token(&reader, "inputs:varname", "")?;
        if id != "UsdPrimvarReader_float2" || var != "st" {
            return Err(self.unsupported(
                &tex,
                "inputs:st",
                format!(
                    "connected to {} ({id:?} of {var:?}): illum maps textures by the mesh's \
                     primvars:st, through a UsdPrimvarReader_float2 of \"st\"",
                    st.as_str()
                ),
            ));
        }
        let name = format!(
            "{}{}",
            tex.as_str(),
            match srgb {
                None => "",
                Some(true) => " (sRGB)",
                Some(false) => " (raw)",
            }
        );
        self.out
            .textures
            .0
            .entry(name.clone())
            .or_insert(TextureDef {
                file,
                srgb,
                filter: FilterDef::Bilinear,
                wrap: s,
                pixels: None,
            });
        Ok((name, [scale[0], scale[1], scale[2]]))
    }

    /// The one source `prim.attr` connects to.
    fn connection(&mut self, prim: &sdf::Path, attr: &str) -> Result<sdf::Path> {
        let path = prim
            .append_property(attr)
            .map_err(|e| self.read_error(prim, attr, e))?;
        let sources = self
            .stage
            .attribute(path)
            .connections()
            .map_err(|e| self.read_error(prim, attr, e))?;
        match sources.as_slice() {
            [one] => Ok(one.clone()),
            [] => Err(self.invalid(prim, attr, "no connection", "must connect to a source")),
            _ => Err(self.invalid(
                prim,
                attr,
                format!("{} connections", sources.len()),
                "must connect to one source",
            )),
        }
    }

    /// Textured inputs other than diffuseColor and emissiveColor are an error until they are
    /// read (a texture silently dropped would render a different material).
    fn no_textures(&self, shader: &sdf::Path, ps: &ReadPreviewSurface) -> Result<()> {
        let channels: [(&str, bool); 7] = [
            ("specularColor", ps.specular_color.texture().is_some()),
            ("metallic", ps.metallic.texture().is_some()),
            ("roughness", ps.roughness.texture().is_some()),
            ("opacity", ps.opacity.texture().is_some()),
            ("ior", ps.ior.texture().is_some()),
            ("clearcoat", ps.clearcoat.texture().is_some()),
            ("normal", ps.normal.texture().is_some()),
        ];
        if let Some((name, _)) = channels.iter().find(|(_, t)| *t) {
            return Err(self.unsupported(
                shader,
                &format!("inputs:{name}"),
                "connected to a UsdUVTexture: only diffuseColor and emissiveColor textures are read yet",
            ));
        }
        Ok(())
    }
}

impl Reader {
    /// An input connected to anything but a UsdUVTexture (a node graph, a material interface
    /// input) would read as unset: an error instead.
    fn no_other_connections(&mut self, shader: &sdf::Path, ps: &ReadPreviewSurface) -> Result<()> {
        let inputs: [(&str, bool); 12] = [
            ("diffuseColor", ps.diffuse_color.texture().is_some()),
            ("emissiveColor", ps.emissive_color.texture().is_some()),
            ("specularColor", ps.specular_color.texture().is_some()),
            ("metallic", ps.metallic.texture().is_some()),
            ("roughness", ps.roughness.texture().is_some()),
            ("clearcoat", ps.clearcoat.texture().is_some()),
            (
                "clearcoatRoughness",
                ps.clearcoat_roughness.texture().is_some(),
            ),
            ("opacity", ps.opacity.texture().is_some()),
            ("opacityThreshold", ps.opacity_threshold.texture().is_some()),
            ("ior", ps.ior.texture().is_some()),
            ("normal", ps.normal.texture().is_some()),
            ("occlusion", ps.occlusion.texture().is_some()),
        ];
        for (name, textured) in inputs {
            let attr = format!("inputs:{name}");
            let path = shader
                .append_property(attr.as_str())
                .map_err(|e| self.read_error(shader, &attr, e))?;
            let sources = self
                .stage
                .attribute(path)
                .connections()
                .map_err(|e| self.read_error(shader, &attr, e))?;
            if !textured && let Some(src) = sources.first() {
                return Err(self.unsupported(
                    shader,
                    &attr,
                    format!(
                        "connected to {}, which illum does not read (inputs take values or a \
                         UsdUVTexture)",
                        src.as_str()
                    ),
                ));
            }
        }
        Ok(())
    }
}

fn lambert(diffuse: [f64; 3]) -> MaterialDef {
    MaterialDef {
        diffuse,
        diffuse_texture: None,
        specular: Vec::new(),
        emission: [0.0; 3],
        emission_texture: None,
        two_sided: false,
        tangent: None,
    }
}
