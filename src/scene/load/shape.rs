//! Shapes of a scene file: analytic shapes, inline meshes and glTF files (placed as instances),
//! with their transforms and materials.

use super::*;

impl Builder<'_> {
    pub(super) fn shape(&mut self, name: &str, def: &ShapeDef) -> Result<()> {
        let ctx = self.ctx;
        let f = format!("shapes.{name}");
        let kind = one_of(
            ctx,
            &f,
            &[
                ("sphere", def.sphere.is_some()),
                ("rect", def.rect.is_some()),
                ("disk", def.disk.is_some()),
                ("mesh", def.mesh.is_some()),
                ("gltf", def.gltf.is_some()),
                ("instance", def.instance.is_some()),
            ],
        )?;
        let material = match &def.material {
            Some(_) if kind == "instance" => {
                return Err(SceneError::unsupported(
                    ctx.file,
                    format!("{f}.material"),
                    "an instance takes the material of the shape it places again",
                ));
            }
            Some(m) => Some(self.material_ref(&format!("{f}.material"), m)?),
            None if kind == "gltf" || kind == "instance" => None,
            None => {
                return Err(SceneError::unsupported(
                    ctx.file,
                    format!("{f}.material"),
                    format!("missing: {kind} shapes need a material"),
                ));
            }
        };
        let transform = match &def.transform {
            Some(_) if !matches!(kind, "mesh" | "gltf" | "instance") => {
                return Err(SceneError::unsupported(
                    ctx.file,
                    format!("{f}.transform"),
                    format!(
                        "{kind} shapes take no transform (analytic shapes are given in world \
                         space; only mesh, gltf and instance shapes have one)"
                    ),
                ));
            }
            Some(t) => transform::parse(ctx, &format!("{f}.transform"), t)?,
            None => DMat4::IDENTITY,
        };
        if def.pole.is_some() && kind != "sphere" {
            return Err(SceneError::unsupported(
                ctx.file,
                format!("{f}.pole"),
                format!("{kind} shapes take no pole (it orients a sphere's tangents)"),
            ));
        }
        let pole = def
            .pole
            .map(|p| ctx.direction(&format!("{f}.pole"), p))
            .transpose()?;
        let analytic = |geometry| AnalyticShape {
            name: name.to_owned(),
            geometry,
            material: material.unwrap_or_default(),
            pole,
        };
        if let Some(s) = &def.sphere {
            let (center, radius) = ctx.sphere(&format!("{f}.sphere"), s, false)?;
            self.parts
                .shapes
                .push(analytic(ShapeGeometry::Sphere { center, radius }));
        } else if let Some(r) = &def.rect {
            let (center, u, v) = ctx.rect(&format!("{f}.rect"), r, false)?;
            self.parts
                .shapes
                .push(analytic(ShapeGeometry::Rect { center, u, v }));
        } else if let Some(d) = &def.disk {
            let (center, normal, radius) = ctx.disk(&format!("{f}.disk"), d, false)?;
            self.parts.shapes.push(analytic(ShapeGeometry::Disk {
                center,
                normal,
                radius,
            }));
        } else if let Some(m) = &def.mesh {
            let mesh = self.mesh(&format!("{f}.mesh"), name, m, material.unwrap_or_default())?;
            let id = self.parts.meshes.len() as u32;
            self.parts.instances.push(MeshInstance {
                mesh: id,
                transform,
                name: name.to_owned(),
            });
            self.parts.meshes.push(mesh);
            self.mesh_ids.insert(name.to_owned(), id);
        } else if let Some(of) = &def.instance {
            let Some(&mesh) = self.mesh_ids.get(of) else {
                return Err(ctx.err(
                    format!("{f}.instance"),
                    quoted(of),
                    "must name an earlier shape with a mesh",
                ));
            };
            self.parts.instances.push(MeshInstance {
                mesh,
                transform,
                name: name.to_owned(),
            });
        } else if let Some(g) = &def.gltf {
            let cameras = gltf_load::load(
                &gltf_load::Request {
                    scene_file: ctx.file,
                    field: &format!("{f}.gltf.file"),
                    base_dir: self.base_dir,
                    file: &g.file,
                    shape: name,
                    transform,
                    material_override: material,
                },
                &mut self.parts,
            )?;
            self.gltf_cameras.insert(name.to_owned(), cameras);
        }
        Ok(())
    }

    fn mesh(&self, f: &str, name: &str, m: &MeshDef, material: MaterialId) -> Result<Mesh> {
        let ctx = self.ctx;
        let n = m.positions.len();
        if n == 0 {
            return Err(ctx.err(format!("{f}.positions"), "[]", "must not be empty"));
        }
        let mut positions = Vec::with_capacity(n);
        for (i, p) in m.positions.iter().enumerate() {
            let v = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
            if !v.is_finite() {
                let field = format!("{f}.positions[{i}]");
                return Err(ctx.err(field, fmt_vec(p), "must be finite (as 32-bit floats)"));
            }
            positions.push(v);
        }
        let per_vertex = |key: &str, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(ctx.err(
                    format!("{f}.{key}"),
                    format!("{len} entries"),
                    &format!("must have one entry per position ({n})"),
                ))
            }
        };
        let normals = match &m.normals {
            None => None,
            Some(normals) => {
                per_vertex("normals", normals.len())?;
                let mut out = Vec::with_capacity(n);
                for (i, v) in normals.iter().enumerate() {
                    let field = || format!("{f}.normals[{i}]");
                    out.push(ctx.direction_of(field, *v)?.as_vec3());
                }
                Some(out)
            }
        };
        let uvs = match &m.uvs {
            None => None,
            Some(uvs) => {
                per_vertex("uvs", uvs.len())?;
                let mut out = Vec::with_capacity(n);
                for (i, uv) in uvs.iter().enumerate() {
                    let v = Vec2::new(uv[0] as f32, uv[1] as f32);
                    if !v.is_finite() {
                        let field = format!("{f}.uvs[{i}]");
                        return Err(ctx.err(field, fmt_vec(uv), "must be finite"));
                    }
                    out.push(v);
                }
                Some(out)
            }
        };
        let tangents = match &m.tangents {
            None => None,
            Some(tangents) => {
                per_vertex("tangents", tangents.len())?;
                let mut out = Vec::with_capacity(n);
                for (i, t) in tangents.iter().enumerate() {
                    let field = || format!("{f}.tangents[{i}]");
                    let xyz = ctx.direction_of(field, [t[0], t[1], t[2]])?.as_vec3();
                    if t[3] != 1.0 && t[3] != -1.0 {
                        return Err(ctx.err(
                            field(),
                            fmt_vec(t),
                            "w (the handedness) must be 1 or -1",
                        ));
                    }
                    out.push(xyz.extend(t[3] as f32));
                }
                Some(out)
            }
        };
        let indices = match &m.indices {
            None if n % 3 != 0 => {
                return Err(ctx.err(
                    format!("{f}.positions"),
                    format!("{n} positions"),
                    "without \"indices\", the number of positions must be a multiple of 3",
                ));
            }
            None => (0..n as u32).collect(),
            Some(idx) => {
                if idx.is_empty() || idx.len() % 3 != 0 {
                    return Err(ctx.err(
                        format!("{f}.indices"),
                        format!("{} indices", idx.len()),
                        "the number of indices must be a non-zero multiple of 3",
                    ));
                }
                if let Some(i) = idx.iter().position(|&i| i as usize >= n) {
                    return Err(ctx.err(
                        format!("{f}.indices[{i}]"),
                        idx[i],
                        &format!("index out of range (the mesh has {n} positions)"),
                    ));
                }
                idx.clone()
            }
        };
        Ok(Mesh {
            name: name.to_owned(),
            positions,
            normals,
            tangents,
            uvs,
            indices,
            material,
        })
    }
}
