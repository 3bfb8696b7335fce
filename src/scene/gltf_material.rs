//! glTF metallic-roughness materials → `Material`, and their images → `Texture`.
//!
//! Mapping (see docs/scene-format.md): diffuse = base_color·(1−metallic); one GGX-Smith lobe
//! with alpha = max(roughness², 1e-4) and Schlick f0 = mix(0.04, base_color, metallic);
//! emission = emissive_factor × KHR_materials_emissive_strength.

use super::error::SceneError;
use super::gltf::{Loader, read_uri};
use super::texture::{self, ImageKind};
use super::types::{Material, MaterialId, MetallicRoughness, TextureId};
use glam::{Vec3, Vec4};

type Result<T> = std::result::Result<T, SceneError>;

impl Loader<'_> {
    /// The scene material for a glTF material (converted once per file).
    pub(crate) fn material_id(&mut self, m: &gltf::Material) -> Result<MaterialId> {
        if let Some(&id) = self.material_ids.get(&m.index()) {
            return Ok(id);
        }
        let material = match m.index() {
            Some(i) => self.convert(m, i)?,
            // glTF's default material is white metal; a neutral grey reads better.
            None => Material::lambert(format!("{}/default", self.req.shape), Vec3::splat(0.5)),
        };
        let id = self.parts.materials.len() as MaterialId;
        self.parts.materials.push(material);
        self.material_ids.insert(m.index(), id);
        Ok(id)
    }

    fn convert(&mut self, m: &gltf::Material, index: usize) -> Result<Material> {
        let f = format!("materials[{index}]");
        let pbr = m.pbr_metallic_roughness();
        // Out-of-range factors are invalid glTF; clamp rather than reject, as viewers do.
        let base = Vec4::from_array(pbr.base_color_factor())
            .truncate()
            .clamp(Vec3::ZERO, Vec3::ONE);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let pf = format!("{f}.pbrMetallicRoughness");
        let diffuse_texture = match pbr.base_color_texture() {
            Some(info) => Some(self.texture_id(&info, true, &format!("{pf}.baseColorTexture"))?),
            None => None,
        };
        let metallic_roughness_texture = match pbr.metallic_roughness_texture() {
            Some(info) => {
                Some(self.texture_id(&info, false, &format!("{pf}.metallicRoughnessTexture"))?)
            }
            None => None,
        };
        let emission_texture = match m.emissive_texture() {
            Some(info) => Some(self.texture_id(&info, true, &format!("{f}.emissiveTexture"))?),
            None => None,
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from_array(m.emissive_factor()) * strength;
        if !emission.is_finite() || emission.min_element() < 0.0 {
            return Err(self.ctx().err(
                format!("{f}.emissiveFactor"),
                format!("{emission} (with emissive_strength {strength})"),
                "emission must be finite and >= 0",
            ));
        }
        let name = match m.name() {
            Some(n) if !n.is_empty() => n.to_owned(),
            _ => f.clone(),
        };
        let factors = MetallicRoughness {
            base_color: base,
            metallic,
            roughness,
            dielectric_f0: 0.04,
        };
        Ok(Material {
            name: format!("{}/{name}", self.req.shape),
            diffuse: factors.diffuse(),
            diffuse_texture,
            specular: vec![factors.lobe()],
            metallic_roughness_texture,
            metallic_roughness: Some(factors),
            emission,
            emission_texture,
            two_sided: m.double_sided(),
            tangent_direction: None,
        })
    }

    /// Decodes the image of a texture reference once per (image, colour space).
    fn texture_id(
        &mut self,
        info: &gltf::texture::Info,
        srgb: bool,
        field: &str,
    ) -> Result<TextureId> {
        if info.tex_coord() != 0 {
            return Err(self.ctx().err(
                format!("{field}.texCoord"),
                info.tex_coord(),
                "only TEXCOORD_0 is supported",
            ));
        }
        let image = info.texture().source();
        let i = image.index();
        if let Some(&id) = self.image_ids.get(&(i, srgb)) {
            return Ok(id);
        }
        let f = format!("images[{i}]");
        let (bytes, origin, mime) = match image.source() {
            gltf::image::Source::View { view, mime_type } => {
                let start = view.offset();
                let data = self
                    .buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.get(start..start.checked_add(view.length())?))
                    .ok_or_else(|| {
                        self.unsupported(
                            &f,
                            format!("bufferViews[{}] exceeds its buffer", view.index()),
                        )
                    })?;
                (
                    data.to_vec(),
                    format!("bufferViews[{}]", view.index()),
                    Some(mime_type),
                )
            }
            gltf::image::Source::Uri { uri, mime_type } => {
                let data = read_uri(uri, self.dir, &self.gfile, &format!("{f}.uri"))?;
                let origin = if uri.starts_with("data:") {
                    "data: URI"
                } else {
                    uri
                };
                (data, origin.to_owned(), mime_type)
            }
        };
        let kind = ImageKind::sniff(&bytes)
            .or(match mime {
                Some("image/png") => Some(ImageKind::Png),
                Some("image/jpeg") => Some(ImageKind::Jpeg),
                _ => None,
            })
            .ok_or_else(|| {
                self.unsupported(
                    &f,
                    format!("unsupported image format in {origin} (illum reads PNG and JPEG)"),
                )
            })?;
        let name = match image.name() {
            Some(n) if !n.is_empty() => format!("{}/{n}", self.req.shape),
            _ => format!("{}/{f}", self.req.shape),
        };
        let tex = texture::decode(&name, &bytes, kind, srgb)
            .map_err(|m| SceneError::decode(&self.gfile, &f, &origin, m))?;
        let id = self.parts.textures.len() as TextureId;
        self.parts.textures.push(tex);
        self.image_ids.insert((i, srgb), id);
        Ok(id)
    }
}
