//! Scene → GPU buffers: the uploaded scene that the trace structures (src/trace) are built over
//! and the integrators (src/render) read. Below both: nothing here imports either.
//! Positions become camera-relative here, in double precision, before the
//! conversion to f32: a scene 1e5 units from the origin keeps the precision of one at the origin.

pub mod dome;
mod dome_sh;
mod light_mean;
pub mod light_tree;
mod lights;
mod update;
pub use update::SceneUpdate;

use crate::error::Result;
use crate::layout::*;
use crate::scene::{
    Distribution, DomeConvention, Fresnel, LightKind, Scene, ShapeGeometry, TextureFilter,
    TextureWrap,
};
use crate::vk::{Buffer, Context};
use ash::vk;
use glam::{DMat3, DMat4, DVec3, Vec3};

/// Index ranges of one mesh inside the shared vertex and index buffers.
#[derive(Clone, Copy, Debug)]
pub struct MeshRange {
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub triangle_count: u32,
}

/// The scene in device memory, plus what the trace structures need to be built over it.
pub struct GpuScene {
    pub frame: Frame,
    pub features: u32,
    pub meshes: Vec<MeshRange>,
    /// (mesh index, rows of the camera-relative object-to-world matrix) per instance.
    pub instances: Vec<(u32, [[f32; 4]; 3])>,
    pub shapes: Vec<GpuShape>,
    /// Ray mask of each shape (MASK_*): scene geometry first, then the light surfaces.
    pub shape_masks: Vec<u32>,
    /// Boxes of the shapes (lo.xyz, hi.xyz), padded so that rounding never clips a hit.
    pub shape_boxes: Vec<[f32; 6]>,
    /// Camera position in world space: the origin of the render's coordinates.
    pub origin: DVec3,
    /// Names of the scene's lights that emit nothing (zero radiance or area), left out.
    pub dark_lights: Vec<String>,
    /// Lights uploaded, emissive geometry included.
    pub emitters: u32,
    /// Object-space vertex positions and triangle indices of every mesh (the `MeshRange`s index
    /// them as they do the GPU buffers): what the compute BVH is built from on the host.
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    pub vertex_buffer: Option<Buffer>,
    pub index_buffer: Option<Buffer>,
    pub aabb_buffer: Option<Buffer>,
    /// The tables the kernels reach through the frame constants, with what is needed to tell
    /// whether an edited scene changes them (see `update.rs`).
    tables: update::Tables,
}

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
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

/// Writes `cam` into the frame constants of a scene uploaded relative to `origin` (in double
/// precision: the camera may have moved since the upload).
pub fn set_camera(frame: &mut Frame, cam: &crate::scene::Camera, origin: DVec3) {
    let forward = (cam.look_at - cam.position).normalize();
    let right_dir = forward.cross(cam.up).normalize();
    let up_dir = right_dir.cross(forward);
    let tan_half = (cam.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = f64::from(cam.width) / f64::from(cam.height);
    frame.cam_forward = v4(forward, 0.0);
    frame.cam_right = v4(right_dir * tan_half * aspect, 0.0);
    frame.cam_up = v4(up_dir * tan_half, 0.0);
    frame.cam_origin = v4(cam.position - origin, 0.0);
    frame.width = cam.width;
    frame.height = cam.height;
}

/// The scene encoded for the device, on the host: what `GpuScene::new` uploads, and what
/// `GpuScene::update` compares with what it uploaded.
pub(crate) struct Host {
    features: u32,
    vertices: Vec<GpuVertex>,
    positions: Vec<Vec3>,
    indices: Vec<u32>,
    meshes: Vec<MeshRange>,
    gpu_instances: Vec<GpuInstance>,
    instances: Vec<(u32, [[f32; 4]; 3])>,
    shapes: Vec<GpuShape>,
    shape_masks: Vec<u32>,
    aabbs: Vec<[f32; 6]>,
    lights: Vec<GpuLight>,
    materials: Vec<GpuMaterial>,
    textures: Vec<GpuTexture>,
    texels: Vec<[f32; 4]>,
    dark_lights: Vec<String>,
    dome: u32,
    light_bvh: lights::LightBvh,
    /// The light tree that light samples descend when there are too many lights to loop over.
    light_tree: Option<light_tree::LightTree>,
    dome_table: Option<dome::DomeTable>,
}

/// Encodes `scene` relative to `origin`. Without `geometry`, mesh vertices, positions, indices
/// and texels are left out (an update compares positions and indices with the scene directly).
fn encode_scene(scene: &Scene, origin: DVec3, geometry: bool) -> Result<Host> {
    {
        let mut features = 0;

        // Meshes: one shared vertex and index buffer.
        let mut vertices = Vec::new();
        let mut positions = Vec::new();
        let (mut first_vertex_next, mut first_index_next) = (0u32, 0u32);
        let mut indices = Vec::new();
        let mut meshes = Vec::new();
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
            meshes.push(MeshRange {
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
        let mut gpu_instances = Vec::new();
        let mut instances = Vec::new();
        for inst in &scene.instances {
            let mesh = &scene.meshes[inst.mesh as usize];
            let range = meshes[inst.mesh as usize];
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
        if !instances.is_empty() {
            features |= FEATURE_MESHES;
        }

        // Analytic shapes: scene geometry first, then the visible surfaces of area lights.
        let mut shapes: Vec<GpuShape> = Vec::new();
        let shape_of = |g: &ShapeGeometry, material: u32, light: u32| -> GpuShape {
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
        };
        for s in &scene.shapes {
            let mut g = shape_of(&s.geometry, s.material, NONE);
            if let Some(pole) = s.pole {
                g.p1 = v4(pole, 0.0);
                g.flags |= SHAPE_FLAG_POLE;
            }
            shapes.push(g);
        }
        let mut shape_masks = vec![MASK_GEOMETRY; shapes.len()];

        // Lights.
        let mut lights = Vec::new();
        let mut dome = NONE;
        // The dome's scene index and map convention.
        let mut dome_map = (0, DomeConvention::Illum);
        let mut dark_lights = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            // A light that emits nothing is left out: sampling it would waste samples.
            if l.emits_nothing() {
                dark_lights.push(l.name.clone());
                continue;
            }
            let index = lights.len() as u32;
            let mut g = GpuLight {
                radiance: v3(l.radiance()),
                texture: l.texture.unwrap_or(NONE),
                shape: NONE,
                flags: if l.two_sided { LIGHT_FLAG_TWO_SIDED } else { 0 }
                    | if l.visible { LIGHT_FLAG_VISIBLE } else { 0 },
                ..Default::default()
            };
            let surface = l.kind.surface();
            if let Some(geom) = &surface {
                let e = encode(geom, origin);
                (g.kind, g.p0, g.p1, g.p2, g.area) = (e.light_kind, e.p0, e.p1, e.p2, e.area);
                features |= e.light_feature;
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
                    dome = index;
                    dome_map = (i, *convention);
                    features |= FEATURE_DOME;
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
                    features |= FEATURE_SUN;
                }
            }
            // The light's surface: seen by camera rays when visible, by shadow rays when it
            // casts shadows (an opaque object, the default).
            let mask = if l.visible { MASK_LIGHTS } else { 0 }
                | if l.shadows { MASK_LIGHT_SHADOWS } else { 0 };
            if let (Some(geom), true) = (surface, mask != 0) {
                g.shape = shapes.len() as u32;
                shapes.push(shape_of(&geom, NONE, index));
                shape_masks.push(mask);
            }
            lights.push(g);
        }
        // Emissive geometry is light too: emissive shapes become lights of their own kind, every
        // triangle of an emissive mesh a triangle light.
        let emissive = |m: u32| {
            let m = &scene.materials[m as usize];
            (m.emission.max_element() > 0.0).then_some(m)
        };
        for (si, s) in scene.shapes.iter().enumerate() {
            let Some(m) = emissive(s.material) else {
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
        for (ii, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh as usize];
            let Some(m) = emissive(mesh.material) else {
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
        if !shapes.is_empty() {
            features |= FEATURE_SHAPES;
        }

        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| {
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
                    },
                    lobe_count: m.specular.len().min(2) as u32,
                    metallic_roughness_texture: m.metallic_roughness_texture.unwrap_or(NONE),
                    roughness: m.metallic_roughness.map_or(0.0, |mr| mr.roughness),
                    base_metallic: m
                        .metallic_roughness
                        .map_or([0.0; 4], |mr| mr.base_color.extend(mr.metallic).to_array()),
                    ..Default::default()
                };
                for (i, l) in m.specular.iter().take(2).enumerate() {
                    g.lobes[i] = lobe(l);
                }
                g
            })
            .collect();

        let mut textures = Vec::new();
        let mut texels: Vec<[f32; 4]> = Vec::new();
        for t in &scene.textures {
            let wrap = |w: TextureWrap| match w {
                TextureWrap::Repeat => TEXTURE_WRAP_REPEAT,
                TextureWrap::Clamp => TEXTURE_WRAP_CLAMP,
                TextureWrap::Mirror => TEXTURE_WRAP_MIRROR,
            };
            textures.push(GpuTexture {
                offset: texels.len() as u32,
                width: t.width,
                height: t.height,
                flags: if t.filter == TextureFilter::Nearest {
                    TEXTURE_FLAG_NEAREST
                } else {
                    0
                } | wrap(t.wrap[0]) << TEXTURE_WRAP_SHIFT_U
                    | wrap(t.wrap[1]) << TEXTURE_WRAP_SHIFT_V,
            });
            if geometry {
                texels.extend(t.texels.iter().map(|v| v.to_array()));
            }
        }
        if !textures.is_empty() {
            features |= FEATURE_TEXTURES;
        }

        light_mean::set_means(&mut lights, &scene.textures);
        let aabbs: Vec<[f32; 6]> = shapes.iter().map(shape_aabb).collect();
        let light_bvh = lights::build(&lights);
        let mean_texel = |t: u32| light_tree::texture_mean(&scene.textures[t as usize]);
        let light_tree = if lights.len() > DIRECT_LOOP_LIGHTS as usize {
            features |= FEATURE_MANY_LIGHTS;
            light_tree::build(&lights, &mean_texel)?
        } else {
            None
        };
        // Importance-sampling tables of a textured dome (a constant dome is sampled uniformly).
        let dome_table = (dome != NONE)
            .then(|| {
                let l = &scene.lights[dome_map.0];
                l.texture
                    .map(|t| dome_sh::table(&scene.textures[t as usize], l, dome_map.1))
            })
            .flatten();
        Ok(Host {
            features,
            vertices,
            positions,
            indices,
            meshes,
            gpu_instances,
            instances,
            shapes,
            shape_masks,
            aabbs,
            lights,
            materials,
            textures,
            texels,
            dark_lights,
            dome,
            light_bvh,
            light_tree,
            dome_table,
        })
    }
}

impl GpuScene {
    pub fn new(ctx: &Context, scene: &Scene, ray_query: bool) -> Result<GpuScene> {
        let origin = scene.camera.position;
        let h = encode_scene(scene, origin, true)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let build_input = if ray_query {
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
        } else {
            vk::BufferUsageFlags::empty()
        };
        let upload = |name: &str, data: &[u8], usage| -> Result<Option<Buffer>> {
            if data.is_empty() {
                return Ok(None);
            }
            ctx.upload(name, data, usage).map(Some)
        };
        let vertex_buffer = upload(
            "vertices",
            bytemuck::cast_slice(&h.vertices),
            storage | build_input,
        )?;
        let index_buffer = upload(
            "indices",
            bytemuck::cast_slice(&h.indices),
            storage | build_input,
        )?;
        let aabb_buffer = upload(
            "shape AABBs",
            bytemuck::cast_slice(&h.aabbs),
            storage | build_input,
        )?;
        let tables = update::Tables::upload(ctx, &h)?;
        let mut frame = Frame::default();
        tables.write_frame(&mut frame, &h);
        let addr = |b: &Option<Buffer>| b.as_ref().map_or(0, |b| b.address);
        frame.vertices = addr(&vertex_buffer);
        frame.indices = addr(&index_buffer);
        set_camera(&mut frame, &scene.camera, origin);
        Ok(GpuScene {
            frame,
            features: h.features,
            meshes: h.meshes,
            instances: h.instances,
            shapes: h.shapes,
            shape_masks: h.shape_masks,
            shape_boxes: h.aabbs,
            origin,
            dark_lights: h.dark_lights,
            emitters: h.lights.len() as u32,
            positions: h.positions,
            indices: h.indices,
            vertex_buffer,
            index_buffer,
            aabb_buffer,
            tables,
        })
    }
}
