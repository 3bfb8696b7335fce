//! The scene encoded for the device on the host, one table at a time: meshes, instances,
//! analytic shapes, lights (the scene's, then emissive geometry), materials and textures, and the
//! structures over the lights. Positions become camera-relative here, in double precision.

use super::{Host, MeshRange, dome, dome_sh, light_mean, light_tree, lights, v4};
use crate::error::Result;
use crate::layout::*;
use crate::scene::{
    Distribution, DomeConvention, Fresnel, Light, LightKind, Material, Scene, ShapeGeometry,
    TextureFilter, TextureWrap,
};
use glam::{DMat3, DMat4, DVec3, Vec3};

/// Encodes `scene` relative to `origin`. Without `geometry`, mesh vertices, positions and indices
/// are left out (an update compares positions and indices with the scene directly). Texels are
/// never copied: they are uploaded from the scene's textures.
pub(super) fn encode_scene(scene: &Scene, origin: DVec3, geometry: bool) -> Result<Host> {
    let meshes = encode_meshes(scene, geometry);
    let instances = encode_instances(scene, origin, &meshes.ranges);
    // Analytic shapes: scene geometry first, then the visible surfaces of area lights.
    let mut shapes = encode_shapes(scene, origin);
    let mut shape_masks = vec![MASK_GEOMETRY; shapes.len()];
    let scene_lights = encode_lights(scene, origin, &mut shapes, &mut shape_masks);
    let mut lights = scene_lights.lights;
    let emissive_features = add_emissive_shapes(scene, origin, &mut shapes, &mut lights)
        | add_emissive_triangles(scene, origin, &mut lights);
    let materials = scene.materials.iter().map(material).collect();
    let textures = encode_textures(scene);
    light_mean::set_means(&mut lights, &scene.textures);
    let aabbs = shapes.iter().map(shape_aabb).collect();
    let light_bvh = lights::build(&lights);
    let many_lights = lights.len() > LIGHT_TREE_MIN_LIGHTS as usize;
    let light_tree = if many_lights {
        let mean_texel = |t: u32| light_tree::texture_mean(&scene.textures[t as usize]);
        light_tree::build(&lights, &mean_texel)?
    } else {
        None
    };
    let features = scene_lights.features
        | emissive_features
        | feature(!instances.trace.is_empty(), FEATURE_MESHES)
        | feature(!shapes.is_empty(), FEATURE_SHAPES)
        // No mesh and few shapes: every ray tests every shape, each culled by its box
        // (trace/bvh.glsl, bvh_flat), which on lavapipe costs less than walking the BVH's nodes
        // (docs/performance-kernels.md, "Flat shapes").
        | feature(
            instances.trace.is_empty()
                && !shapes.is_empty()
                && shapes.len() <= BVH_FLAT_MAX as usize
                && shapes.iter().all(|s| s.kind <= SHAPE_DISK),
            FEATURE_FLAT_SHAPES,
        )
        | feature(!textures.is_empty(), FEATURE_TEXTURES)
        | feature(many_lights, FEATURE_MANY_LIGHTS)
        | feature(
            scene.materials.iter().any(|m| {
                m.specular
                    .iter()
                    .take(2)
                    .any(|l| l.distribution == Distribution::GgxSmith)
            }),
            FEATURE_GGX,
        )
        | feature(
            dome_shaped(scene, scene_lights.dome_source),
            FEATURE_DOME_SHAPED,
        );
    Ok(Host {
        features,
        vertices: meshes.vertices,
        positions: meshes.positions,
        indices: meshes.indices,
        meshes: meshes.ranges,
        gpu_instances: instances.device,
        instances: instances.trace,
        shapes,
        shape_masks,
        aabbs,
        lights,
        materials,
        textures,
        dark_lights: scene_lights.dark_lights,
        dome: scene_lights.dome,
        light_bvh,
        light_tree,
        dome_table: dome_table(scene, scene_lights.dome_source),
    })
}

fn feature(on: bool, bit: u32) -> u32 {
    if on { bit } else { 0 }
}

/// The meshes in one shared vertex and index buffer.
struct Meshes {
    vertices: Vec<GpuVertex>,
    positions: Vec<Vec3>,
    indices: Vec<u32>,
    ranges: Vec<MeshRange>,
}

fn encode_meshes(scene: &Scene, geometry: bool) -> Meshes {
    let mut vertices = Vec::new();
    let mut positions = Vec::new();
    let (mut first_vertex_next, mut first_index_next) = (0u32, 0u32);
    let mut indices = Vec::new();
    let mut ranges = Vec::new();
    for m in &scene.meshes {
        let first_vertex = first_vertex_next;
        first_vertex_next += m.positions.len() as u32;
        if geometry {
            positions.extend_from_slice(&m.positions);
        }
        for (i, p) in m.positions.iter().enumerate().filter(|_| geometry) {
            let n = m.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]);
            let uv = m.uvs.as_ref().map_or(glam::Vec2::ZERO, |u| u[i]);
            let t = m.tangents.as_ref().map_or(glam::Vec4::ZERO, |t| t[i]);
            vertices.push(GpuVertex {
                position: p.to_array(),
                u: uv.x,
                normal: n.to_array(),
                v: uv.y,
                tangent: t.to_array(),
            });
        }
        ranges.push(MeshRange {
            first_vertex,
            vertex_count: m.positions.len() as u32,
            first_index: first_index_next,
            triangle_count: (m.indices.len() / 3) as u32,
        });
        if geometry {
            indices.extend_from_slice(&m.indices);
        }
        first_index_next += m.indices.len() as u32;
    }
    Meshes {
        vertices,
        positions,
        indices,
        ranges,
    }
}

/// The mesh instances, camera-relative.
struct Instances {
    /// As the kernels read them.
    device: Vec<GpuInstance>,
    /// (mesh, rows of the object-to-world matrix), for the trace structures.
    trace: Vec<(u32, [[f32; 4]; 3])>,
}

fn encode_instances(scene: &Scene, origin: DVec3, ranges: &[MeshRange]) -> Instances {
    let mut gpu_instances = Vec::new();
    let mut instances = Vec::new();
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh as usize];
        let range = ranges[inst.mesh as usize];
        let rel = DMat4::from_translation(-origin) * inst.transform;
        let mut flags = 0;
        if mesh.normals.is_some() {
            flags |= INSTANCE_FLAG_NORMALS;
        }
        if mesh.uvs.is_some() {
            flags |= INSTANCE_FLAG_UVS;
        }
        if mesh.tangents.is_some() {
            flags |= INSTANCE_FLAG_TANGENTS;
        }
        gpu_instances.push(GpuInstance {
            object_to_world: rows3x4(&rel),
            normal_to_world: normal_rows(&rel),
            first_index: range.first_index,
            first_vertex: range.first_vertex,
            material: mesh.material,
            flags,
        });
        instances.push((inst.mesh, rows3x4(&rel)));
    }
    Instances {
        device: gpu_instances,
        trace: instances,
    }
}

fn shape(g: &ShapeGeometry, origin: DVec3, material: u32, light: u32) -> GpuShape {
    let e = encode(g, origin);
    GpuShape {
        p0: e.p0,
        p1: [e.p1[0], e.p1[1], e.p1[2], 0.0],
        p2: e.p2,
        kind: e.shape_kind,
        material,
        light,
        ..Default::default()
    }
}

/// The scene's analytic shapes.
fn encode_shapes(scene: &Scene, origin: DVec3) -> Vec<GpuShape> {
    scene
        .shapes
        .iter()
        .map(|s| {
            let mut g = shape(&s.geometry, origin, s.material, NONE);
            if let Some(pole) = s.pole {
                g.p1 = v4(pole, 0.0);
                g.flags |= SHAPE_FLAG_POLE;
            }
            g
        })
        .collect()
}

/// The scene's own lights on the device (emissive geometry comes after them).
struct SceneLights {
    lights: Vec<GpuLight>,
    /// The kernels' feature bits of their kinds.
    features: u32,
    /// The device index of the dome, or NONE.
    dome: u32,
    /// The dome's scene index and map convention.
    dome_source: Option<(usize, DomeConvention)>,
    dark_lights: Vec<String>,
}

/// The scene's lights, and the shapes of their surfaces that rays see (appended to `shapes`,
/// with their ray masks).
fn encode_lights(
    scene: &Scene,
    origin: DVec3,
    shapes: &mut Vec<GpuShape>,
    shape_masks: &mut Vec<u32>,
) -> SceneLights {
    let mut out = SceneLights {
        lights: Vec::new(),
        features: 0,
        dome: NONE,
        dome_source: None,
        dark_lights: Vec::new(),
    };
    for (i, l) in scene.lights.iter().enumerate() {
        // A light that emits nothing is left out: sampling it would waste samples.
        if l.emits_nothing() {
            out.dark_lights.push(l.name.clone());
            continue;
        }
        let index = out.lights.len() as u32;
        let (mut g, feature) = light(l, origin);
        out.features |= feature;
        if let LightKind::Dome { convention, .. } = &l.kind {
            out.dome = index;
            out.dome_source = Some((i, *convention));
        }
        // The light's surface: seen by camera rays when visible, by shadow rays when it
        // casts shadows (an opaque object, the default).
        let mask = if l.visible { MASK_LIGHTS } else { 0 }
            | if l.shadows { MASK_LIGHT_SHADOWS } else { 0 };
        if let (Some(geom), true) = (l.kind.surface(), mask != 0) {
            g.shape = shapes.len() as u32;
            shapes.push(shape(&geom, origin, NONE, index));
            shape_masks.push(mask);
        }
        out.lights.push(g);
    }
    out
}

/// One light of the scene, and the feature bit of its kind.
fn light(l: &Light, origin: DVec3) -> (GpuLight, u32) {
    let mut g = GpuLight {
        radiance: v3(l.radiance()),
        texture: l.texture.unwrap_or(NONE),
        shape: NONE,
        flags: if l.two_sided { LIGHT_FLAG_TWO_SIDED } else { 0 }
            | if l.visible { LIGHT_FLAG_VISIBLE } else { 0 },
        ..Default::default()
    };
    let mut feature = 0;
    if let Some(geom) = &l.kind.surface() {
        let e = encode(geom, origin);
        (g.kind, g.p0, g.p1, g.p2, g.area) = (e.light_kind, e.p0, e.p1, e.p2, e.area);
        feature |= e.light_feature;
    }
    match &l.kind {
        LightKind::Rect { .. } | LightKind::Disk { .. } | LightKind::Sphere { .. } => {}
        LightKind::Dome {
            rotation_deg,
            convention,
        } => {
            let r = rotation_deg.to_radians();
            g.kind = LIGHT_DOME;
            g.flags |= match convention {
                DomeConvention::Illum => 0,
                DomeConvention::Mitsuba => LIGHT_FLAG_DOME_MITSUBA,
                DomeConvention::Pbrt => LIGHT_FLAG_DOME_PBRT,
            };
            g.p0 = [r.cos() as f32, r.sin() as f32, 0.0, 0.0];
            feature |= FEATURE_DOME;
        }
        LightKind::Sun {
            direction,
            angular_diameter_deg,
        } => {
            let half = (angular_diameter_deg * 0.5).to_radians();
            // 1 - cos(theta) = 2 sin^2(theta / 2): no cancellation for tiny suns.
            let om = 2.0 * (half * 0.5).sin().powi(2);
            g.kind = LIGHT_SUN;
            g.p0 = v4(direction.normalize(), half.cos());
            g.p1 = [om as f32, 0.0, 0.0];
            feature |= FEATURE_SUN;
        }
    }
    (g, feature)
}

/// Material `m` when it emits.
fn emissive(scene: &Scene, m: u32) -> Option<&Material> {
    let m = &scene.materials[m as usize];
    (m.emission.max_element() > 0.0).then_some(m)
}

/// Emissive geometry is light too: emissive shapes become lights of their own kind. Returns the
/// feature bits of those kinds.
fn add_emissive_shapes(
    scene: &Scene,
    origin: DVec3,
    shapes: &mut [GpuShape],
    lights: &mut Vec<GpuLight>,
) -> u32 {
    let mut features = 0;
    for (si, s) in scene.shapes.iter().enumerate() {
        let Some(m) = emissive(scene, s.material) else {
            continue;
        };
        let mut g = GpuLight {
            radiance: v3(m.emission),
            texture: m.emission_texture.unwrap_or(NONE),
            shape: si as u32,
            flags: LIGHT_FLAG_GEOMETRY | if m.two_sided { LIGHT_FLAG_TWO_SIDED } else { 0 },
            ..Default::default()
        };
        let e = encode(&s.geometry, origin);
        (g.kind, g.p0, g.p1, g.p2, g.area) = (e.light_kind, e.p0, e.p1, e.p2, e.area);
        shapes[si].light = lights.len() as u32;
        lights.push(g);
        features |= e.light_feature;
    }
    features
}

/// Every triangle of an emissive mesh instance becomes a triangle light. Returns
/// FEATURE_TRIANGLE_LIGHTS if there is one.
fn add_emissive_triangles(scene: &Scene, origin: DVec3, lights: &mut Vec<GpuLight>) -> u32 {
    let mut features = 0;
    for (ii, inst) in scene.instances.iter().enumerate() {
        let mesh = &scene.meshes[inst.mesh as usize];
        let Some(m) = emissive(scene, mesh.material) else {
            continue;
        };
        let rel = DMat4::from_translation(-origin) * inst.transform;
        let world = |i: u32| rel.transform_point3(mesh.positions[i as usize].as_dvec3());
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let (a, b, c) = (world(tri[0]), world(tri[1]), world(tri[2]));
            let area = 0.5 * (b - a).cross(c - a).length();
            if (area as f32) <= 0.0 {
                continue; // degenerate: emits nothing
            }
            lights.push(GpuLight {
                p0: v4(a, 0.0),
                p1: d3(b - a),
                triangle: t as u32,
                p2: v4(c - a, 0.0),
                radiance: v3(m.emission),
                kind: LIGHT_TRIANGLE,
                texture: m.emission_texture.unwrap_or(NONE),
                shape: ii as u32,
                flags: LIGHT_FLAG_GEOMETRY | if m.two_sided { LIGHT_FLAG_TWO_SIDED } else { 0 },
                area: area as f32,
                mean: light_mean::triangle_light_mean(scene, mesh, tri, m),
                ..Default::default()
            });
            features |= FEATURE_TRIANGLE_LIGHTS;
        }
    }
    features
}

fn material(m: &Material) -> GpuMaterial {
    let mut g = GpuMaterial {
        diffuse: v3(m.diffuse),
        diffuse_texture: m.diffuse_texture.unwrap_or(NONE),
        emission: v3(m.emission),
        emission_texture: m.emission_texture.unwrap_or(NONE),
        tangent_dir: v3(m.tangent_direction.unwrap_or(Vec3::ZERO)),
        flags: if m.two_sided {
            MATERIAL_FLAG_TWO_SIDED
        } else {
            0
        } | if m.tangent_direction.is_some() {
            MATERIAL_FLAG_TANGENT_DIR
        } else {
            0
        } | if m.metallic_roughness.is_some() {
            MATERIAL_FLAG_METALLIC_ROUGHNESS
        } else {
            0
        },
        lobe_count: m.specular.len().min(2) as u32,
        metallic_roughness_texture: m.metallic_roughness_texture.unwrap_or(NONE),
        roughness: m.metallic_roughness.map_or(0.0, |mr| mr.roughness),
        dielectric_f0: m.metallic_roughness.map_or(0.0, |mr| mr.dielectric_f0),
        base_metallic: m
            .metallic_roughness
            .map_or([0.0; 4], |mr| mr.base_color.extend(mr.metallic).to_array()),
        ..Default::default()
    };
    for (i, l) in m.specular.iter().take(2).enumerate() {
        g.lobes[i] = lobe(l);
    }
    g
}

/// The textures' headers; their texels are uploaded from the scene, one after the other
/// (`update::Tables::upload`), each at the offset its header gives.
fn encode_textures(scene: &Scene) -> Vec<GpuTexture> {
    let mut offset = 0usize;
    let wrap = |w: TextureWrap| match w {
        TextureWrap::Repeat => TEXTURE_WRAP_REPEAT,
        TextureWrap::Clamp => TEXTURE_WRAP_CLAMP,
        TextureWrap::Mirror => TEXTURE_WRAP_MIRROR,
    };
    let mut textures = Vec::with_capacity(scene.textures.len());
    for t in &scene.textures {
        textures.push(GpuTexture {
            offset: offset as u32,
            width: t.width,
            height: t.height,
            flags: if t.filter == TextureFilter::Nearest {
                TEXTURE_FLAG_NEAREST
            } else {
                0
            } | wrap(t.wrap[0]) << TEXTURE_WRAP_SHIFT_U
                | wrap(t.wrap[1]) << TEXTURE_WRAP_SHIFT_V,
        });
        offset += t.texels.len();
    }
    textures
}

/// Whether the scene's dome is textured with a lookup that varies inside its sampling cells (the
/// kernels then hold the cells' shaped densities). Fixed by the texture and the convention, not
/// by the light's colour, so that an edit of its colour keeps the kernels.
fn dome_shaped(scene: &Scene, dome_source: Option<(usize, DomeConvention)>) -> bool {
    dome_source.is_some_and(|(i, convention)| {
        scene.lights[i].texture.is_some_and(|t| {
            dome::cell_shape(convention, scene.textures[t as usize].filter) != DOME_SHAPE_UNIFORM
        })
    })
}

/// Importance-sampling tables of a textured dome (a constant dome has none: it samples the
/// cosine about the shading normal).
fn dome_table(
    scene: &Scene,
    dome_source: Option<(usize, DomeConvention)>,
) -> Option<dome::DomeTable> {
    let (i, convention) = dome_source?;
    let l = &scene.lights[i];
    l.texture.map(|t| {
        let texture = &scene.textures[t as usize];
        let mut table = dome_sh::table(texture, l, convention);
        // As encode_textures lays the texels out: one texture after the other. A Mitsuba
        // cell's corners are two texel rows, which a one-row map lacks (its lookup clamps).
        table.texel_offset =
            (convention != DomeConvention::Mitsuba || texture.height >= 2).then(|| {
                scene.textures[..t as usize]
                    .iter()
                    .map(|x| x.texels.len() as u64)
                    .sum()
            });
        table
    })
}

fn v3(v: Vec3) -> [f32; 3] {
    v.to_array()
}
fn d3(v: DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

fn rows3x4(m: &DMat4) -> [[f32; 4]; 3] {
    let r = |i: usize| {
        let row = m.row(i);
        [row.x as f32, row.y as f32, row.z as f32, row.w as f32]
    };
    [r(0), r(1), r(2)]
}

fn normal_rows(m: &DMat4) -> [[f32; 4]; 3] {
    let n = DMat3::from_mat4(*m).inverse().transpose();
    let r = |i: usize| {
        let row = n.row(i);
        [row.x as f32, row.y as f32, row.z as f32, 0.0]
    };
    [r(0), r(1), r(2)]
}

/// Any unit vector perpendicular to `n`.
fn perpendicular(n: DVec3) -> DVec3 {
    n.any_orthonormal_vector()
}

fn lobe(l: &crate::scene::SpecularLobe) -> GpuLobe {
    let (fresnel, f0, f1) = match l.fresnel {
        Fresnel::Constant(c) => (FRESNEL_CONSTANT, c, Vec3::ZERO),
        Fresnel::Schlick { f0 } => (FRESNEL_SCHLICK, f0, Vec3::ZERO),
        Fresnel::Conductor { eta, k } => (FRESNEL_CONDUCTOR, eta, k),
    };
    GpuLobe {
        fresnel0: f0.extend(0.0).to_array(),
        fresnel1: f1.extend(0.0).to_array(),
        // Mitsuba 3's floor of 1e-4, where the lobe is still exact in float32; zero along both
        // axes is a perfect mirror (a delta lobe, glsl/scene/microfacet.glsl).
        alpha: if l.alpha == glam::Vec2::ZERO {
            [0.0; 2]
        } else {
            l.alpha.max(glam::Vec2::splat(1e-4)).to_array()
        },
        distribution: match l.distribution {
            Distribution::DBrdf => DIST_DBRDF,
            Distribution::BeckmannSmith => DIST_BECKMANN_SMITH,
            Distribution::GgxSmith => DIST_GGX_SMITH,
        },
        fresnel,
    }
}

fn shape_aabb(s: &GpuShape) -> [f32; 6] {
    let c = Vec3::from_slice(&s.p0[..3]);
    let ext = match s.kind {
        SHAPE_SPHERE => Vec3::splat(s.p0[3]),
        SHAPE_RECT => {
            (Vec3::from_slice(&s.p1[..3]).abs() + Vec3::from_slice(&s.p2[..3]).abs()) * 0.5
        }
        _ => {
            // Disk: per axis, r * sqrt(1 - n_i^2).
            let n = Vec3::from_slice(&s.p1[..3]);
            (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5) * s.p0[3]
        }
    };
    // Pad by a relative epsilon so that flat shapes have volume and rounding never clips a hit.
    let pad = ext * 1e-4 + (c.abs() + ext) * 1e-6 + Vec3::splat(1e-7);
    let lo = c - ext - pad;
    let hi = c + ext + pad;
    [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]
}

/// The device encoding of an analytic shape's geometry, camera-relative: the one place where a
/// sphere, rect or disk becomes p0/p1/p2 (glsl/shared/layout.glsl), for scene shapes, area lights,
/// their visible surfaces and emissive shapes alike.
struct Encoded {
    shape_kind: u32,
    light_kind: u32,
    /// The kernels' feature bit of that light kind: a kernel holds the samplers of its kinds.
    light_feature: u32,
    p0: [f32; 4],
    p1: [f32; 3],
    p2: [f32; 4],
    area: f32,
}

fn encode(g: &ShapeGeometry, origin: DVec3) -> Encoded {
    use std::f64::consts::PI;
    match *g {
        ShapeGeometry::Sphere { center, radius } => {
            let dist = (center - origin).length();
            Encoded {
                shape_kind: SHAPE_SPHERE,
                light_kind: LIGHT_SPHERE,
                light_feature: FEATURE_SPHERE_LIGHTS,
                p0: v4(center - origin, radius),
                p1: [0.0; 3],
                // The origin's signed distance to the surface and to the centre, in double precision:
                // intersect_sphere's exact start (glsl/trace/shapes.glsl).
                p2: [(dist - radius) as f32, dist as f32, 0.0, 0.0],
                area: (4.0 * PI * radius * radius) as f32,
            }
        }
        ShapeGeometry::Rect { center, u, v } => Encoded {
            shape_kind: SHAPE_RECT,
            light_kind: LIGHT_RECT,
            light_feature: FEATURE_RECT_LIGHTS,
            p0: v4(center - origin, 0.0),
            p1: d3(u),
            p2: v4(v, 0.0),
            area: u.cross(v).length() as f32,
        },
        ShapeGeometry::Disk {
            center,
            normal,
            radius,
        } => {
            let n = normal.normalize();
            Encoded {
                shape_kind: SHAPE_DISK,
                light_kind: LIGHT_DISK,
                light_feature: FEATURE_DISK_LIGHTS,
                p0: v4(center - origin, radius),
                p1: d3(n),
                p2: v4(perpendicular(n), 0.0),
                area: (PI * radius * radius) as f32,
            }
        }
    }
}

#[cfg(test)]
#[path = "encode_tests.rs"]
mod tests;
