//! UsdShade materials: the material bound to a gprim (`material:binding` for the full purpose,
//! `bindMaterialAs` strength and collection bindings as openusd resolves them) read as a
//! `UsdPreviewSurface`, mapped as illum maps glTF's metallic-roughness materials: diffuse =
//! diffuseColor·(1−metallic) and one GGX-Smith lobe of alpha roughness² whose Schlick f0 mixes
//! the dielectric's ((ior−1)/(ior+1))² toward diffuseColor by metallic (the specular workflow:
//! f0 = specularColor, diffuse = diffuseColor).

use super::{Reader, Result, value};
use crate::scene::format::{FresnelDef, LobeDef, MaterialDef, ModelDef, NumOrArray};
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
        let base = v3(&ps.diffuse_color, FALLBACK_GREY);
        let roughness = s(&ps.roughness, 0.5).clamp(0.0, 1.0);
        let emission = v3(&ps.emissive_color, [0.0; 3]);
        let specular_workflow = self.number(&shader, "inputs:useSpecularWorkflow", 0.0)? != 0.0;
        let (diffuse, f0) = if specular_workflow {
            (base, v3(&ps.specular_color, [0.0; 3]))
        } else {
            let metallic = s(&ps.metallic, 0.0).clamp(0.0, 1.0);
            let ior = s(&ps.ior, 1.5);
            let dielectric = ((ior - 1.0) / (ior + 1.0)).powi(2);
            (
                base.map(|c| c * (1.0 - metallic)),
                base.map(|c| dielectric + (c - dielectric) * metallic),
            )
        };
        Ok(MaterialDef {
            diffuse: diffuse.map(|c| c.clamp(0.0, 1.0)),
            diffuse_texture: None,
            specular: vec![LobeDef {
                model: ModelDef::Ggx,
                roughness: NumOrArray::One(roughness * roughness),
                fresnel: FresnelDef::Schlick(f0.map(|c| c.clamp(0.0, 1.0))),
            }],
            emission,
            emission_texture: None,
            two_sided: false,
            tangent: None,
        })
    }

    /// Textured inputs are an error until they are read (a texture silently dropped would
    /// render a different material).
    fn no_textures(&self, shader: &sdf::Path, ps: &ReadPreviewSurface) -> Result<()> {
        let channels: [(&str, bool); 9] = [
            ("diffuseColor", ps.diffuse_color.texture().is_some()),
            ("emissiveColor", ps.emissive_color.texture().is_some()),
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
                "connected to a UsdUVTexture: textured UsdPreviewSurface inputs are not read yet",
            ));
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
