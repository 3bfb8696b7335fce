// The layout contract between Rust and every kernel: structs, bindings, constants, written once
// here. build.rs generates the Rust side from this file (src/layout.rs includes it): every
// `#define NAME <integer>` becomes a `u32` constant, every struct a #[repr(C)] Pod mirror with the
// same member names and order, documented by the comments here. For the generator, write
// `struct Name {` on one line and one member per line (`type name;` or `type name[N];`); the `//`
// lines right above a struct document it, a member's trailing comment (and comment lines directly
// below it) document that member. Scalar block layout everywhere; members are ordered so that
// std430 gives the same offsets and sizes (build.rs fails otherwise). tests/layout.rs checks every
// size and offset against the offsets glslang emits for tests/kernels/layout_check.comp, and that this
// header, that kernel and the Rust mirrors name the same structs.
#ifndef ILLUM_LAYOUT_GLSL
#define ILLUM_LAYOUT_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

// Descriptor set 0.
#define BINDING_FRAME 0
// The device film (FilmPixel per film slot) for the resolve kernels; the integrators' film
// kernels reach it by address instead (PassConstants.film_address, glsl/film/film.glsl).
#define BINDING_FILM 1
// The AOV planes an integrator declares (Integrator::aov_planes, src/render/integrator.rs): only
// when it declares P > 0 of them, a buffer of P vec4 sums per pixel of the device film, plane k
// of the pixel in film slot p (film_slot, as for the film) at p * P + k; .rgb are the sums of the
// block's samples, .w is unused (keep it 0). Cleared and read back with the film, so the same
// 256-sample block rules hold. Film kernels reach it at PassConstants.aovs_address (aov_load,
// aov_store, glsl/film/film.glsl) and add to it as to the film (one invocation owns a pixel: no
// atomics); resolve_aov.comp reads it at BINDING_AOVS.
#define BINDING_AOVS 4
// Floats of one AOV plane's sums at a pixel (its vec4), as the host reads them.
#define AOV_CHANNELS 4
// Regions of the kernel profile (glsl/shared/profile.glsl; kernels built with ILLUM_PROFILE),
// by index; src/render/profile.rs names them.
#define PROF_CAMERA_RAY 0
#define PROF_CAMERA_TRACE 1
#define PROF_CAMERA_SHADE 2
#define PROF_DIRECT_PLAN 3
#define PROF_LIGHT_SAMPLE 4
#define PROF_BRDF_SAMPLE 5
#define PROF_SHADOW_TRACE 6
#define PROF_DIRECT_LOOP 7
#define PROF_FILM 8
#define PROF_BOUNCE_TRACE 9
#define PROF_BOUNCE_SHADE 10
#define PROF_BOUNCE 11
#define PROF_OTHER 12
#define PROF_DIRECT_OPEN 13
#define PROF_DIRECT_FLUSH 14
#define PROF_DIRECT_CANDIDATES 15
// An empty span: what a mark itself costs (the host subtracts it from every region).
#define PROF_EMPTY 16
// Regions counted: every one above, the empty spans' the last.
#define PROFILE_REGIONS 17
#define BINDING_TLAS 2
#define BINDING_BVH 3
#define BINDING_IMAGE 5   // the host's storage image (glsl/film/resolve_image.comp)

// Specialization constants.
#define SPEC_FEATURES 0
// With FEATURE_FLAT_SHAPES: shape i's kind in bits 2i, 2i + 1 (SHAPE_* + 1; 0 past the last
// shape), so that the flat loop holds each shape's own test only (trace/bvh.glsl).
#define SPEC_FLAT_KINDS 1

// Feature bits: what a scene uses. Kernels test them against the FEATURES specialization constant,
// so code for absent features is folded away at pipeline creation.
#define FEATURE_MESHES 1
#define FEATURE_SHAPES 2
// Rect lights, analytic or emissive rects (disk and sphere lights have bits of their own below).
#define FEATURE_RECT_LIGHTS 4
#define FEATURE_DOME 8
#define FEATURE_SUN 16
#define FEATURE_TEXTURES 32
#define FEATURE_TRIANGLE_LIGHTS 64
// More than LIGHT_TREE_MIN_LIGHTS lights: the scene has a light tree, and light samples may pick
// lights (Frame.light_select).
#define FEATURE_MANY_LIGHTS 128
// Settings, not the scene: shadow rays for a resampled subset of the candidates
// (Frame.shadow_resample < 1), and Russian roulette on each candidate (Frame.shadow_cull > 0).
// Off, their code is left out of the kernels (glsl/direct/shadow.glsl; docs/techniques.md,
// "Shadow resampling", "Shadow culling").
#define FEATURE_SHADOW_RESAMPLE 256
#define FEATURE_SHADOW_CULL 512
// Settings: control variates for the diffuse light samples of the looped lights
// (Frame.control_variates; docs/techniques.md, "Control variates").
#define FEATURE_CONTROL_VARIATES 1024
// Disk and sphere lights, analytic or emissive shapes (like FEATURE_RECT_LIGHTS).
#define FEATURE_DISK_LIGHTS 2048
#define FEATURE_SPHERE_LIGHTS 4096
// A textured dome whose lookup varies inside its sampling cells (Mitsuba's, or illum's bilinear):
// the cells' shaped densities (DOME_SHAPE_*), whichever cells the map's luminance then shapes.
#define FEATURE_DOME_SHAPED 8192
// A material lobe of the GGX (Trowbridge-Reitz) distribution: without one the kernels hold the
// Beckmann lobes' code only.
#define FEATURE_GGX 16384
// No mesh and at most BVH_FLAT_MAX analytic shapes (light surfaces included): the trace tests
// every shape, culled by its box, from a copy in the BVH's uniform buffer instead of walking the
// BVH (trace/bvh.glsl says why).
#define FEATURE_FLAT_SHAPES 32768

#define WORKGROUP_X 8
#define WORKGROUP_Y 8
// Witness blocks (Frame.witness, src/film/split.rs) are workgroups; block (bx, by) is one where
// (bx + WITNESS_ROW_STEP by + offset) mod period is 0, so that each row's witnesses are shifted.
#define WITNESS_ROW_STEP 5

// Analytic shape kinds (GpuShape.kind).
#define SHAPE_SPHERE 0
#define SHAPE_RECT 1
#define SHAPE_DISK 2
// GpuShape.flags: a sphere's p1.xyz is the pole of its tangent frame.
#define SHAPE_FLAG_POLE 1

// Light kinds (GpuLight.kind).
#define LIGHT_RECT 0
#define LIGHT_DISK 1
#define LIGHT_SPHERE 2
#define LIGHT_DOME 3
#define LIGHT_SUN 4
#define LIGHT_TRIANGLE 5

#define LIGHT_FLAG_TWO_SIDED 1
#define LIGHT_FLAG_VISIBLE 2
// The light is the emission of scene geometry (an emissive shape or mesh triangle): it occludes
// like any geometry and has no separate light surface.
#define LIGHT_FLAG_GEOMETRY 4
// Never uploaded: set by the integrator on its copy of a light when the shading point lies on that
// light's own surface (emissive geometry lit by itself). A sphere then counts the point as inside
// (float rounding cannot put it outside and sample the outer cap), a planar light skips itself.
#define LIGHT_FLAG_SELF 8
// A dome's map convention (docs/scene-format.md; glsl/lights/dome_map.glsl): neither bit is illum's.
#define LIGHT_FLAG_DOME_MITSUBA 16
#define LIGHT_FLAG_DOME_PBRT 32

// Microfacet models (GpuLobe.distribution) and Fresnel kinds (GpuLobe.fresnel).
#define DIST_DBRDF 0
#define DIST_BECKMANN_SMITH 1
#define DIST_GGX_SMITH 2
#define DIST_GGX_SMITH_SEPARABLE 3
#define FRESNEL_CONSTANT 0
#define FRESNEL_SCHLICK 1
#define FRESNEL_CONDUCTOR 2

#define MATERIAL_FLAG_TWO_SIDED 1
#define MATERIAL_FLAG_TANGENT_DIR 2
// Metallic-roughness (glTF, UsdPreviewSurface): diffuse, lobes[0].fresnel0 and lobes[0].alpha are
// re-derived per texel from base_metallic, roughness, dielectric_f0 and the base-colour and
// metallic-roughness textures.
#define MATERIAL_FLAG_METALLIC_ROUGHNESS 4

// GpuTexture.flags: the filter, and the wrap mode (TEXTURE_WRAP_*) of each axis in two bits.
#define TEXTURE_FLAG_NEAREST 1
#define TEXTURE_WRAP_SHIFT_U 1
#define TEXTURE_WRAP_SHIFT_V 3
#define TEXTURE_WRAP_REPEAT 0
#define TEXTURE_WRAP_CLAMP 1
#define TEXTURE_WRAP_MIRROR 2

#define INSTANCE_FLAG_NORMALS 1
#define INSTANCE_FLAG_UVS 2
#define INSTANCE_FLAG_TANGENTS 4

// Ray masks. Camera rays see geometry and the visible light surfaces; shadow rays (and so BRDF
// samples, which end at the first occluder) see geometry and the light surfaces that cast shadows.
// Area lights are opaque objects by default, as in Mitsuba 3, pbrt-v4 and RenderMan; a light with
// "shadows": false is transparent to shadow rays.
#define MASK_GEOMETRY 1
#define MASK_LIGHTS 2
#define MASK_LIGHT_SHADOWS 4
#define MASK_OCCLUDERS 5

// Direct-lighting techniques (Frame.technique): BRDF sampling only, light sampling only, or
// both combined by multiple importance sampling (the power heuristic).
#define TECHNIQUE_BRDF 0
#define TECHNIQUE_LIGHT 1
#define TECHNIQUE_MIS 2
// Frame.integrator_flags: the diffuse lobe also takes cosine-sampled BRDF samples under MIS (the
// course lights diffuse with light samples only).
#define INTEGRATOR_DIFFUSE_MIS 1
// Frame.integrator_flags (full): the diffuse chain also goes on through the specular lobes of the
// surfaces it meets, so that light reaching a diffuse surface through glossy and specular ones
// (L S+ D ...) is kept; off: the course's split, which leaves it out.
#define INTEGRATOR_CAUSTICS 2
// Frame.control_variates (with FEATURE_CONTROL_VARIATES): the course's average visibility
// (biased, consistent) or its leave-one-out form (unbiased).
#define CONTROL_VARIATES_AVGVIS 1
#define CONTROL_VARIATES_LOO 2
// Radiosity cache (src/integrators/indirect/radiosity.rs): a world-space hashed grid. Lookups probe at
// most RADIOSITY_PROBES consecutive entries; each update record names its cell at
// RADIOSITY_RECORD_KEYS levels (the footprint's, then the next coarser one).
#define RADIOSITY_PROBES 16
#define RADIOSITY_RECORD_KEYS 2

// Lights that direct lighting loops over at every shading point (each with its own sample count)
// unless told otherwise; above it, light samples pick lights from the light tree. Measured:
// docs/performance.md. Between LIGHT_TREE_MIN_LIGHTS and it, both can run (FEATURE_MANY_LIGHTS):
// the allocation pilot measures which costs less (docs/allocation.md). Up to
// LIGHT_TREE_MIN_LIGHTS lights, a loop costs at most that many shadow rays a round: no tree.
#define DIRECT_LOOP_LIGHTS 64
#define LIGHT_TREE_MIN_LIGHTS 8
// How light samples pick lights (Frame.light_select): loop over every light, the former linear
// scan of a CDF over all lights (kept for comparison), or the light tree (docs/techniques.md,
// "The light tree").
#define LIGHT_SELECT_LOOP 0
#define LIGHT_SELECT_SCAN 1
#define LIGHT_SELECT_TREE 2
// GpuLightTreeNode.link: a leaf, whose light index is link & ~LIGHT_TREE_LEAF.
#define LIGHT_TREE_LEAF 0x80000000
// GpuLightTreeNode.flags: some emitter below emits on both sides (the cone test folds the angle).
#define LIGHT_TREE_TWO_SIDED 1
// Levels a light's trail (one bit per level) can hold.
#define LIGHT_TREE_MAX_DEPTH 32

// Hit kinds reported by the trace interface.
#define HIT_NONE 0
#define HIT_TRIANGLE 1
#define HIT_SHAPE 2

#define NONE 0xffffffff

// Compute BVH (TRACE_BVH; src/trace/bvh/). A link names a child: an inner node index, or, with
// BVH_LEAF_BIT set, a leaf of (count - 1) << BVH_LEAF_COUNT_SHIFT | first. Bottom-level leaves
// are ranges of BvhTriangle; top-level leaves are single BvhInstance entries.
#define BVH_LEAF_BIT 0x80000000
#define BVH_LEAF_COUNT_SHIFT 27
#define BVH_LEAF_FIRST_MASK 0x07ffffff
#define BVH_MAX_LEAF 8
// Entries of the traversal stack (enough for the depth the builder allows, top plus bottom level).
#define BVH_STACK_SIZE 48
// BvhInstance.root for an analytic shape.
#define BVH_SHAPE 0xffffffff
// Most shapes FEATURE_FLAT_SHAPES tests (BvhFlat's arrays).
#define BVH_FLAT_MAX 16

// Per-render constants (uniform buffer). Positions are camera-relative: the host subtracts the
// camera position in double precision, so large world coordinates keep their precision here.
struct Frame {
    vec4 cam_forward;     // xyz: unit view direction
    vec4 cam_right;       // xyz: right, scaled by tan(fov_y / 2) * aspect
    vec4 cam_up;          // xyz: up, scaled by tan(fov_y / 2)
    vec4 cam_origin;      // xyz: the camera's position relative to the scene's upload origin (the
                          // camera it was prepared with: 0 unless a prepared scene renders a
                          // moved camera)
    uint width;           // image size in pixels
    uint height;
    uint light_count;     // GpuLight entries
    uint shape_count;     // GpuShape entries
    uint instance_count;  // GpuInstance entries
    uint material_count;  // GpuMaterial entries
    uint texture_count;   // GpuTexture entries
    uint dome_light;      // GpuLight index of the dome, or NONE
    uint technique;       // direct lighting: TECHNIQUE_*
    uint light_samples;   // most light samples per light
    uint brdf_samples;    // BRDF samples per lobe
    uint integrator_flags;    // INTEGRATOR_*
    uint64_t instances;   // device addresses of the scene buffers (0 when absent)
    uint64_t vertices;
    uint64_t indices;
    uint64_t materials;
    uint64_t shapes;
    uint64_t lights;
    uint64_t textures;
    uint64_t texels;
    uint64_t dome_sampling;   // GpuDomeSampling of the dome's map (0: none; uniform sampling)
    uint64_t light_nodes;     // GpuLightNode array: BVH over the finite lights' bounds
    uint64_t light_refs;      // uint array: light indices in leaf order, then the infinite lights
    uint light_bvh_nodes;     // GpuLightNode count (0: no finite light)
    uint infinite_first;      // light_refs index of the first infinite light
    uint infinite_count;      // infinite lights (dome, sun), at light_refs[infinite_first ...]
    float clamp_luminance;    // firefly clamp: the most luminance of one camera sample's direct
                              // lighting (0: off; biased when on)
    uint nan_every;           // test hook: every n-th sample is NaN (0: off)
    uint light_select;        // LIGHT_SELECT_* (with FEATURE_MANY_LIGHTS)
    uint light_tree_nodes;    // GpuLightTreeNode count
    uint max_depth;           // path integrator: most path segments (NONE: unbounded)
    uint64_t light_tree;      // GpuLightTreeNode array over the finite lights (0: none)
    uint64_t light_trails;    // uint per light: its leaf's path, bit k set = second child at depth k
    uint specular_depth;      // full integrator: most specular bounces of the reflection part
    uint radiosity_mask;      // entries - 1 (a power of two)
    uint64_t radiosity_table; // RadiosityEntry array of the radiosity cache (0: no cache)
    uint radiosity_levels;    // cell edges radiosity_cell * 2^l, l < radiosity_levels
    float radiosity_cell;     // finest cell edge (scene units)
    float diffuse_spread;     // ray-cone spread angle a diffuse bounce starts (radians)
    float shadow_resample;    // share of a group's candidates that get shadow rays (with
                              // FEATURE_SHADOW_RESAMPLE; 1: all)
    float shadow_cull;        // Russian roulette threshold on a candidate's luminance (with
                              // FEATURE_SHADOW_CULL; 0: off)
    uint control_variates;    // CONTROL_VARIATES_* (with FEATURE_CONTROL_VARIATES)
    uint dome_samples;        // a textured dome's light samples per N_max (light_count_for)
    uint film_x0;             // the device film's window: its first column and row, and its
    uint64_t pixel_ends;      // uint per pixel: the sample index at which it stops (adaptive
                              // sampling, film_sample_count; 0: every pixel takes every sample)
    uint64_t pixel_order;     // uint array: pixel indices by descending end sample, which the
                              // dispatches of PassConstants.order take in prefixes (film_pixel)
    uint film_y0;             // width (film_slot; a render holds the film of its job's pixels only)
    uint film_width;
    uint light_floor;         // fewest samples a looped light takes (light_count_for; 0 or 1: the
                              // course's rule alone)
    uint witness;             // which pixels split their samples into two sequences (the
                              // half-buffers; film_samples, src/film/split.rs): bits 0-15 the period
                              // M of witness blocks (workgroups), bits 16-31 their offset. M 1:
                              // every pixel, its samples alternating; else a pixel of a witness
                              // block (WITNESS_ROW_STEP) takes twice the samples, one sequence
                              // each, and the others one sequence
    uint64_t profile;         // uint64 per PROFILE_REGIONS region per film slot: time by region
                              // in kernels built with ILLUM_PROFILE (shared/profile.glsl; 0: none)
};

// Per-dispatch constants.
struct PassConstants {
    uint first_sample;    // index of the first sample of this dispatch (per pixel)
    uint sample_count;    // samples per pixel in this dispatch
    uint seed_lo;
    uint seed_hi;
    uvec4 tile;           // x0, y0, width, height of the pixel rectangle of this dispatch; with
                          // `order`: first entry of Frame.pixel_order, entries, and the grid's
                          // width and height that cover them
    uint order;           // 1: the dispatch takes pixels from Frame.pixel_order, else the tile
    uint row_step;        // workgroup row r of the dispatch covers the tile's row (r row_step) mod
                          // rows (coprime to them; 0: in order), so that each of the equal ranges
                          // of workgroups lavapipe gives its threads spans the whole tile
    uint pad1;
    uint pad2;
    // Device addresses of the film (FilmPixel per film slot) and of its AOV planes (0: none). Not
    // storage-buffer descriptors: lavapipe turns each access to one at a per-lane index into a
    // branch per lane and component (60% of the `full` kernel's basic blocks, a quarter of its
    // compile time: docs/performance-kernels.md, "The film by address").
    uint64_t film_address;
    uint64_t aovs_address;
};

struct GpuVertex {
    vec3 position;
    float u;
    vec3 normal;
    float v;
    vec4 tangent;         // xyz, w = handedness
};

struct GpuInstance {
    vec4 object_to_world[3];  // rows of the 3x4 object-to-world matrix (camera-relative)
    vec4 normal_to_world[3];  // rows of the inverse transpose of its 3x3 part
    uint first_index;         // first index of the mesh in the index buffer
    uint first_vertex;        // added to every index of the mesh
    uint material;
    uint flags;               // INSTANCE_FLAG_*
};

struct GpuShape {
    vec4 p0;   // sphere: centre, radius; rect: centre; disk: centre, radius
    vec4 p1;   // rect: full edge u; disk: unit normal; sphere: unit pole (SHAPE_FLAG_POLE)
    vec4 p2;   // rect: full edge v; disk: unit tangent; sphere: |c| - r, |c| (double precision, shapes.glsl)
    uint kind;       // SHAPE_*
    uint material;   // NONE for light shapes
    uint light;      // index of the light it is the surface of, or NONE
    uint flags;
};

struct GpuLobe {
    vec4 fresnel0;   // constant colour, Schlick f0, or conductor eta
    vec4 fresnel1;   // conductor k
    vec2 alpha;      // roughness along tangent and bitangent
    uint distribution;
    uint fresnel;
};

struct GpuMaterial {
    vec3 diffuse;
    uint diffuse_texture;
    vec3 emission;
    uint emission_texture;
    vec3 tangent_dir;
    uint flags;
    uint lobe_count;
    uint metallic_roughness_texture;
    float roughness;        // glTF roughness factor (MATERIAL_FLAG_METALLIC_ROUGHNESS)
    float dielectric_f0;    // Schlick f0 at metallic 0 (glTF: 0.04; UsdPreviewSurface: from its ior)
    vec4 base_metallic;     // glTF base colour factor, metallic factor
    GpuLobe lobes[2];
};

// Lights. Emissive geometry becomes lights too (LIGHT_FLAG_GEOMETRY): an emissive analytic shape
// gives a rect/disk/sphere light whose `shape` is that shape; every triangle of an emissive mesh
// gives a LIGHT_TRIANGLE (emission textures are read through the instance's uvs when evaluated).
struct GpuLight {
    vec4 p0;   // rect: centre; disk/sphere: centre, radius; dome: cos, sin of rotation; sun: direction, cos(theta_max)
               // triangle: vertex 0 (camera-relative world)
    vec3 p1;   // rect: full edge u; disk: unit normal; sun: x = 1 - cos(theta_max) (stable)
               // triangle: edge v1 - v0
    uint triangle;   // LIGHT_TRIANGLE: the triangle's index within its mesh (0 otherwise)
    vec4 p2;   // rect: full edge v; disk: unit tangent; sphere: |c| - r, |c| (double precision, shapes.glsl); triangle: edge v2 - v0 (normal: normalize(p1 x p2))
    vec3 radiance;   // color * intensity * 2^exposure (sun: irradiance at normal incidence;
                     // emissive geometry: the material's emission)
    uint kind;       // LIGHT_*
    uint texture;    // NONE or texture index (emissive geometry: the material's emission texture)
    uint shape;      // its GpuShape (visible light surface, or the emissive shape), else NONE;
                     // triangle: the GpuInstance index
    uint flags;      // LIGHT_FLAG_*
    float area;      // surface area (rect, disk, sphere, triangle)
    vec3 mean;       // textured rect, disk, sphere, triangle: radiance x the mean of the texture
                     // lookup over the surface (the control variates' constant radiance), else 0
    uint pad;
};

// The density inside a dome's sampling cell (GpuDomeSampling.shape): uniform (the lookup is constant
// there: nearest texels, pbrt's square, a black map), one bilinear patch of the cell's four corner
// texels (Mitsuba's cells between texel centres), or the four bilinear quarters of a texel (illum's
// bilinear lookup: nodes from the 3 x 3 texels around it). The last two follow the lookup's own
// luminance, so that a light sample's weight L / pdf does not vary inside a cell.
#define DOME_SHAPE_UNIFORM 0
#define DOME_SHAPE_CORNERS 1
#define DOME_SHAPE_TENT 2

// Importance-sampling tables of a dome's map (src/gpu_scene/dome.rs builds them;
// glsl/lights/light_sampling.glsl reads them) over a grid of width x height cells of its map
// coordinates (glsl/lights/dome_map.glsl: the texels, or for the Mitsuba convention the cells
// between texel centres), each weighted by the luminance the lookup gives inside it (every cell
// where the radiance can be positive has a weight > 0) times the solid angle per unit map area at
// its centre. width == 0: no table (uniform sphere).
struct GpuDomeSampling {
    uint64_t marginal;     // float[height + 1]: CDF over rows, marginal[0] = 0, marginal[height] = 1
    uint64_t conditional;  // float[height * (width + 1)]: per row, CDF over its texels, 0 ... 1
    uint64_t nodes;        // float[(map width + 2) (map height + 2)]: the luminance the cells' shape
                           // is drawn from (DOME_SHAPE_*), texel (i, j) at (j + 1) (map width + 2) + i + 1
                           // for i in -1 ..= map width, j in -1 ..= map height, wrapped as the lookup wraps
    uint64_t texels;       // the map's first texel (vec4) in the texel buffer, 0: none. With the Mitsuba
                           // convention a light sample reads its cell's four corner texels there once,
                           // for the cell's shape and its radiance (sample_dome)
    uint width;
    uint height;
    float integral;        // mean texel weight (sum / (width height)), for diagnostics
    float defensive;       // share of samples drawn uniformly over the sphere (pdf mixed alike);
                           // 0 in the buffer, set by dome_sampling() (lights/lights.glsl) under control variates
    uint shape;            // DOME_SHAPE_*: the density inside a cell
    uint nodes_width;      // map width + 2 (0 without nodes)
    uint marginal_buckets; // guide buckets of the marginal CDF (a multiple of height; each row's: width)
    uint pad0;             // sh at a 16-byte offset in scalar and std430 alike
    vec4 sh[9];            // xyz: the dome's radiance (colour included) projected on real SH9 in world
                           // directions, order (l, m) = 00, 1-1, 10, 11, 2-2, 2-1, 20, 21, 22
                           // (src/gpu_scene/dome_sh.rs): the control variate's L_SH
};

// A node of the light BVH (src/gpu_scene/lights.rs): BRDF samples find the finite lights they cross
// by traversing it instead of testing every light. count == 0: inner node with children `index`
// and `index + 1`; else a leaf of light_refs[index .. index + count].
struct GpuLightNode {
    vec3 lo;
    uint index;
    vec3 hi;
    uint count;
};

// A node of the light tree (src/gpu_scene/light_tree.rs; docs/techniques.md, "The light tree"):
// light samples descend it choosing children by importance. Depth-first: an inner node's first
// child is the next node, its second `link`; a leaf (LIGHT_TREE_LEAF in link) holds one light.
struct GpuLightTreeNode {
    vec3 lo;         // bounds of the subtree's emitters
    float power;     // emitted power (luminance), relative to the root's
    vec3 hi;
    uint link;
    vec3 axis;       // orientation cone bounding the emitters' normals: unit axis,
    float cos_o;     // cos(theta_o), the normals' spread about it
    float cos_e;     // cos(theta_e), emission beyond the normals (0: Lambertian)
    uint flags;      // LIGHT_TREE_*
    uint pad0;
    uint pad1;
};

struct GpuTexture {
    uint offset;     // first texel in the texel buffer
    uint width;
    uint height;
    uint flags;      // TEXTURE_FLAG_NEAREST | wrap mode along u << TEXTURE_WRAP_SHIFT_U | along v << ..._V
};

// Accumulated per pixel over all samples so far (sums, divided by the sample count on readback).
// Each member's `channels:` line names its floats: the film channels the host reads
// (src/render/film.rs) and partial EXRs store, whose count, offsets and names build.rs generates
// from these lines.
struct FilmPixel {
    vec4 beauty;     // rgb sum; w = samples the firefly clamp reduced
                     // channels: beauty.r beauty.g beauty.b clamped
    vec4 beauty_sq;  // rgb sum of squares (for the variance of the mean); w = rays traced
                     // channels: beauty_sq.r beauty_sq.g beauty_sq.b rays
    vec4 albedo;     // rgb sum over samples that hit a surface; w = number of such samples
                     // channels: albedo.r albedo.g albedo.b hits
    vec4 normal;     // xyz sum of shading normals; w = sum of hit distances
                     // channels: normal.x normal.y normal.z depth
    vec4 emission;   // rgb sum of directly seen emission; w = samples with non-finite beauty
                     // channels: emission.r emission.g emission.b non_finite
    vec4 beauty_odd; // rgb sum over the odd-numbered samples only: the two half-buffers (even =
                     // beauty - beauty_odd) give an unbiased estimate of the pixel's variance;
                     // w = samples taken (fewer than the pass's where adaptive sampling stops it)
                     // channels: odd.r odd.g odd.b samples
};

// The compute BVH: device addresses of its arrays (uniform buffer at BINDING_BVH).
struct BvhHeader {
    uint64_t nodes;       // BvhNode array: bottom levels of every mesh, then the top level
    uint64_t triangles;   // BvhTriangle array in leaf order
    uint64_t instances;   // BvhInstance array: the top level's leaves
    uint root;            // link of the top-level root, NONE for an empty scene
    uint node_count;
};

// The shapes, their ray masks (MASK_*) and boxes in shape order, after BvhHeader in the BVH's
// uniform buffer: what FEATURE_FLAT_SHAPES tests. Entries past Frame.shape_count are zero.
struct BvhFlat {
    GpuShape shapes[16];   // BVH_FLAT_MAX
    uint masks[16];
    vec4 lo[16];           // xyz: the shape's box, padded as the BVH's (GpuScene::shape_boxes)
    vec4 hi[16];
};

// Four children's boxes, quantized to 8 bits per plane on a grid over the node's own box (one
// byte per child in each plane word, so that one 64-byte fetch tests all four): child k's box is
// origin + step * byte k of lo_*/hi_*, step = 2^(byte a of `scale` - 127) along axis a. An unused
// slot has link NONE. trace/bvh.glsl reads it as 64-bit words by offset: keep the order.
struct BvhNode {
    vec3 origin;
    uint scale;
    uvec4 links;
    uint lo_x;
    uint hi_x;
    uint lo_y;
    uint hi_y;
    uint lo_z;
    uint hi_z;
    uint pad0;
    uint pad1;
};

// A triangle's object-space vertices gathered in leaf order (no index indirection) and its index
// within its mesh: 40 bytes, which the traversal reads as five 64-bit words. (Single floats: a
// vec3 would align to 16 bytes in std430, the Rust mirror's reference.)
struct BvhTriangle {
    float x0;
    float y0;
    float z0;
    float x1;
    float y1;
    float z1;
    float x2;
    float y2;
    float z2;
    uint prim;            // triangle index within its mesh (Hit.prim)
};

// A top-level leaf: a mesh instance or an analytic shape (read as 64-bit words by offset, like
// BvhNode).
struct BvhInstance {
    vec4 world_to_object[3];  // rows of the inverse of the instance's object-to-world matrix
    uint root;                // link of the mesh's bottom-level root, or BVH_SHAPE
    uint index;               // GpuInstance index (Hit.instance), or shape index (Hit.prim)
    uint mask;                // MASK_* bits
    uint pad;
};

// A ray of glsl/trace/trace_query.comp (the trace interface as a kernel, for tests and benchmarks).
struct QueryRay {
    vec3 origin;
    float tmin;
    vec3 dir;
    float tmax;
    uint mask;
    float shadow_resample;    // share of a group's candidates that get shadow rays (with
                              // FEATURE_SHADOW_RESAMPLE; 1: all)
    float shadow_cull;        // Russian roulette threshold on a candidate's luminance (with
                              // FEATURE_SHADOW_CULL; 0: off)
    uint pad2;
};

// What glsl/trace/trace_query.comp reports per ray: trace_closest's Hit and trace_occluded's answer.
struct QueryHit {
    float t;
    uint kind;
    uint instance;
    uint prim;
    vec2 bary;
    uint occluded;
    uint pad;
};

// Push constants of glsl/trace/trace_query.comp.
struct QueryConstants {
    uint64_t rays;        // QueryRay array
    uint64_t hits;        // QueryHit array
    uint count;           // rays in this dispatch
    uint mode;            // QUERY_*
};

// An entry of the radiosity cache's table: a cell's key (two independent 32-bit hashes of its
// grid coordinates, level and normal octant; key.y == 0 marks an empty slot) and its mean
// outgoing diffuse radiance B = rho / pi * E.
struct RadiosityEntry {
    vec3 value;
    uint count;               // update samples behind the value
    uvec2 key;
    uvec2 pad;
};

// One update sample of the radiosity cache (the update pass of glsl/indirect/full.comp): B at a
// point, filed under the keys of its cell at RADIOSITY_RECORD_KEYS levels.
struct RadiosityRecord {
    vec3 value;
    uint valid;               // 0: no sample (the path ended earlier)
    uvec2 keys[2];
};

// The radiosity cache's update pass of glsl/indirect/full.comp (FullPass.update).
struct RadiosityPass {
    uint64_t records;         // RadiosityRecord array
    uint index;               // update index of gl_GlobalInvocationID.z == 0: the sample index it
                              // belongs to, or a warm-up round; z counts consecutive indices
    uint vertices;            // records per path
    uint block;               // one path per block x block pixels (gl_GlobalInvocationID.xy)
    uint row_step;            // as PassConstants.row_step, over the dispatch's workgroup rows
};

// The passes of the full integrator's one kernel (FullPass.mode): the driver compiles the code
// they share (traversal, direct lighting, materials) once.
#define FULL_PASS_FILM 0
#define FULL_PASS_UPDATE 1

// Push constants of glsl/indirect/full.comp: a film pass (`film`, as for every film kernel) or
// a radiosity cache update (`update`, with film.seed_lo and film.seed_hi; the rest of `film` 0).
struct FullPass {
    PassConstants film;
    uint mode;                // FULL_PASS_*
    uint pad0;
    RadiosityPass update;
};

#define QUERY_CLOSEST 1
#define QUERY_OCCLUDED 2

#endif
