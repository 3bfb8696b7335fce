//! Updates of an uploaded scene without a new upload: the edited scene is encoded again on the
//! host (without mesh vertices and texels), and only the tables whose bytes changed are written,
//! in place when their size is the same (else reallocated: the kernels reach every table through
//! the frame constants, which each render writes anew).

use super::{GpuScene, Host};
use crate::error::{Error, Result};
use crate::layout::*;
use crate::scene::Scene;
use crate::vk::{Buffer, Context};
use ash::vk;

/// One table in device memory and the hash of the bytes it holds.
pub(crate) struct Table {
    name: &'static str,
    buffer: Option<Buffer>,
    hash: u64,
}

/// FNV-1a over 8-byte words (the tail zero-padded): a change detector, not a checksum; the
/// word-wise form hashes a dome's half-gigabyte tables in a tenth of the byte-wise time.
fn fnv(parts: &[&[u8]]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for part in parts {
        let mut words = part.chunks_exact(8);
        for w in &mut words {
            h = (h ^ u64::from_le_bytes(w.try_into().unwrap())).wrapping_mul(0x0000_0100_0000_01b3);
        }
        let mut tail = [0u8; 8];
        tail[..words.remainder().len()].copy_from_slice(words.remainder());
        h = (h ^ u64::from_le_bytes(tail)).wrapping_mul(0x0000_0100_0000_01b3);
        h = (h ^ part.len() as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

impl Table {
    fn upload(ctx: &Context, name: &'static str, bytes: &[u8]) -> Result<Table> {
        Table::upload_parts(ctx, name, &[bytes])
    }

    /// The table of `parts` one after the other.
    fn upload_parts(ctx: &Context, name: &'static str, parts: &[&[u8]]) -> Result<Table> {
        let buffer = if parts.iter().all(|p| p.is_empty()) {
            None
        } else {
            Some(ctx.upload_parts(name, parts, vk::BufferUsageFlags::STORAGE_BUFFER)?)
        };
        Ok(Table {
            name,
            buffer,
            hash: fnv(parts),
        })
    }

    /// Writes `parts` (one after the other) if they differ from what the table holds; true if
    /// they did.
    fn update_parts(&mut self, ctx: &Context, parts: &[&[u8]]) -> Result<bool> {
        let hash = fnv(parts);
        if hash == self.hash {
            return Ok(false);
        }
        let size: u64 = parts.iter().map(|p| p.len() as u64).sum();
        match &self.buffer {
            Some(b) if size <= b.size && size > 0 => {
                let mut offset = 0;
                for p in parts {
                    ctx.write(b, offset, p)?;
                    offset += p.len() as u64;
                }
            }
            _ => *self = Table::upload_parts(ctx, self.name, parts)?,
        }
        self.hash = hash;
        Ok(true)
    }

    fn address(&self) -> u64 {
        self.buffer.as_ref().map_or(0, |b| b.address)
    }
}

pub(crate) struct Tables {
    instances: Table,
    materials: Table,
    shapes: Table,
    lights: Table,
    textures: Table,
    texels: Table,
    light_nodes: Table,
    light_refs: Table,
    light_tree: Table,
    light_trails: Table,
    dome_data: Table,
    dome_sampling: Table,
}

fn bytes<T: bytemuck::Pod>(v: &[T]) -> &[u8] {
    bytemuck::cast_slice(v)
}

impl Tables {
    /// The tables of `h`, encoded from `scene` (whose textures' texels are uploaded as they are).
    pub(crate) fn upload(ctx: &Context, h: &Host, scene: &Scene) -> Result<Tables> {
        let dome_data = Table::upload_parts(ctx, "dome CDFs", &dome_parts(h))?;
        let texels = Table::upload_parts(
            ctx,
            "texels",
            &scene
                .textures
                .iter()
                .map(|t| bytes(&t.texels))
                .collect::<Vec<_>>(),
        )?;
        let sampling = dome_sampling(h, &dome_data, &texels);
        Ok(Tables {
            instances: Table::upload(ctx, "instances", bytes(&h.gpu_instances))?,
            materials: Table::upload(ctx, "materials", bytes(&h.materials))?,
            shapes: Table::upload(ctx, "shapes", bytes(&h.shapes))?,
            lights: Table::upload(ctx, "lights", bytes(&h.lights))?,
            textures: Table::upload(ctx, "textures", bytes(&h.textures))?,
            texels,
            light_nodes: Table::upload(ctx, "light BVH nodes", bytes(&h.light_bvh.nodes))?,
            light_refs: Table::upload(ctx, "light BVH references", bytes(&h.light_bvh.refs))?,
            light_tree: Table::upload(ctx, "light tree", bytes(tree_nodes(h)))?,
            light_trails: Table::upload(ctx, "light trails", bytes(tree_trails(h)))?,
            dome_sampling: Table::upload(ctx, "dome sampling", bytes(&sampling))?,
            dome_data,
        })
    }

    /// The counts and addresses of the frame constants.
    pub(crate) fn write_frame(&self, f: &mut Frame, h: &Host) {
        f.light_count = h.lights.len() as u32;
        f.shape_count = h.shapes.len() as u32;
        f.instance_count = h.gpu_instances.len() as u32;
        f.material_count = h.materials.len() as u32;
        f.texture_count = h.textures.len() as u32;
        f.dome_light = h.dome;
        f.instances = self.instances.address();
        f.materials = self.materials.address();
        f.shapes = self.shapes.address();
        f.lights = self.lights.address();
        f.textures = self.textures.address();
        f.texels = self.texels.address();
        f.dome_sampling = self.dome_sampling.address();
        f.light_nodes = self.light_nodes.address();
        f.light_refs = self.light_refs.address();
        f.light_bvh_nodes = h.light_bvh.nodes.len() as u32;
        f.infinite_first = h.light_bvh.infinite_first;
        f.infinite_count = h.light_bvh.infinite_count;
        f.light_tree = self.light_tree.address();
        f.light_trails = self.light_trails.address();
        f.light_tree_nodes = tree_nodes(h).len() as u32;
    }
}

fn dome_parts(h: &Host) -> Vec<&[u8]> {
    h.dome_table
        .as_ref()
        .map_or(Vec::new(), |t| t.parts().to_vec())
}

fn tree_nodes(h: &Host) -> &[GpuLightTreeNode] {
    h.light_tree.as_ref().map_or(&[][..], |t| &t.nodes[..])
}

fn tree_trails(h: &Host) -> &[u32] {
    h.light_tree.as_ref().map_or(&[][..], |t| &t.trails[..])
}

fn dome_sampling(h: &Host, data: &Table, texels: &Table) -> Vec<GpuDomeSampling> {
    h.dome_table
        .as_ref()
        .map(|t| t.gpu(data.address(), texels.address()))
        .into_iter()
        .collect()
}

/// What [`GpuScene::update`] changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneUpdate {
    /// Names of the tables written.
    pub tables: Vec<&'static str>,
    /// Some instance transform changed: the trace structure's top level follows.
    pub instances_moved: bool,
    /// Wall time of the update (set by `PreparedScene::update`).
    pub seconds: f64,
}

/// A digest of what an update does not upload again: texture pixels and mesh vertex attributes
/// (an edit of either is refused rather than silently kept out).
pub(super) fn fixed_data(scene: &Scene) -> [u64; 2] {
    use std::hash::{Hash, Hasher};
    let texels: Vec<&[u8]> = scene.textures.iter().map(|x| bytes(&x.texels)).collect();
    let mut m = std::collections::hash_map::DefaultHasher::new();
    for mesh in &scene.meshes {
        mesh.normals.as_deref().map(bytes).hash(&mut m);
        mesh.tangents.as_deref().map(bytes).hash(&mut m);
        mesh.uvs.as_deref().map(bytes).hash(&mut m);
    }
    [fnv(&texels), m.finish()]
}

impl GpuScene {
    /// Whether `scene`'s mesh positions and indices are those uploaded.
    fn same_meshes(&self, scene: &Scene) -> bool {
        scene.meshes.len() == self.meshes.len()
            && scene.meshes.iter().zip(&self.meshes).all(|(m, r)| {
                let v = r.first_vertex as usize..(r.first_vertex + r.vertex_count) as usize;
                let i =
                    r.first_index as usize..r.first_index as usize + 3 * r.triangle_count as usize;
                self.positions.get(v) == Some(&m.positions[..])
                    && self.indices.get(i) == Some(&m.indices[..])
            })
    }

    /// Brings the uploaded scene to `scene`, an edit of the one it was made from: materials,
    /// lights and instance transforms may change; geometry (mesh positions and indices, analytic
    /// shapes, mesh normals, uvs and tangents), the set of lights that emit and textures (their
    /// sizes and pixels) may not: an error names what changed (prepare the scene again).
    pub fn update(&mut self, ctx: &Context, scene: &Scene) -> Result<SceneUpdate> {
        let h = super::encode_scene(scene, self.origin, false)?;
        let fixed = fixed_data(scene);
        let fixed = [
            ("the set of features", h.features == self.features),
            ("mesh geometry", self.same_meshes(scene)),
            (
                "instances",
                h.instances.len() == self.instances.len()
                    && h.instances
                        .iter()
                        .zip(&self.instances)
                        .all(|(a, b)| a.0 == b.0),
            ),
            (
                "analytic shapes and light surfaces",
                h.aabbs == self.shape_boxes && h.shape_masks == self.shape_masks,
            ),
            ("the lights that emit", h.dark_lights == self.dark_lights),
            (
                "textures",
                h.textures.len() as u32 == self.frame.texture_count,
            ),
            ("texture pixels", fixed[0] == self.fixed_data[0]),
            (
                "mesh normals, uvs and tangents",
                fixed[1] == self.fixed_data[1],
            ),
        ];
        if let Some((what, _)) = fixed.iter().find(|f| !f.1) {
            return Err(Error::Invalid(format!(
                "an update cannot change {what}: prepare the scene again"
            )));
        }
        let t = &mut self.tables;
        let mut written = Vec::new();
        let mut put = |table: &mut Table, parts: &[&[u8]]| -> Result<()> {
            if table.update_parts(ctx, parts)? {
                written.push(table.name);
            }
            Ok(())
        };
        put(&mut t.instances, &[bytes(&h.gpu_instances)])?;
        put(&mut t.materials, &[bytes(&h.materials)])?;
        put(&mut t.shapes, &[bytes(&h.shapes)])?;
        put(&mut t.lights, &[bytes(&h.lights)])?;
        put(&mut t.textures, &[bytes(&h.textures)])?;
        put(&mut t.light_nodes, &[bytes(&h.light_bvh.nodes)])?;
        put(&mut t.light_refs, &[bytes(&h.light_bvh.refs)])?;
        put(&mut t.light_tree, &[bytes(tree_nodes(&h))])?;
        put(&mut t.light_trails, &[bytes(tree_trails(&h))])?;
        put(&mut t.dome_data, &dome_parts(&h))?;
        let sampling = dome_sampling(&h, &t.dome_data, &t.texels);
        put(&mut t.dome_sampling, &[bytes(&sampling)])?;
        let instances_moved = h.instances != self.instances;
        self.tables.write_frame(&mut self.frame, &h);
        self.instances = h.instances;
        self.shapes = h.shapes;
        self.emitters = h.lights.len() as u32;
        Ok(SceneUpdate {
            tables: written,
            instances_moved,
            seconds: 0.0,
        })
    }
}
