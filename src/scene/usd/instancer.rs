//! `UsdGeomPointInstancer`: instance i of prototype `protoIndices[i]` is placed by the
//! instancer's world transform × T(positions[i]) · R(orientations[i]) · S(scales[i]) × the
//! prototype's own transform, as pxr's `ComputeInstanceTransformsAtTime` composes them. Each
//! prototype's meshes are converted once per material and placed again by every instance.

use super::geom::Place;
use super::{Reader, Result, value};
use glam::{DMat4, DQuat, DVec3};
use openusd::sdf::{self, Value};
use std::collections::HashSet;

/// A gprim of a prototype: its path, type and transform relative to the instance.
struct Part {
    path: sdf::Path,
    kind: String,
    transform: DMat4,
}

impl Reader {
    /// The instancer's `inactiveIds` (prim metadata, an int64 list op): each layer's opinion
    /// composed from the strongest down, as pxr composes list-op metadata.
    fn inactive_ids(&self, prim: &sdf::Path) -> Result<Vec<i64>> {
        let field = "inactiveIds";
        let stack = self
            .stage
            .prim(prim.clone())
            .prim_stack()
            .map_err(|e| self.read_error(prim, field, e))?;
        let mut composed: Option<sdf::Int64ListOp> = None;
        for (layer, spec) in stack {
            let Some(layer) = self.stage.layer(&layer) else {
                continue;
            };
            let value = layer
                .data()
                .try_field(&spec, field)
                .map_err(|e| self.read_error(prim, field, e))?;
            let Some(value) = value else {
                continue;
            };
            let Value::Int64ListOp(op) = value.as_ref() else {
                return Err(self.invalid(
                    prim,
                    field,
                    value::show(value.as_ref()),
                    "expected an int64 list op",
                ));
            };
            composed = Some(match composed {
                None => op.clone(),
                Some(stronger) => stronger.combined_with(op),
            });
        }
        Ok(composed.map(|op| op.flatten()).unwrap_or_default())
    }

    pub(super) fn point_instancer(&mut self, prim: &sdf::Path, world: DMat4) -> Result<()> {
        // The prototypes are read from here, not as prims of their own.
        self.pruned.insert(prim.clone());
        let protos = self.targets(prim, "prototypes")?;
        let (Some(indices), Some(positions)) = (
            self.ints(prim, "protoIndices")?,
            self.vec3s(prim, "positions")?,
        ) else {
            self.warn(
                prim,
                "",
                "a PointInstancer without protoIndices and positions: nothing to render",
            );
            return Ok(());
        };
        let n = indices.len();
        if positions.len() != n {
            return Err(self.invalid(
                prim,
                "positions",
                format!("{} values", positions.len()),
                &format!("protoIndices has {n}"),
            ));
        }
        self.check_indices(prim, "protoIndices", &indices, protos.len(), "prototypes")?;
        let orientations = self.quats(prim, n)?;
        let scales = match self.vec3s(prim, "scales")? {
            Some(s) if s.len() != n => {
                return Err(self.invalid(
                    prim,
                    "scales",
                    format!("{} values", s.len()),
                    &format!("protoIndices has {n}"),
                ));
            }
            s => s,
        };
        let ids = self.ints(prim, "ids")?;
        let mut hidden: HashSet<i64> = self
            .ints(prim, "invisibleIds")?
            .unwrap_or_default()
            .into_iter()
            .collect();
        hidden.extend(self.inactive_ids(prim)?);
        let mut parts = Vec::with_capacity(protos.len());
        for proto in &protos {
            let mut found = Vec::new();
            self.prototype_parts(proto, DMat4::IDENTITY, &mut found)?;
            parts.push(found);
        }
        for (i, &proto) in indices.iter().enumerate() {
            let id = ids
                .as_ref()
                .and_then(|ids| ids.get(i).copied())
                .unwrap_or(i as i64);
            if hidden.contains(&id) {
                continue;
            }
            let p = positions[i];
            if !p.iter().all(|c| c.is_finite()) {
                return Err(self.invalid(prim, "positions", format!("{p:?}"), "must be finite"));
            }
            let r = orientations.as_ref().map_or(DQuat::IDENTITY, |o| o[i]);
            let s = scales.as_ref().map_or(DVec3::ONE, |s| DVec3::from(s[i]));
            let instance = world * DMat4::from_scale_rotation_translation(s, r, DVec3::from(p));
            for part in &parts[proto as usize] {
                let at = Place {
                    name: format!("{}[{i}]{}", prim.as_str(), part.path.as_str()),
                    world: instance * part.transform,
                    share: Some(part.path.as_str().to_string()),
                };
                let path = part.path.clone();
                let kind = part.kind.clone();
                self.gprim(&path, &kind, &at)?;
            }
        }
        Ok(())
    }

    /// `orientations` (half) or `orientationsf` (float), one per instance, normalized.
    fn quats(&mut self, prim: &sdf::Path, n: usize) -> Result<Option<Vec<DQuat>>> {
        for attr in ["orientations", "orientationsf"] {
            let Some(v) = self.attr(prim, attr)? else {
                continue;
            };
            let q: Vec<[f64; 4]> = match &v {
                Value::QuathVec(a) => a
                    .iter()
                    .map(|q| [q.x, q.y, q.z, q.w].map(|c| f64::from(c.to_f32())))
                    .collect(),
                Value::QuatfVec(a) => a
                    .iter()
                    .map(|q| [q.x, q.y, q.z, q.w].map(f64::from))
                    .collect(),
                Value::QuatdVec(a) => a.iter().map(|q| [q.x, q.y, q.z, q.w]).collect(),
                _ => return Err(self.invalid(prim, attr, value::show(&v), "expected quaternions")),
            };
            if q.len() != n {
                return Err(self.invalid(
                    prim,
                    attr,
                    format!("{} values", q.len()),
                    &format!("protoIndices has {n}"),
                ));
            }
            let mut out = Vec::with_capacity(n);
            for q in q {
                let q = DQuat::from_array(q);
                if !(q.is_finite() && q.length() > 0.0) {
                    return Err(self.invalid(
                        prim,
                        attr,
                        format!("{q:?}"),
                        "must be finite, non-zero quaternions",
                    ));
                }
                out.push(q.normalize());
            }
            return Ok(Some(out));
        }
        Ok(None)
    }

    /// The gprims of the subtree at `prim` (active, visible, not guide or proxy), each with its
    /// transform relative to the instance (`parent` × the prim's own).
    fn prototype_parts(
        &mut self,
        prim: &sdf::Path,
        parent: DMat4,
        out: &mut Vec<Part>,
    ) -> Result<()> {
        let p = self.stage.prim(prim.clone());
        if !p
            .is_active()
            .map_err(|e| self.read_error(prim, "active", e))?
        {
            return Ok(());
        }
        if self.token(prim, "visibility", "inherited")? == "invisible" {
            return Ok(());
        }
        if matches!(
            self.token(prim, "purpose", "default")?.as_str(),
            "guide" | "proxy"
        ) {
            return Ok(());
        }
        let kind = p
            .type_name()
            .map_err(|e| self.read_error(prim, "", e))?
            .map(|t| t.as_str().to_string())
            .unwrap_or_default();
        let (local, _) = self.local_transform(prim)?;
        let transform = parent * local;
        match kind.as_str() {
            "Mesh" | "Sphere" | "Cube" | "Plane" | "Cylinder" | "Cone" | "Capsule"
            | "Cylinder_1" | "Capsule_1" => out.push(Part {
                path: prim.clone(),
                kind,
                transform,
            }),
            "Material" | "Shader" | "NodeGraph" | "GeomSubset" => return Ok(()),
            "" | "Xform" | "Scope" => {}
            other => self.warn(
                prim,
                "",
                format!("{other} in a PointInstancer prototype is not rendered"),
            ),
        }
        let children = p.children().map_err(|e| self.read_error(prim, "", e))?;
        for c in children {
            self.prototype_parts(c.path(), transform, out)?;
        }
        Ok(())
    }
}
