// illum-variants: rq bvh
// The full integrator's one kernel, for two passes chosen by pc.mode (FullPass, layout.glsl): the
// film pass and the radiosity cache's update pass share their traversal, direct lighting,
// materials and lights, so the driver compiles that code once (docs/performance-kernels.md,
// "Kernel compilation").
//
// Film pass (FULL_PASS_FILM): the seed's split of the rendering equation (docs/techniques.md,
// "Indirect lighting: the three integrators"), one camera sample at a time: at the camera hit x1,
// emission seen directly plus direct lighting exactly as primary.comp does (the Direct AOV); the
// diffuse lobe's indirect light by one cosine-sampled ray whose hit returns its outgoing diffuse
// radiance, from the radiosity cache or by brute force (IndirectDiffuse); and the specular lobes'
// indirect light by the reflection integrator (Reflection): a specular chain of up to
// frame.specular_depth BRDF-sampled bounces, each reflected point shaded like a camera hit (direct
// lighting in full, its indirect diffuse through the cache). Rays that reach a light or the sky add
// nothing: direct lighting has them. Paths light -> specular -> diffuse -> eye (caustics) are left
// out, as in the course.
//
// Update pass (FULL_PASS_UPDATE, src/integrators/indirect/radiosity.rs): one path per block x block
// pixels (gl_GlobalInvocationID.xy) and update index (pc.update.index + gl_GlobalInvocationID.z): a
// camera ray through a random point of the block, a first bounce chosen as the film pass's camera
// hit chooses (diffuse or specular lobe), then up to pc.update.vertices diffuse vertices. At each
// it writes a record of B = rho/pi E: direct lighting of the diffuse lobe plus one cosine-sampled
// bounce whose hit reads the cache's current table (the previous generation: one Jacobi iteration
// of the radiosity equation per generation, docs/techniques.md, "The radiosity cache"), filed under
// its cell's keys at the cone width the render's lookups there will have. The host averages the
// records into the next generation's table.
#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#include "shared/layout.glsl"
#include "trace/trace.glsl"
#include "direct/direct.glsl"
#include "indirect/indirect.glsl"
#include "film/film.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_FILM) buffer FilmBlock { FilmPixel film[]; };
layout(scalar, binding = BINDING_AOVS) buffer AovBlock { vec4 aovs[]; };
layout(push_constant, scalar) uniform PassBlock { FullPass pc; };
layout(buffer_reference, scalar, buffer_reference_align = 8) writeonly buffer RecordRef { RadiosityRecord v[]; };

#define AOV_DIRECT 0u
#define AOV_INDIRECT_DIFFUSE 1u
#define AOV_REFLECTION 2u
#define AOV_PLANES 3u

// One loop traces one ray and shades one vertex per iteration, in the order (which fixes the
// random numbers) of the former recursion. Film: at the camera hit direct lighting, then its
// indirect diffuse (the diffuse chain, indirect.glsl), then the reflection chain; at each
// reflected point direct lighting, then its indirect diffuse. Update: camera hit, first bounce;
// at each path vertex direct lighting, then the diffuse chain from the next vertex, which the
// path then visits itself. The kernel so holds one closest-hit traversal and one
// direct_lighting() (with its shadow-ray traversal) for both passes, instead of one per call site
// and pass (the driver inlines every call: each copy is LLVM compile time).
#define RAY_CAMERA 0u
#define RAY_VERTEX 1u   // its hit is a path vertex: film, a reflection's; update, vertex v
#define RAY_DIFFUSE 2u  // its hit is a vertex of the diffuse chain
#define RAY_NEXT 3u     // update: the diffuse chain's first ray, whose hit is also vertex v + 1

void main() {
    bool update = pc.mode == FULL_PASS_UPDATE;
    uvec3 id = gl_GlobalInvocationID;
    // Film: the pixel and its sums. Update: the path and its records.
    uvec2 pix;
    uint pixel;
    FilmPixel acc;
    vec4 a_direct, a_indirect, a_reflection;
    RecordRef records = RecordRef(pc.update.records);
    uint path, base;
    if (update) {
        uint block = pc.update.block;
        uvec2 blocks = (uvec2(frame.width, frame.height) + block - 1u) / block;
        if (id.x >= blocks.x || id.y >= blocks.y) return;
        path = id.y * blocks.x + id.x;
        base = (id.z * blocks.x * blocks.y + path) * pc.update.vertices;
        RadiosityRecord none;
        none.value = vec3(0.0);
        none.valid = 0u;
        none.keys[0] = none.keys[1] = uvec2(0u);
        for (uint v = 0u; v < pc.update.vertices; ++v) records.v[base + v] = none;
    } else {
        if (id.x >= pc.film.tile.z || id.y >= pc.film.tile.w) return;
        pix = id.xy + pc.film.tile.xy;
        pixel = pix.y * frame.width + pix.x;
        acc = film[pixel];
        a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
        a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
        a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    }
    bool cache = radiosity_cache_on();
    uint rays = 0u;   // traced by this invocation (the rays-per-second figures)
    uint count = update ? 1u : pc.film.sample_count;
    for (uint k = 0u; k < count; ++k) {
        uint sample_index = pc.film.first_sample + k;
        Rng rng;
        vec3 d;
        if (update) {
            // A random stream apart from the camera samples' (another seed word).
            uint block = pc.update.block;
            rng = rng_init(pc.film.seed_lo ^ 0x5bd1e995u, pc.film.seed_hi, path, pc.update.index + id.z);
            vec2 size = vec2(frame.width, frame.height);
            vec2 film_uv = min(vec2(id.xy * block) + rng_next2(rng) * float(block), size * (1.0 - 1e-6)) / size;
            d = camera_direction(film_uv);
        } else {
            d = film_camera_ray(pc.film, pix, pixel, sample_index, rng);
        }
        vec3 o = frame.cam_origin.xyz;
        uint mask = MASK_GEOMETRY | MASK_LIGHTS;
        uint ray = RAY_CAMERA;
        bool trace = true;   // false: h is the next vertex's hit, traced already (update)
        Hit h;
        vec3 le = vec3(0.0), direct = vec3(0.0), indirect = vec3(0.0);
        GpuMaterial m;
        Shading sh;
        // The path vertex whose indirect diffuse is being gathered (film: the camera hit, then
        // the reflected points; update: vertex v) and its direct light.
        Shading sh_s;
        GpuMaterial m_s;
        vec3 direct_s = vec3(0.0);
        // Film: the reflection chain's sum, throughput and depth.
        bool at_camera = true;
        uint depth = 0u;
        vec3 sum_s = vec3(0.0), thr_s = vec3(1.0);
        // Update: the vertex index, ray cones (indirect.glsl), and vertex v + 1's ray and hit.
        uint v = 0u;
        float angle = pixel_spread(), width = 0.0, width_v = 0.0;
        Hit next;
        vec3 o_next = o, d_next = d;
        // The diffuse chain from the path vertex: its sum, throughput and vertex count.
        vec3 sum_d = vec3(0.0), thr_d = vec3(1.0);
        uint vertex_d = 0u;
        for (;;) {
            if (trace) {
                h = trace_closest(o, d, 0.0, INF, mask);
                rays += 1u;
            }
            trace = true;
            mask = MASK_OCCLUDERS;
            bool shade = false;        // direct lighting at (sh, m)
            bool diffuse_over = false; // the diffuse chain ends here
            bool bounce = false;       // a BRDF-sampled bounce from (sh_s, m_s) follows
            // The hit's surface and shading: one copy of that code for every kind of ray.
            Surface s;
            bool material = false;
            if (h.kind != HIT_NONE) {
                s = surface_at(h, o, d);
                if (s.material != NONE) {
                    m = get_material(s.material);
                    sh = shading_at(s, m, d);
                    material = true;
                }
            }
            if (ray == RAY_CAMERA && !update) {
                film_camera_aovs(h, s, material, sh, d, acc, le);
                if (!material) break;
                shade = true;
            } else {
                if (ray == RAY_CAMERA) {
                    // Update: the first bounce, from either lobe.
                    if (!material) break;
                    width = h.t * angle;
                    sh_s = sh;
                    m_s = m;
                    bounce = true;
                } else if (ray == RAY_VERTEX) {
                    if (update) {
                        if (v >= pc.update.vertices || h.kind == HIT_NONE) break;
                        width += h.t * angle;
                        if (!material || !(max3(sh.albedo) > 0.0)) break;
                        m.lobe_count = 0u;   // B of the diffuse lobe
                    }
                    if (!material) break;
                    shade = true;
                } else {
                    if (ray == RAY_NEXT) {
                        next = h;
                        o_next = o;
                        d_next = d;
                    }
                    diffuse_over = true;
                    if (material && vertex_d < RADIOSITY_BRUTE_MAX && max3(sh.albedo) > 0.0) {
                        // The cached value where the segment is longer than the cell.
                        float w = h.t * frame.diffuse_spread;
                        vec3 b;
                        if (cache && h.t > radiosity_cell_size(radiosity_level(w)) && radiosity_lookup(sh, w, rng, b)) {
                            sum_d += thr_d * b;
                        } else {
                            m.lobe_count = 0u;   // the diffuse lobe only
                            shade = true;
                            diffuse_over = false;
                        }
                    }
                }
            }
            vec3 dl = shade ? direct_lighting(sh, m, rng, rays) : vec3(0.0);
            if (shade && ray <= RAY_VERTEX) {
                // A path vertex: its direct light, then its diffuse chain.
                if (update) {
                    width_v = width;
                    next.kind = HIT_NONE;
                }
                if (ray == RAY_CAMERA) direct = film_clamp(dl, acc);
                else direct_s = dl;
                sh_s = sh;
                m_s = m;
                sum_d = vec3(0.0);
                thr_d = vec3(1.0);
                vertex_d = 0u;
                diffuse_over = true;
                if (max3(sh.albedo) > 0.0) diffuse_over = !diffuse_direction(sh, rng, d);
                ray = update ? RAY_NEXT : RAY_DIFFUSE;
            } else if (shade) {
                // A vertex of the diffuse chain: its direct light, then the next bounce.
                diffuse_over = !diffuse_chain_next(sh, dl, sum_d, thr_d, vertex_d, rng, d);
                ray = RAY_DIFFUSE;
            }
            if (diffuse_over && update) {
                // Vertex v is complete: its record; then the path goes on to the next vertex,
                // whose hit the chain's first ray found.
                vec3 value = direct_s;
                if (next.kind != HIT_NONE) value += sh_s.albedo * sum_d;
                RadiosityRecord r;
                r.value = value;
                r.valid = non_finite(value) ? 0u : 1u;
                uint level = radiosity_level(width_v);
                for (uint i = 0u; i < RADIOSITY_RECORD_KEYS; ++i)
                    r.keys[i] = radiosity_key(sh_s.p, sh_s.ng, radiosity_record_level(level, i));
                records.v[base + v] = r;
                v += 1u;
                o = o_next;
                d = d_next;
                h = next;
                trace = false;
                ray = RAY_VERTEX;
                angle = frame.diffuse_spread;
                width = 0.0;
                continue;
            }
            if (diffuse_over) {
                // Back at the film's path vertex: its indirect diffuse, then the next reflection.
                vec3 ind = sh_s.albedo * sum_d;
                if (at_camera) {
                    indirect = ind;
                    at_camera = false;
                } else {
                    sum_s += thr_s * (direct_s + ind);
                    depth += 1u;
                }
                if (depth >= frame.specular_depth) break;
                bounce = true;
            }
            if (bounce) {
                Bounce b = sample_bounce(sh_s, m_s, update, true, rng);
                if (!b.valid) break;
                if (!update) {
                    thr_s *= b.weight;
                } else if (b.diffuse) {
                    // Cones as the film pass's (indirect.glsl): a diffuse bounce starts a new one.
                    angle = b.spread;
                    width = 0.0;
                } else {
                    angle += b.spread;
                }
                d = b.wi;
                ray = RAY_VERTEX;
            }
            o = ray == RAY_VERTEX ? sh_s.origin : sh.origin;
        }
        if (update) break;
        vec3 reflected = sum_s;
        vec3 beauty = le + direct + indirect + reflected;
        if (!film_add(acc, sample_index, beauty, le)) le = direct = indirect = reflected = vec3(0.0);
        a_direct.rgb += le + direct;
        a_indirect.rgb += indirect;
        a_reflection.rgb += reflected;
    }
    if (update) return;
    acc.beauty_sq.w += float(rays);
    film[pixel] = acc;
    aovs[pixel * AOV_PLANES + AOV_DIRECT] = a_direct;
    aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE] = a_indirect;
    aovs[pixel * AOV_PLANES + AOV_REFLECTION] = a_reflection;
}
