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
// nothing: direct lighting has them. With INTEGRATOR_CAUSTICS the diffuse chain also goes on
// through the specular lobes it meets (full_diffuse_hit, lobe_chain_next), keeping the paths the
// course leaves out: light -> specular -> diffuse (caustics, and glossy surfaces seen by diffuse
// bounces).
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
// path then visits itself. The kernel so holds one closest-hit traversal, one direct_lighting()
// (with its shadow-ray traversal) and one sample_bounce() for both passes, instead of one per
// call site and pass (the driver inlines every call: each copy is LLVM compile time).
#define RAY_CAMERA 0u
#define RAY_VERTEX 1u   // its hit is a path vertex: film, a reflection's; update, vertex v
#define RAY_DIFFUSE 2u  // its hit is a vertex of the diffuse chain
#define RAY_NEXT 3u     // update: the diffuse chain's first ray, whose hit is also vertex v + 1

// The invocation's pixel (film pass) or path (update pass).
struct FullPixel {
    uvec2 pix;
    uint pixel;
    uint slot;           // its sums' place in the device film (film_slot)
    FilmPixel acc;       // its sums and AOV planes, as read from the film
    vec4 a_direct, a_indirect, a_reflection;
    uint path;           // update: the path, and the index of its first record
    uint base;
};

// The update pass's invocation: its block (xy) and update index (z), its workgroup rows
// interleaved as the film pass's are (film.glsl).
uvec3 update_id() {
    return uvec3(gl_GlobalInvocationID.x, interleaved_invocation_y(pc.update.row_step), gl_GlobalInvocationID.z);
}

// The invocation's pixel and its sums, or its path with its records cleared; false when it has
// none (outside the tile, or beyond the blocks).
bool full_begin(bool update, out FullPixel px) {
    uvec3 id = update_id();
    if (update) {
        uint block = pc.update.block;
        uvec2 blocks = (uvec2(frame.width, frame.height) + block - 1u) / block;
        if (id.x >= blocks.x || id.y >= blocks.y) return false;
        px.path = id.y * blocks.x + id.x;
        px.base = (id.z * blocks.x * blocks.y + px.path) * pc.update.vertices;
        RadiosityRecord none;
        none.value = vec3(0.0);
        none.valid = 0u;
        none.keys[0] = none.keys[1] = uvec2(0u);
        RecordRef records = RecordRef(pc.update.records);
        for (uint v = 0u; v < pc.update.vertices; ++v) records.v[px.base + v] = none;
        return true;
    }
    if (!film_pixel(pc.film, px.pix, px.pixel)) return false;
    px.slot = film_slot(px.pix);
    px.acc = film_load(pc.film, px.slot);
    px.a_direct = aov_load(pc.film, px.slot, AOV_PLANES, AOV_DIRECT);
    px.a_indirect = aov_load(pc.film, px.slot, AOV_PLANES, AOV_INDIRECT_DIFFUSE);
    px.a_reflection = aov_load(pc.film, px.slot, AOV_PLANES, AOV_REFLECTION);
    return true;
}

// A camera sample's path through the loop: the ray to trace and what its hit is, the path vertex
// whose indirect diffuse is being gathered, the reflection chain (film), the cones and the next
// vertex (update), the diffuse chain, and what this iteration does with its hit.
struct FullPath {
    vec3 o, d;
    uint mask;
    uint ray;            // RAY_*
    bool trace;          // false: h is the next vertex's hit, traced already (update)
    Hit h;
    vec3 le, direct, indirect;
    Shading sh;          // the hit's shading (its material is main's m)
    // The path vertex whose indirect diffuse is being gathered (film: the camera hit, then the
    // reflected points; update: vertex v; its material is main's m_s) and its direct light.
    Shading sh_s;
    vec3 direct_s;
    // Film: the reflection chain's sum, throughput and depth.
    bool at_camera;
    uint depth;
    vec3 sum_s, thr_s;
    // Update: the vertex index, ray cones (indirect.glsl), and vertex v + 1's ray and hit.
    uint v;
    float angle, width, width_v;
    Hit next;
    vec3 o_next, d_next;
    // The diffuse chain from the path vertex: its sum, throughput, vertex count and ray cone
    // (a diffuse bounce starts one; a specular bounce through a glossy hit widens it).
    vec3 sum_d, thr_d;
    uint vertex_d;
    float width_d, angle_d;
    // This iteration: direct lighting at the hit (of its diffuse lobe only, or of its specular
    // lobes only where the cache gave the diffuse lobe's), the end of the diffuse chain, a
    // BRDF-sampled bounce from the path vertex, and whether that bounce waits for the next
    // iteration (main's loop draws one bounce an iteration).
    bool shade, diffuse_only, specular_only, diffuse_over, bounce, resume;
};

// Sample `sample_index`'s camera ray (update: through a random point of the path's block, from a
// random stream apart from the camera samples', another seed word) and its path's start.
FullPath full_camera_ray(bool update, FullPixel px, uint sample_index, bool split, out Rng rng) {
    FullPath p;
    if (update) {
        uvec3 id = update_id();
        uint block = pc.update.block;
        rng = rng_init(pc.film.seed_lo ^ 0x5bd1e995u, pc.film.seed_hi, px.path, pc.update.index + id.z);
        vec2 size = vec2(frame.width, frame.height);
        vec2 film_uv = min(vec2(id.xy * block) + rng_next2(rng) * float(block), size * (1.0 - 1e-6)) / size;
        p.d = camera_direction(film_uv);
    } else {
        p.d = film_camera_ray(pc.film, px.pix, px.pixel, sample_index, split, rng);
    }
    p.o = frame.cam_origin.xyz;
    p.mask = MASK_GEOMETRY | MASK_LIGHTS;
    p.ray = RAY_CAMERA;
    p.trace = true;
    p.le = p.direct = p.indirect = vec3(0.0);
    p.direct_s = vec3(0.0);
    p.at_camera = true;
    p.depth = 0u;
    p.sum_s = vec3(0.0);
    p.thr_s = vec3(1.0);
    p.v = 0u;
    p.angle = pixel_spread();
    p.width = p.width_v = 0.0;
    p.o_next = p.o;
    p.d_next = p.d;
    p.sum_d = vec3(0.0);
    p.thr_d = vec3(1.0);
    p.vertex_d = 0u;
    p.width_d = 0.0;
    p.angle_d = frame.diffuse_spread;
    p.resume = false;
    return p;
}

// Whether the diffuse chain goes on through the specular lobes of material m (the light that
// reaches a diffuse surface through glossy and specular ones, L S+ D ...).
bool full_glossy(GpuMaterial m) {
    return (frame.integrator_flags & INTEGRATOR_CAUSTICS) != 0u && m.lobe_count > 0u;
}

// A hit of the diffuse chain (RAY_DIFFUSE, RAY_NEXT), material m: the cached B where the segment
// is longer than the cell, else direct lighting of its diffuse lobe in place; and where it has
// specular lobes, their direct light and a bounce from them (with the diffuse lobe's, in place);
// or the chain's end.
void full_diffuse_hit(bool cache, bool material, GpuMaterial m, inout FullPath p, inout Rng rng) {
    if (p.ray == RAY_NEXT) {
        p.next = p.h;
        p.o_next = p.o;
        p.d_next = p.d;
    }
    p.diffuse_over = true;
    if (!(material && p.vertex_d < RADIOSITY_BRUTE_MAX)) return;
    bool diffuse = max3(p.sh.albedo) > 0.0;
    bool glossy = full_glossy(m);
    if (!(diffuse || glossy)) return;
    p.width_d += p.h.t * p.angle_d;
    float w = p.width_d;
    vec3 b;
    if (diffuse && cache && p.h.t > radiosity_cell_size(radiosity_level(w)) && radiosity_lookup(p.sh, w, rng, b)) {
        p.sum_d += p.thr_d * b;
        if (!glossy) return;
        p.specular_only = true;
    } else if (!glossy) {
        p.diffuse_only = true;
    }
    p.shade = true;
    p.diffuse_over = false;
}

// What this iteration does with its hit (surface s, with a material or not), by the kind of ray:
// false where the path ends. The film's camera hit records its AOVs; the update pass's takes the
// first bounce.
bool full_visit(bool update, bool cache, Surface s, bool material, GpuMaterial m, inout FullPath p,
                inout FilmPixel acc, inout Rng rng) {
    p.shade = p.diffuse_only = p.specular_only = p.diffuse_over = p.bounce = false;
    if (p.ray == RAY_CAMERA && !update) {
        film_camera_aovs(p.h, s, material, p.sh, p.d, acc, p.le);
        p.shade = material;
        return material;
    }
    if (p.ray == RAY_CAMERA) {
        // Update: the first bounce, from either lobe.
        if (!material) return false;
        p.width = p.h.t * p.angle;
        p.sh_s = p.sh;
        p.bounce = true;
    } else if (p.ray == RAY_VERTEX) {
        if (update) {
            if (p.v >= pc.update.vertices || p.h.kind == HIT_NONE) return false;
            p.width += p.h.t * p.angle;
            if (!material || !(max3(p.sh.albedo) > 0.0)) return false;
            p.diffuse_only = true;   // B of the diffuse lobe
        }
        if (!material) return false;
        p.shade = true;
    } else {
        full_diffuse_hit(cache, material, m, p, rng);
    }
    return true;
}

// A path vertex, lit (dl): its direct light, then its diffuse chain's first ray.
void full_path_vertex(bool update, vec3 dl, inout FullPath p, inout FilmPixel acc, inout Rng rng) {
    if (update) {
        p.width_v = p.width;
        p.next.kind = HIT_NONE;
    }
    if (p.ray == RAY_CAMERA) p.direct = film_clamp(dl, acc);
    else p.direct_s = dl;
    p.sh_s = p.sh;
    p.sum_d = vec3(0.0);
    p.thr_d = vec3(1.0);
    p.vertex_d = 0u;
    p.width_d = 0.0;
    p.angle_d = frame.diffuse_spread;
    p.diffuse_over = true;
    if (max3(p.sh.albedo) > 0.0) p.diffuse_over = !diffuse_direction(p.sh, rng, p.d);
    p.ray = update ? RAY_NEXT : RAY_DIFFUSE;
}

// Update: vertex v is complete, its record written; the path goes on to the next vertex, whose hit
// the chain's first ray found.
void full_record(inout FullPath p, uint base) {
    vec3 value = p.direct_s;
    if (p.next.kind != HIT_NONE) value += p.sh_s.albedo * p.sum_d;
    RadiosityRecord r;
    r.value = value;
    r.valid = non_finite(value) ? 0u : 1u;
    uint level = radiosity_level(p.width_v);
    for (uint i = 0u; i < RADIOSITY_RECORD_KEYS; ++i)
        r.keys[i] = radiosity_key(p.sh_s.p, p.sh_s.ng, radiosity_record_level(level, i));
    RecordRef(pc.update.records).v[base + p.v] = r;
    p.v += 1u;
    p.o = p.o_next;
    p.d = p.d_next;
    p.h = p.next;
    p.trace = false;
    p.ray = RAY_VERTEX;
    p.angle = frame.diffuse_spread;
    p.width = 0.0;
}

// Film: back at the path vertex, its indirect diffuse, then the next reflection (false: the
// reflection chain is as deep as it may be).
bool full_gather(inout FullPath p) {
    vec3 ind = p.sh_s.albedo * p.sum_d;
    if (p.at_camera) {
        p.indirect = ind;
        p.at_camera = false;
    } else {
        p.sum_s += p.thr_s * (p.direct_s + ind);
        p.depth += 1u;
    }
    if (p.depth >= frame.specular_depth) return false;
    p.bounce = true;
    return true;
}

// The path vertex's BRDF-sampled bounce b: the reflection chain's throughput, or the update
// pass's cone (as the film pass's, indirect.glsl: a diffuse bounce starts a new one).
bool full_bounce(bool update, Bounce b, inout FullPath p) {
    if (!b.valid) return false;
    if (!update) {
        p.thr_s *= b.weight;
    } else if (b.diffuse) {
        p.angle = b.spread;
        p.width = 0.0;
    } else {
        p.angle += b.spread;
    }
    p.d = b.wi;
    p.ray = RAY_VERTEX;
    return true;
}

// Film: the sample's beauty and AOV planes.
void full_add_sample(inout FullPixel px, uint sample_index, bool split, FullPath p) {
    vec3 le = p.le, direct = p.direct, indirect = p.indirect, reflected = p.sum_s;
    vec3 beauty = le + direct + indirect + reflected;
    if (!film_add(px.acc, sample_index, split, beauty, le)) le = direct = indirect = reflected = vec3(0.0);
    px.a_direct.rgb += le + direct;
    px.a_indirect.rgb += indirect;
    px.a_reflection.rgb += reflected;
}

void main() {
    bool update = pc.mode == FULL_PASS_UPDATE;
    FullPixel px;
    if (!full_begin(update, px)) return;
    bool cache = radiosity_cache_on();
    uint rays = 0u;   // traced by this invocation (the rays-per-second figures)
    FilmSamples fs = update ? FilmSamples(pc.film.first_sample, 1u, true) : film_samples(pc.film, px.pix, px.pixel);
    for (uint k = 0u; k < fs.count; ++k) {
        uint sample_index = fs.first + k;
        Rng rng;
        FullPath p = full_camera_ray(update, px, sample_index, fs.split, rng);
        GpuMaterial m;     // the hit's material
        GpuMaterial m_s;   // the path vertex's
        for (;;) {
            // The path vertex's bounce, left for this iteration by the last one (below): nothing
            // else happens in it.
            bool resume = p.resume;
            p.resume = false;
            bool chain = false;   // this iteration's bounce is the diffuse chain's, from a glossy hit
            if (!resume) {
                if (p.trace) {
                    p.h = trace_closest(p.o, p.d, 0.0, INF, p.mask);
                    rays += 1u;
                }
                p.trace = true;
                p.mask = MASK_OCCLUDERS;
                // The hit's surface and shading: one copy of that code for every kind of ray.
                Surface s;
                bool material = false;
                if (p.h.kind != HIT_NONE) {
                    s = surface_at(p.h, p.o, p.d);
                    if (s.material != NONE) {
                        m = get_material(s.material);
                        p.sh = shading_at(s, m, p.d);
                        material = true;
                    }
                }
                if (!full_visit(update, cache, s, material, m, p, px.acc, rng)) break;
                if (p.diffuse_only) m.lobe_count = 0u;
                if (p.specular_only) p.sh.albedo = vec3(0.0);
                vec3 dl = p.shade ? direct_lighting(p.sh, m, rng, rays) : vec3(0.0);
                // The hit becomes the path vertex where it is lit as one (and at the update pass's
                // first bounce); else a lit hit is a vertex of the diffuse chain.
                bool vertex = p.shade && p.ray <= RAY_VERTEX;
                if (vertex || p.bounce) m_s = m;
                if (vertex) {
                    full_path_vertex(update, dl, p, px.acc, rng);
                } else if (p.shade) {
                    // A vertex of the diffuse chain: its direct light, then the next bounce.
                    if (full_glossy(m)) {
                        p.sum_d += p.thr_d * dl;
                        chain = true;
                    } else {
                        p.diffuse_over = !diffuse_chain_next(p.sh, dl, p.sum_d, p.thr_d, p.vertex_d,
                                                             rng, p.d, p.width_d, p.angle_d);
                    }
                    p.ray = RAY_DIFFUSE;
                }
                if (!chain && p.diffuse_over && update) {
                    full_record(p, px.base);
                    continue;
                }
                if (!chain && p.diffuse_over && !full_gather(p)) break;
            }
            // One BRDF-sampled bounce an iteration, so that the kernel holds one sample_bounce (each
            // call site is inlined: LLVM compile time): a glossy vertex's of the diffuse chain, or the
            // path vertex's. Where the chain ends at a glossy vertex and the path vertex then bounces,
            // that bounce takes the next iteration (p.resume), its random numbers in the same order.
            if (chain || p.bounce) {
                Bounce b = sample_bounce(chain ? p.sh : p.sh_s, chain ? m : m_s, chain || update, true,
                                         rng);
                if (chain) {
                    p.d = b.wi;
                    p.diffuse_over =
                        !lobe_chain_next(b, p.thr_d, p.vertex_d, rng, p.width_d, p.angle_d);
                    if (p.diffuse_over && update) {
                        full_record(p, px.base);
                        continue;
                    }
                    if (p.diffuse_over) {
                        if (!full_gather(p)) break;
                        p.resume = true;
                        continue;
                    }
                } else if (!full_bounce(update, b, p)) {
                    break;
                }
            }
            p.o = p.ray == RAY_VERTEX ? p.sh_s.origin : p.sh.origin;
        }
        if (update) break;
        full_add_sample(px, sample_index, fs.split, p);
    }
    if (update) return;
    px.acc.beauty_sq.w += float(rays);
    film_store(pc.film, px.slot, px.acc);
    aov_store(pc.film, px.slot, AOV_PLANES, AOV_DIRECT, px.a_direct);
    aov_store(pc.film, px.slot, AOV_PLANES, AOV_INDIRECT_DIFFUSE, px.a_indirect);
    aov_store(pc.film, px.slot, AOV_PLANES, AOV_REFLECTION, px.a_reflection);
}
