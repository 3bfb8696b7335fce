//! glTF primitives → `Mesh`. Accessors are checked (type, bounds) before the gltf crate's
//! reader touches them: the reader trusts the file and would misread or panic otherwise.

use super::error::SceneError;
use super::gltf::Loader;
use super::types::{MaterialId, Mesh};
use glam::{Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

type Result<T> = std::result::Result<T, SceneError>;

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

fn type_name(t: DataType, normalized: bool, dims: Dimensions) -> String {
    let t = match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    };
    let d = match dims {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    };
    let n = if normalized { " normalized" } else { "" };
    format!("{t}{n} {d}")
}

/// Accepted (component type, normalized) pairs of an attribute, with their description.
struct Expect {
    types: &'static [(DataType, bool)],
    dims: Dimensions,
    what: &'static str,
}

const POSITION: Expect = Expect {
    types: &[(DataType::F32, false)],
    dims: Dimensions::Vec3,
    what: "FLOAT VEC3",
};
const NORMAL: Expect = POSITION;
const TANGENT: Expect = Expect {
    types: &[(DataType::F32, false)],
    dims: Dimensions::Vec4,
    what: "FLOAT VEC4",
};
const TEXCOORD: Expect = Expect {
    types: &[
        (DataType::F32, false),
        (DataType::U8, true),
        (DataType::U16, true),
    ],
    dims: Dimensions::Vec2,
    what: "FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT VEC2",
};
const INDICES: Expect = Expect {
    types: &[
        (DataType::U8, false),
        (DataType::U16, false),
        (DataType::U32, false),
    ],
    dims: Dimensions::Scalar,
    what: "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT SCALAR",
};

/// Whether every element of an optional attribute passes `ok`.
fn all<T>(v: &Option<Vec<T>>, ok: impl Fn(&T) -> bool) -> bool {
    v.as_ref().is_none_or(|v| v.iter().all(ok))
}

impl Loader<'_> {
    pub(crate) fn primitive(
        &mut self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        name: String,
        material: MaterialId,
    ) -> Result<Mesh> {
        let f = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let ctx = self.ctx();
        if prim.mode() != Mode::Triangles {
            return Err(ctx.err(
                format!("{f}.mode"),
                mode_name(prim.mode()),
                "only TRIANGLES is supported",
            ));
        }
        let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
            return Err(self.unsupported(format!("{f}.attributes"), "POSITION is missing"));
        };
        let n = pos_acc.count();
        self.check(
            &format!("{f}.attributes.POSITION"),
            &pos_acc,
            &POSITION,
            None,
        )?;
        let optional = |sem: gltf::Semantic, key: &str, e: &Expect| -> Result<bool> {
            match prim.get(&sem) {
                Some(acc) => self
                    .check(&format!("{f}.attributes.{key}"), &acc, e, Some(n))
                    .map(|_| true),
                None => Ok(false),
            }
        };
        let has_normals = optional(gltf::Semantic::Normals, "NORMAL", &NORMAL)?;
        let has_tangents = optional(gltf::Semantic::Tangents, "TANGENT", &TANGENT)?;
        let has_uvs = optional(gltf::Semantic::TexCoords(0), "TEXCOORD_0", &TEXCOORD)?;
        if let Some(acc) = prim.indices() {
            self.check(&format!("{f}.indices"), &acc, &INDICES, None)?;
        }

        let buffers = &self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let short = |key: &str| self.unsupported(format!("{f}.{key}"), "accessor data is short");
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| short("attributes.POSITION"))?
            .map(Vec3::from_array)
            .collect();
        let normals: Option<Vec<Vec3>> = match has_normals {
            false => None,
            true => Some(
                reader
                    .read_normals()
                    .ok_or_else(|| short("attributes.NORMAL"))?
                    .map(Vec3::from_array)
                    .collect(),
            ),
        };
        let tangents: Option<Vec<Vec4>> = match has_tangents {
            false => None,
            true => Some(
                reader
                    .read_tangents()
                    .ok_or_else(|| short("attributes.TANGENT"))?
                    .map(Vec4::from_array)
                    .collect(),
            ),
        };
        let uvs: Option<Vec<Vec2>> = match has_uvs {
            false => None,
            true => Some(
                reader
                    .read_tex_coords(0)
                    .ok_or_else(|| short("attributes.TEXCOORD_0"))?
                    .into_f32()
                    .map(Vec2::from_array)
                    .collect(),
            ),
        };
        let indices: Vec<u32> = match reader.read_indices() {
            Some(idx) => idx.into_u32().collect(),
            None if prim.indices().is_some() => return Err(short("indices")),
            None => (0..n as u32).collect(),
        };

        let finite = |key: &str, ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(ctx.err(
                    format!("{f}.{key}"),
                    "NaN or infinity",
                    "values must be finite",
                ))
            }
        };
        let lengths_ok = positions.len() == n
            && normals.as_ref().is_none_or(|v| v.len() == n)
            && tangents.as_ref().is_none_or(|v| v.len() == n)
            && uvs.as_ref().is_none_or(|v| v.len() == n);
        if !lengths_ok {
            return Err(short("attributes"));
        }
        finite(
            "attributes.POSITION",
            positions.iter().all(|p| p.is_finite()),
        )?;
        finite("attributes.NORMAL", all(&normals, |v| v.is_finite()))?;
        finite("attributes.TANGENT", all(&tangents, |v| v.is_finite()))?;
        finite("attributes.TEXCOORD_0", all(&uvs, |v| v.is_finite()))?;

        if indices.is_empty() || indices.len() % 3 != 0 {
            let key = if prim.indices().is_some() {
                "indices"
            } else {
                "attributes.POSITION"
            };
            return Err(ctx.err(
                format!("{f}.{key}"),
                format!("{} indices", indices.len()),
                "a triangle list needs a non-zero multiple of 3 indices",
            ));
        }
        if let Some(i) = indices.iter().position(|&i| i as usize >= n) {
            return Err(ctx.err(
                format!("{f}.indices[{i}]"),
                indices[i],
                &format!("index out of range (POSITION has {n} vertices)"),
            ));
        }
        Ok(Mesh {
            name,
            positions,
            normals,
            tangents,
            uvs,
            indices,
            material,
        })
    }

    /// Checks the type of an accessor and that all its data lies inside its buffer.
    fn check(
        &self,
        field: &str,
        acc: &gltf::Accessor,
        e: &Expect,
        count: Option<usize>,
    ) -> Result<()> {
        let field = format!("{field} (accessors[{}])", acc.index());
        let got = (acc.data_type(), acc.normalized());
        if !e.types.contains(&got) || acc.dimensions() != e.dims {
            return Err(self.ctx().err(
                field,
                type_name(got.0, got.1, acc.dimensions()),
                &format!("must be {}", e.what),
            ));
        }
        if acc.count() == 0 {
            return Err(self.ctx().err(field, 0, "count must be at least 1"));
        }
        if let Some(n) = count.filter(|&n| n != acc.count()) {
            return Err(self.ctx().err(
                field,
                format!("count {}", acc.count()),
                &format!("must have as many elements as POSITION ({n})"),
            ));
        }
        let elem = acc.size();
        let bounds =
            |r: std::result::Result<(), String>| r.map_err(|m| self.unsupported(field.clone(), m));
        match acc.view() {
            Some(view) => bounds(self.check_range(&view, acc.offset(), elem, acc.count()))?,
            None if acc.sparse().is_none() => {
                return Err(self.unsupported(
                    field,
                    "accessors without a bufferView (all zeros) are not supported",
                ));
            }
            None => {}
        }
        if let Some(sparse) = acc.sparse() {
            let n = sparse.count();
            if n == 0 {
                return Err(self.ctx().err(field, 0, "sparse.count must be at least 1"));
            }
            let idx = sparse.indices();
            let idx_size = idx.index_type().size();
            bounds(self.check_range(&idx.view(), idx.offset(), idx_size, n))?;
            let values = sparse.values();
            bounds(self.check_range(&values.view(), values.offset(), elem, n))?;
        }
        Ok(())
    }

    fn check_range(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        elem: usize,
        count: usize,
    ) -> std::result::Result<(), String> {
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(format!(
                "bufferViews[{}].byteStride {stride} is smaller than the element size {elem}",
                view.index()
            ));
        }
        let end = stride
            .checked_mul(count - 1)
            .and_then(|x| x.checked_add(offset))
            .and_then(|x| x.checked_add(elem));
        if end.is_none_or(|end| end > view.length()) {
            return Err(format!(
                "data runs past the end of bufferViews[{}] ({} bytes)",
                view.index(),
                view.length()
            ));
        }
        let buffer_len = self.buffers.get(view.buffer().index()).map_or(0, Vec::len);
        if view
            .offset()
            .checked_add(view.length())
            .is_none_or(|e| e > buffer_len)
        {
            return Err(format!(
                "bufferViews[{}] runs past the end of buffers[{}] ({buffer_len} bytes)",
                view.index(),
                view.buffer().index()
            ));
        }
        Ok(())
    }
}
