//! UsdUVTexture nodes: the image a shading input reads (file, wraps, colour space, scale) and
//! the texture coordinates it reads them at (a primvar reader, and a UsdTransform2d).

use super::shade::Source;
use super::{Reader, Result, TexCoords, Transform2d, value};
use crate::scene::format::{ChannelName, WrapDef};
use openusd::sdf::{self, Value};

impl Reader {
    /// What a texture's `inputs:st` reads: a `UsdPrimvarReader_float2` of a mesh primvar,
    /// directly or through one `UsdTransform2d`.
    fn texcoords_of(&mut self, tex: &sdf::Path) -> Result<TexCoords> {
        let not_connected = |r: &Self, prim: &sdf::Path, attr: &str| {
            r.invalid(
                prim,
                attr,
                "not connected",
                "must connect to a UsdPrimvarReader_float2 (texture coordinates)",
            )
        };
        let Source::Shader(mut reader, _) = self.source(tex, "inputs:st")? else {
            return Err(not_connected(self, tex, "inputs:st"));
        };
        let mut transform = None;
        if self.shader_id(&reader)? == "UsdTransform2d" {
            let node = reader.clone();
            let two = |r: &mut Self, attr: &str, fallback: [f64; 2]| -> Result<[f64; 2]> {
                Ok(match r.node_value(&node, attr)? {
                    None => fallback,
                    Some(v) => match value::vec2(&v) {
                        Some(x) if x.iter().all(|c| c.is_finite()) => x,
                        _ => {
                            return Err(r.invalid(&node, attr, value::show(&v), "expected float2"));
                        }
                    },
                })
            };
            let rotation_deg = match self.node_value(&node, "inputs:rotation")? {
                None => 0.0,
                Some(v) => match value::scalar(&v) {
                    Some(x) if x.is_finite() => x,
                    _ => {
                        return Err(self.invalid(
                            &node,
                            "inputs:rotation",
                            value::show(&v),
                            "expected a finite float (degrees)",
                        ));
                    }
                },
            };
            transform = Some(Transform2d {
                rotation_deg,
                scale: two(self, "inputs:scale", [1.0, 1.0])?,
                translation: two(self, "inputs:translation", [0.0, 0.0])?,
            });
            reader = match self.source(&node, "inputs:in")? {
                Source::Shader(p, _) => p,
                _ => return Err(not_connected(self, &node, "inputs:in")),
            };
        }
        let id = self.shader_id(&reader)?;
        let var = self.node_token(&reader, "inputs:varname", "")?;
        if id != "UsdPrimvarReader_float2" || var.is_empty() {
            return Err(self.unsupported(
                tex,
                "inputs:st",
                format!(
                    "connected to {} ({id:?} of {var:?}): illum maps textures by a mesh \
                     primvar, through a UsdPrimvarReader_float2 that names it (and at most one \
                     UsdTransform2d)",
                    reader.as_str()
                ),
            ));
        }
        Ok(TexCoords {
            primvar: var,
            transform,
        })
    }

    /// The `UsdUVTexture` `tex` that `shader.attr` connects to (its `output`: `rgb` or one
    /// channel), as a texture of the scene (its name) and its `scale`; without a file, no
    /// texture and its `fallback` as the scale. Its `st` must come from a
    /// `UsdPrimvarReader_float2` of `st`, the primvar meshes give; a `bias` on the channels
    /// read, a `black` wrap and unequal wraps are errors.
    pub(super) fn uv_texture(
        &mut self,
        shader: &sdf::Path,
        attr: &str,
        tex: &sdf::Path,
        output: &str,
    ) -> Result<(Option<String>, [f64; 4])> {
        let id = self.shader_id(tex)?;
        if id != "UsdUVTexture" {
            return Err(self.unsupported(
                shader,
                attr,
                format!(
                    "connected to {}.{output} ({id:?}): illum reads UsdUVTexture outputs",
                    tex.as_str()
                ),
            ));
        }
        let read = output_channel(output).map_or(vec![0, 1, 2], |c| vec![c as usize]);
        let four = |r: &mut Self, attr: &str, fallback: [f64; 4]| -> Result<[f64; 4]> {
            Ok(match r.node_value(tex, attr)? {
                None => fallback,
                Some(Value::Vec4f(v)) => [v.x, v.y, v.z, v.w].map(f64::from),
                Some(Value::Vec4d(v)) => [v.x, v.y, v.z, v.w],
                Some(v) => return Err(r.invalid(tex, attr, value::show(&v), "expected float4")),
            })
        };
        let (file, bytes) = match self.node_value(tex, "inputs:file")? {
            Some(Value::AssetPath(a)) if !a.as_str().is_empty() => {
                self.asset_file(tex, "inputs:file", &a)
            }
            Some(Value::AssetPath(_)) | None => {
                // No image: the texture gives its fallback.
                let f = four(self, "inputs:fallback", [0.0, 0.0, 0.0, 1.0])?;
                return Ok((None, f));
            }
            Some(v) => {
                return Err(self.invalid(
                    tex,
                    "inputs:file",
                    value::show(&v),
                    "expected an asset path",
                ));
            }
        };
        let mut wraps = Vec::new();
        for attr in ["inputs:wrapS", "inputs:wrapT"] {
            wraps.push(match self.node_token(tex, attr, "useMetadata")?.as_str() {
                // The file's own wrap metadata is not read: repeat, the usual default.
                "repeat" | "useMetadata" => WrapDef::Repeat,
                "clamp" => WrapDef::Clamp,
                "mirror" => WrapDef::Mirror,
                other => {
                    return Err(self.invalid(
                        tex,
                        attr,
                        other,
                        "illum wraps repeat, clamp or mirror",
                    ));
                }
            });
        }
        if std::mem::discriminant(&wraps[0]) != std::mem::discriminant(&wraps[1]) {
            return Err(self.unsupported(
                tex,
                "inputs:wrapT",
                "differs from inputs:wrapS: illum wraps both axes alike",
            ));
        }
        let srgb = match self
            .node_token(tex, "inputs:sourceColorSpace", "auto")?
            .as_str()
        {
            "auto" => None,
            "sRGB" => Some(true),
            "raw" => Some(false),
            other => {
                return Err(self.invalid(
                    tex,
                    "inputs:sourceColorSpace",
                    other,
                    "expected auto, sRGB or raw",
                ));
            }
        };
        let scale = four(self, "inputs:scale", [1.0; 4])?;
        let bias = four(self, "inputs:bias", [0.0; 4])?;
        if read.iter().any(|&c| bias[c] != 0.0) {
            return Err(self.invalid(
                tex,
                "inputs:bias",
                format!("{bias:?}"),
                "illum's textures take a scale only (bias 0)",
            ));
        }
        // Texture coordinates: a mesh primvar, through a primvar reader (and a UsdTransform2d).
        let coords = self.texcoords_of(tex)?;
        // One set of texture coordinates per material: the meshes give that primvar.
        match &self.texcoords {
            Some(other) if *other != coords => {
                return Err(self.unsupported(
                    tex,
                    "inputs:st",
                    format!(
                        "reads {coords:?}, another texture of the material {other:?}: illum \
                         gives a mesh one set of texture coordinates"
                    ),
                ));
            }
            _ => self.texcoords = Some(coords),
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
        let wrap = wraps[0];
        self.add_texture(&name, file, bytes, srgb, wrap);
        Ok((Some(name), scale))
    }
}

/// The channel a UsdUVTexture output gives (`outputs:r` … `outputs:a`); None for `outputs:rgb`
/// and anything else.
pub(super) fn output_channel(output: &str) -> Option<ChannelName> {
    match output {
        "outputs:r" => Some(ChannelName::R),
        "outputs:g" => Some(ChannelName::G),
        "outputs:b" => Some(ChannelName::B),
        "outputs:a" => Some(ChannelName::A),
        _ => None,
    }
}
