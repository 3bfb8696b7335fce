//! UsdGeom gprims: `Mesh` (polygons triangulated as fans, normals and texture coordinates at any
//! interpolation, indexed or not), `Sphere` (illum's exact sphere), `Cube` and `Plane` (their
//! exact triangles). Meshes keep their local points and carry the world transform.

use super::xform::row_major;
use super::{Reader, Result, TexCoords, value};
use crate::scene::format::{MeshDef, ShapeDef, SphereDef, TransformDef};
use glam::{DMat4, DVec3};
use openusd::sdf;

/// How a primvar's values map onto a mesh (UsdGeom's interpolation tokens).
#[derive(Clone, Copy, PartialEq)]
enum Interp {
    Constant,
    Uniform,
    Vertex,
    FaceVarying,
}

/// A primvar's values, one per element of its interpolation.
struct Primvar<T> {
    values: Vec<T>,
    interp: Interp,
}

impl<T: Copy> Primvar<T> {
    /// The value at corner `k` (of face `f`, on point `p`).
    fn at(&self, f: usize, k: usize, p: usize) -> T {
        self.values[match self.interp {
            Interp::Constant => 0,
            Interp::Uniform => f,
            Interp::Vertex => p,
            Interp::FaceVarying => k,
        }]
    }
}

/// Where a gprim goes: its shape's name, its world transform, and the key of the meshes it may
/// share (its prototype prim, for instances), with which it places an existing mesh again.
pub(super) struct Place {
    pub name: String,
    pub world: DMat4,
    pub share: Option<String>,
}

impl Reader {
    /// A gprim's shape entry: its material and, for meshes, its transform.
    fn add_shape(&mut self, prim: &sdf::Path, at: &Place, mut shape: ShapeDef) -> Result<()> {
        let double_sided = self.boolean(prim, "doubleSided", false)?;
        shape.material = Some(self.material(prim, double_sided)?);
        self.out.shapes.0.insert(at.name.clone(), shape);
        Ok(())
    }

    /// A mesh shape at `at`. Gprims with the same share key and material share one mesh: the
    /// first makes it (`build`), the others place it again (an `instance` shape).
    fn mesh_shape(
        &mut self,
        prim: &sdf::Path,
        at: &Place,
        build: impl FnOnce(&mut Self, &TexCoords) -> Result<Option<MeshDef>>,
    ) -> Result<()> {
        let double_sided = self.boolean(prim, "doubleSided", false)?;
        let material = self.material(prim, double_sided)?;
        let texcoords = self
            .texcoord_of
            .get(&material)
            .cloned()
            .unwrap_or_else(TexCoords::st);
        let transform = Some(TransformDef {
            matrix: Some(row_major(at.world)),
            ..Default::default()
        });
        let key = at.share.as_ref().map(|p| format!("{p}\n{material}"));
        let name = at.name.clone();
        if let Some(first) = key.as_ref().and_then(|k| self.instanced.get(k)) {
            let shape = ShapeDef {
                instance: Some(first.clone()),
                transform,
                ..Default::default()
            };
            self.out.shapes.0.insert(name, shape);
            return Ok(());
        }
        let Some(mesh) = build(self, &texcoords)? else {
            return Ok(());
        };
        let shape = ShapeDef {
            mesh: Some(mesh),
            material: Some(material),
            transform,
            ..Default::default()
        };
        self.out.shapes.0.insert(name.clone(), shape);
        if let Some(k) = key {
            self.instanced.insert(k, name);
        }
        Ok(())
    }

    /// The gprim at `prim` of a supported kind, placed at `at`; false for another kind.
    pub(super) fn gprim(&mut self, prim: &sdf::Path, kind: &str, at: &Place) -> Result<bool> {
        match kind {
            "Mesh" => self.mesh_shape(prim, at, |r, st| r.read_mesh(prim, st))?,
            "Sphere" => self.sphere(prim, at)?,
            "Cube" => self.cube(prim, at)?,
            "Plane" => self.plane(prim, at)?,
            "Cylinder" | "Cone" | "Capsule" | "Cylinder_1" | "Capsule_1" => {
                self.quadric(prim, kind, at)?
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The prim of the prototype that an instance proxy stands for.
    pub(super) fn prototype_of(&self, prim: &sdf::Path) -> Result<Option<sdf::Path>> {
        let p = self.stage.prim(prim.clone());
        let read = |e| self.read_error(prim, "", e);
        if !p.is_instance_proxy().map_err(read)? {
            return Ok(None);
        }
        Ok(p.prim_in_prototype()
            .map_err(|e| self.read_error(prim, "", e))?
            .map(|q| q.path().clone()))
    }

    /// A Mesh prim's triangles, or None (with a warning) when it has none.
    /// `coords` are the texture coordinates its material reads (`primvars:<primvar>`).
    fn read_mesh(&mut self, prim: &sdf::Path, coords: &TexCoords) -> Result<Option<MeshDef>> {
        let points = self.vec3s(prim, "points")?;
        let counts = self.ints(prim, "faceVertexCounts")?;
        let indices = self.ints(prim, "faceVertexIndices")?;
        let (Some(points), Some(counts), Some(indices)) = (points, counts, indices) else {
            self.warn(
                prim,
                "",
                "a Mesh without points, faceVertexCounts and faceVertexIndices: nothing to render",
            );
            return Ok(None);
        };
        if let Some(p) = points.iter().find(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(self.invalid(prim, "points", format!("{p:?}"), "points must be finite"));
        }
        let total: i64 = counts.iter().sum();
        if let Some(c) = counts.iter().find(|&&c| c < 3) {
            return Err(self.invalid(
                prim,
                "faceVertexCounts",
                c,
                "each face needs at least 3 vertices",
            ));
        }
        if total != indices.len() as i64 {
            return Err(self.invalid(
                prim,
                "faceVertexIndices",
                format!("{} indices", indices.len()),
                &format!("faceVertexCounts adds up to {total}"),
            ));
        }
        self.check_indices(prim, "faceVertexIndices", &indices, points.len(), "points")?;
        if self.token(prim, "subdivisionScheme", "catmullClark")? != "none" {
            self.warn(
                prim,
                "subdivisionScheme",
                "rendered as its control mesh (illum does not subdivide surfaces)",
            );
        }
        let left = self.token(prim, "orientation", "rightHanded")? == "leftHanded";
        let faces = counts.len();
        let (n_points, n_corners) = (points.len(), indices.len());
        let sizes = (faces, n_points, n_corners);
        let normals = match self.primvar_n(prim, "primvars:normals", value::vec3_array, sizes)? {
            Some(n) => Some(n),
            None => self.primvar_n(prim, "normals", value::vec3_array, sizes)?,
        };
        let st_attr = format!("primvars:{}", coords.primvar);
        let st = self.primvar_n(prim, &st_attr, value::vec2_array, sizes)?;
        let per_point = |i: Option<Interp>| i.is_none_or(|i| i == Interp::Vertex);
        let shared = per_point(normals.as_ref().map(|n| n.interp))
            && per_point(st.as_ref().map(|s| s.interp));
        // Triangle fans over the face corners; left-handed faces wind the other way.
        let mut tris: Vec<u32> = Vec::with_capacity(3 * (n_corners - 2 * faces));
        let mut start = 0usize;
        for &c in &counts {
            for j in 1..c as usize - 1 {
                let (a, b) = (start + j, start + j + 1);
                let t = if left { [start, b, a] } else { [start, a, b] };
                tris.extend(t.map(|k| k as u32));
            }
            start += c as usize;
        }
        let point = |k: usize| indices[k] as usize;
        let flip = |st: [f64; 2]| coords.uv(st);
        let mesh = if shared {
            MeshDef {
                indices: Some(tris.iter().map(|&k| point(k as usize) as u32).collect()),
                positions: points,
                normals: normals.map(|n| n.values),
                uvs: st.map(|s| s.values.into_iter().map(flip).collect()),
                tangents: None,
            }
        } else {
            // One vertex per face corner: (face, corner).
            let mut corners = Vec::with_capacity(n_corners);
            let mut start = 0usize;
            for (f, &c) in counts.iter().enumerate() {
                corners.extend((start..start + c as usize).map(|k| (f, k)));
                start += c as usize;
            }
            MeshDef {
                positions: corners.iter().map(|&(_, k)| points[point(k)]).collect(),
                indices: Some(tris),
                normals: normals
                    .map(|n| corners.iter().map(|&(f, k)| n.at(f, k, point(k))).collect()),
                uvs: st.map(|s| {
                    corners
                        .iter()
                        .map(|&(f, k)| flip(s.at(f, k, point(k))))
                        .collect()
                }),
                tangents: None,
            }
        };
        if mesh.indices.as_ref().is_some_and(|i| i.is_empty()) {
            self.warn(prim, "", "a Mesh with no faces: nothing to render");
            return Ok(None);
        }
        Ok(Some(mesh))
    }

    pub(super) fn vec3s(&mut self, prim: &sdf::Path, attr: &str) -> Result<Option<Vec<[f64; 3]>>> {
        match self.attr(prim, attr)? {
            None => Ok(None),
            Some(v) => value::vec3_array(&v).map(Some).ok_or_else(|| {
                self.invalid(
                    prim,
                    attr,
                    value::show(&v),
                    "expected an array of 3-vectors",
                )
            }),
        }
    }

    pub(super) fn ints(&mut self, prim: &sdf::Path, attr: &str) -> Result<Option<Vec<i64>>> {
        match self.attr(prim, attr)? {
            None => Ok(None),
            Some(v) => value::int_array(&v)
                .map(Some)
                .ok_or_else(|| self.invalid(prim, attr, value::show(&v), "expected int[]")),
        }
    }

    /// The interpolation of a primvar (its metadata; `fallback` when unauthored).
    fn interp(&mut self, prim: &sdf::Path, attr: &str, fallback: Interp) -> Result<Interp> {
        let path = prim
            .append_property(attr)
            .map_err(|e| self.read_error(prim, attr, e))?;
        let m = self
            .stage
            .attribute(path)
            .get_metadata::<sdf::Value>("interpolation")
            .map_err(|e| self.read_error(prim, attr, e))?;
        Ok(match m.as_ref().and_then(value::token) {
            None => fallback,
            Some("constant") => Interp::Constant,
            Some("uniform") => Interp::Uniform,
            Some("vertex" | "varying") => Interp::Vertex,
            Some("faceVarying") => Interp::FaceVarying,
            Some(other) => {
                return Err(self.invalid(
                    prim,
                    attr,
                    other,
                    "unknown interpolation (expected constant, uniform, vertex, varying or faceVarying)",
                ));
            }
        })
    }

    /// A primvar's values expanded through its `:indices`, checked against its interpolation.
    fn primvar<T: Copy>(
        &mut self,
        prim: &sdf::Path,
        attr: &str,
        values: Vec<T>,
        (faces, points, corners): (usize, usize, usize),
    ) -> Result<Primvar<T>> {
        // Normals are per vertex unless said otherwise; primvars are constant.
        let fallback = if attr == "normals" || attr == "primvars:normals" {
            Interp::Vertex
        } else {
            Interp::Constant
        };
        let interp = self.interp(prim, attr, fallback)?;
        let index_attr = format!("{attr}:indices");
        let values = match self.ints(prim, &index_attr)? {
            None => values,
            Some(idx) => {
                self.check_indices(prim, &index_attr, &idx, values.len(), "values")?;
                idx.iter().map(|&i| values[i as usize]).collect()
            }
        };
        let need = match interp {
            Interp::Constant => 1,
            Interp::Uniform => faces,
            Interp::Vertex => points,
            Interp::FaceVarying => corners,
        };
        if values.len() != need {
            return Err(self.invalid(
                prim,
                attr,
                format!("{} values", values.len()),
                &format!("its interpolation needs {need}"),
            ));
        }
        Ok(Primvar { values, interp })
    }

    /// The primvar `prim.attr` with values of N numbers (`parse` reads them), finite.
    fn primvar_n<const N: usize>(
        &mut self,
        prim: &sdf::Path,
        attr: &str,
        parse: fn(&sdf::Value) -> Option<Vec<[f64; N]>>,
        sizes: (usize, usize, usize),
    ) -> Result<Option<Primvar<[f64; N]>>> {
        let Some(v) = self.attr(prim, attr)? else {
            return Ok(None);
        };
        let Some(values) = parse(&v) else {
            let expected = format!("expected an array of {N}-vectors");
            return Err(self.invalid(prim, attr, value::show(&v), &expected));
        };
        if let Some(n) = values.iter().find(|n| !n.iter().all(|c| c.is_finite())) {
            return Err(self.invalid(prim, attr, format!("{n:?}"), "must be finite"));
        }
        Ok(Some(self.primvar(prim, attr, values, sizes)?))
    }

    /// The uniform scale of a similarity transform (rotation, uniform scale, translation), or an
    /// error naming what `what` would need instead.
    pub(super) fn uniform_scale(&self, prim: &sdf::Path, world: DMat4, what: &str) -> Result<f64> {
        let axes = [world.x_axis, world.y_axis, world.z_axis].map(|a| a.truncate());
        let lengths = axes.map(DVec3::length);
        let s = lengths[0];
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        let orthogonal = (0..3).all(|i| {
            let (a, b) = (axes[i], axes[(i + 1) % 3]);
            a.dot(b).abs() <= 1e-9 * a.length() * b.length()
        });
        if !(lengths.iter().all(|&l| close(l, s)) && orthogonal && s > 0.0) {
            return Err(self.unsupported(
                prim,
                "xformOpOrder",
                format!("the world transform scales unevenly (axis lengths {lengths:?}): {what}"),
            ));
        }
        Ok(s)
    }

    fn sphere(&mut self, prim: &sdf::Path, at: &Place) -> Result<()> {
        let world = at.world;
        let radius = self.number(prim, "radius", 1.0)?;
        let s = self.uniform_scale(
            prim,
            world,
            "illum traces exact spheres; author an ellipsoid as a Mesh",
        )?;
        let center = world.transform_point3(DVec3::ZERO);
        self.add_shape(
            prim,
            at,
            ShapeDef {
                sphere: Some(SphereDef {
                    center: center.to_array(),
                    radius: radius * s,
                }),
                ..Default::default()
            },
        )
    }

    /// A cube of edge `size` centred on the origin: 6 faces of 2 triangles, outward.
    fn cube(&mut self, prim: &sdf::Path, at: &Place) -> Result<()> {
        let h = self.number(prim, "size", 2.0)? / 2.0;
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut indices = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let n =
                    DVec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
                // u × v = n, so the corners below wind counter-clockwise seen from outside.
                let u = DVec3::from_array(std::array::from_fn(|i| {
                    if i == (axis + 1) % 3 { 1.0 } else { 0.0 }
                })) * sign;
                let v = n.cross(u);
                let base = positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    positions.push(((n + u * a + v * b) * h).to_array());
                    normals.push(n.to_array());
                }
                indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
            }
        }
        let mesh = MeshDef {
            positions,
            indices: Some(indices),
            normals: Some(normals),
            ..Default::default()
        };
        self.mesh_shape(prim, at, |_, _| Ok(Some(mesh)))
    }

    /// A Cylinder, Cone or Capsule (or the `_1` schemas with a top and a bottom radius) as a
    /// mesh (src/scene/usd/quadric.rs), with UsdGeom's defaults.
    fn quadric(&mut self, prim: &sdf::Path, kind: &str, at: &Place) -> Result<()> {
        let axis_token = self.token(prim, "axis", "Z")?;
        let axis = super::quadric::frame(&axis_token)
            .ok_or_else(|| self.invalid(prim, "axis", &axis_token, "expected X, Y or Z"))?;
        let (radius, height) = match kind {
            "Capsule" | "Capsule_1" => (0.5, 1.0),
            _ => (1.0, 2.0),
        };
        let height = self.number(prim, "height", height)?;
        let (bottom, top) = match kind {
            "Cylinder_1" | "Capsule_1" => (
                self.number(prim, "radiusBottom", radius)?,
                self.number(prim, "radiusTop", radius)?,
            ),
            _ => {
                let r = self.number(prim, "radius", radius)?;
                (r, if kind == "Cone" { 0.0 } else { r })
            }
        };
        for (attr, v) in [("height", height), ("radius", bottom), ("radius", top)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(self.invalid(prim, attr, v, "expected a finite value >= 0"));
            }
        }
        let mesh = if kind.starts_with("Capsule") {
            if bottom != top {
                return Err(self.invalid(
                    prim,
                    "radiusTop",
                    top,
                    "a capsule with unequal radii is not rendered (author it as a Mesh)",
                ));
            }
            super::quadric::capsule(bottom, height, axis)
        } else {
            super::quadric::frustum(bottom, top, height, axis)
        };
        self.mesh_shape(prim, at, |_, _| Ok(Some(mesh)))
    }

    /// A `width` × `length` rectangle facing +`axis`: 2 triangles.
    fn plane(&mut self, prim: &sdf::Path, at: &Place) -> Result<()> {
        let w = self.number(prim, "width", 2.0)? / 2.0;
        let l = self.number(prim, "length", 2.0)? / 2.0;
        // (width axis, length axis, normal) per UsdGeomPlane's `axis`.
        let (u, v, n) = match self.token(prim, "axis", "Z")?.as_str() {
            "X" => (DVec3::Z, DVec3::Y, DVec3::X),
            "Y" => (DVec3::X, DVec3::Z, DVec3::Y),
            "Z" => (DVec3::X, DVec3::Y, DVec3::Z),
            other => return Err(self.invalid(prim, "axis", other, "expected X, Y or Z")),
        };
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        let positions = corners
            .map(|(a, b)| (u * a * w + v * b * l).to_array())
            .to_vec();
        // Counter-clockwise about n: flip when u × v points against it.
        let indices = if u.cross(v).dot(n) > 0.0 {
            vec![0, 1, 2, 0, 2, 3]
        } else {
            vec![0, 2, 1, 0, 3, 2]
        };
        let mesh = MeshDef {
            positions,
            indices: Some(indices),
            normals: Some(vec![n.to_array(); 4]),
            ..Default::default()
        };
        self.mesh_shape(prim, at, |_, _| Ok(Some(mesh)))
    }
}
