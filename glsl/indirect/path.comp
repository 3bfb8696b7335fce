// illum-variants: rq bvh
// A brute-force unidirectional path tracer, the reference the radiosity cache is measured
// against (Mitsuba 3's and pbrt-v4's `path`): at every vertex direct lighting by
// direct_lighting() (light and BRDF samples combined by MIS, as at the camera hit), then one
// continuation from the lobes (indirect.glsl), Russian roulette from the fifth vertex on (Mitsuba
// 3's rr_depth 5: docs/indirect.md says what the third cost).
// frame.max_depth counts path segments as Mitsuba's max_depth does: 1 = emission seen directly,
// 2 = direct lighting, NONE = unbounded. AOVs: Direct (emission seen directly and direct lighting
// at the camera hit), IndirectDiffuse and Reflection (paths whose first bounce took the diffuse
// or a specular lobe).
#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#include "shared/layout.glsl"
#include "trace/trace.glsl"
#include "direct/direct.glsl"
#include "indirect/indirect.glsl"
#include "film/film.glsl"
#include "shared/profile.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(push_constant, scalar) uniform PassBlock { PassConstants pc; };

#define AOV_DIRECT 0u
#define AOV_INDIRECT_DIFFUSE 1u
#define AOV_REFLECTION 2u
#define AOV_PLANES 3u

void main() {
    uvec2 pix;
    uint pixel;
    if (!film_pixel(pc, pix, pixel)) return;
    uint slot = film_slot(pix);
    FilmPixel acc = film_load(pc, slot);
    vec4 a_direct = aov_load(pc, slot, AOV_PLANES, AOV_DIRECT);
    vec4 a_indirect = aov_load(pc, slot, AOV_PLANES, AOV_INDIRECT_DIFFUSE);
    vec4 a_reflection = aov_load(pc, slot, AOV_PLANES, AOV_REFLECTION);
    uint max_depth = frame.max_depth;
    uint rays = 0u;   // traced by this invocation (the rays-per-second figures)
    FilmSamples fs = film_samples(pc, pix, pixel);
    // One loop over the vertices of all the pixel's samples: where a path ends, the next sample
    // starts in the same iteration order (path regeneration, Novák et al. 2010), so that the
    // lanes of a SIMD group wait for the longest sum of path lengths, not for the longest path
    // of every sample. Each sample's arithmetic, random numbers and order are as in a loop per
    // sample: the same pixels bit for bit. One ray and one vertex per iteration (the camera hit
    // is vertex 1): the kernel holds one closest-hit traversal and one direct_lighting()
    // (full.comp says why). Direct lighting at vertex `depth` takes depth + 1 segments.
    uint k = 0u;
    uint depth = 0u;   // 0: sample k starts
    uint sample_index;
    Rng rng;
    vec3 o, d, le, direct, rest, thr;
    bool first_diffuse;
    GpuMaterial m;
    Shading sh;
    uint mask;
    PROF_START();
    while (k < fs.count) {
        if (depth == 0u) {
            sample_index = fs.first + k;
            d = film_camera_ray(pc, pix, pixel, sample_index, fs.split, rng);
            o = frame.cam_origin.xyz;
            le = direct = rest = vec3(0.0);
            thr = vec3(1.0);
            first_diffuse = false;
            mask = MASK_GEOMETRY | MASK_LIGHTS;
            depth = 1u;
            PROF(PROF_CAMERA_RAY);
        }
        // Set afresh each iteration: otherwise the vertex's material and frame are carried
        // around the loop on the paths that leave them unset (spilled every iteration).
        m = no_material();
        sh = no_shading();
        PROF(PROF_BOUNCE);
        Hit h = trace_closest(o, d, 0.0, INF, mask);
        rays += 1u;
        if (depth == 1u) PROF(PROF_CAMERA_TRACE); else PROF(PROF_BOUNCE_TRACE);
        bool go = true;
        bool shade = true;
        if (depth == 1u) {
            go = film_camera_hit(h, o, d, acc, le, m, sh);
            shade = max_depth >= 2u;
        } else if (h.kind == HIT_NONE) {
            go = false;
        } else {
            Surface s = surface_at(h, o, d);
            go = s.material != NONE;
            if (go) {
                m = get_material(s.material);
                sh = shading_at(s, m, d);
            }
        }
        if (depth == 1u) PROF(PROF_CAMERA_SHADE); else PROF(PROF_BOUNCE_SHADE);
        if (go) {
            vec3 dl = shade ? direct_lighting(sh, m, rng, rays) : vec3(0.0);
            if (depth == 1u) direct = film_clamp(dl, acc);
            else rest += thr * dl;
            go = depth < PATH_MAX_VERTICES && depth + 2u <= max_depth;
        }
        if (go) {
            Bounce b = sample_bounce(sh, m, true, true, rng);
            go = b.valid;
            if (go) {
                if (depth == 1u) first_diffuse = b.diffuse;
                thr *= b.weight;
                if (depth >= 5u) go = russian_roulette(thr, rng);
                o = sh.origin;
                d = b.wi;
                mask = MASK_OCCLUDERS;
            }
        }
        PROF(PROF_BOUNCE);
        if (go) {
            depth += 1u;
            continue;
        }
        // Sample k is complete.
        vec3 beauty = le + direct + rest;
        if (!film_add(acc, sample_index, fs.split, beauty, le)) le = direct = rest = vec3(0.0);
        a_direct.rgb += le + direct;
        if (first_diffuse) a_indirect.rgb += rest; else a_reflection.rgb += rest;
        k += 1u;
        depth = 0u;
        PROF(PROF_FILM);
    }
    acc.beauty_sq.w += float(rays);
    film_store(pc, slot, acc);
    aov_store(pc, slot, AOV_PLANES, AOV_DIRECT, a_direct);
    aov_store(pc, slot, AOV_PLANES, AOV_INDIRECT_DIFFUSE, a_indirect);
    aov_store(pc, slot, AOV_PLANES, AOV_REFLECTION, a_reflection);
    PROF_END(frame.profile, slot);
}
