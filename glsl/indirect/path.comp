// illum-variants: rq bvh
// A brute-force unidirectional path tracer, the reference the radiosity cache is measured
// against (Mitsuba 3's and pbrt-v4's `path`): at every vertex direct lighting by
// direct_lighting() (light and BRDF samples combined by MIS, as at the camera hit), then one
// continuation from the lobes (indirect.glsl), Russian roulette from the third bounce on.
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

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_FILM) buffer FilmBlock { FilmPixel film[]; };
layout(scalar, binding = BINDING_AOVS) buffer AovBlock { vec4 aovs[]; };
layout(push_constant, scalar) uniform PassBlock { PassConstants pc; };

#define AOV_DIRECT 0u
#define AOV_INDIRECT_DIFFUSE 1u
#define AOV_REFLECTION 2u
#define AOV_PLANES 3u

void main() {
    uvec2 pix;
    uint pixel;
    if (!film_pixel(pc, pix, pixel)) return;
    FilmPixel acc = film[pixel];
    vec4 a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
    vec4 a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
    vec4 a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    uint max_depth = frame.max_depth;
    uint rays = 0u;   // traced by this invocation (the rays-per-second figures)
    uint samples = film_sample_count(pc, pixel);
    for (uint k = 0u; k < samples; ++k) {
        uint sample_index = pc.first_sample + k;
        Rng rng;
        vec3 d = film_camera_ray(pc, pix, pixel, sample_index, rng);
        vec3 o = frame.cam_origin.xyz;
        vec3 le = vec3(0.0), direct = vec3(0.0), rest = vec3(0.0), thr = vec3(1.0);
        bool first_diffuse = false;
        GpuMaterial m;
        Shading sh;
        uint mask = MASK_GEOMETRY | MASK_LIGHTS;
        // One ray and one vertex per iteration (the camera hit is vertex 1): the kernel holds one
        // closest-hit traversal and one direct_lighting() (full.comp says why). Direct lighting
        // at vertex `depth` takes depth + 1 segments.
        for (uint depth = 1u;; ++depth) {
            Hit h = trace_closest(o, d, 0.0, INF, mask);
            rays += 1u;
            bool shade = true;
            if (depth == 1u) {
                if (!film_camera_hit(h, o, d, acc, le, m, sh)) break;
                shade = max_depth >= 2u;
            } else {
                if (h.kind == HIT_NONE) break;
                Surface s = surface_at(h, o, d);
                if (s.material == NONE) break;
                m = get_material(s.material);
                sh = shading_at(s, m, d);
            }
            vec3 dl = shade ? direct_lighting(sh, m, rng, rays) : vec3(0.0);
            if (depth == 1u) direct = film_clamp(dl, acc);
            else rest += thr * dl;
            if (!(depth < PATH_MAX_VERTICES && depth + 2u <= max_depth)) break;
            Bounce b = sample_bounce(sh, m, true, true, rng);
            if (!b.valid) break;
            if (depth == 1u) first_diffuse = b.diffuse;
            thr *= b.weight;
            if (depth >= 3u) {
                float q = min(max3(thr), 0.95);
                if (rng_next(rng) >= q) break;
                thr /= q;
            }
            o = sh.origin;
            d = b.wi;
            mask = MASK_OCCLUDERS;
        }
        vec3 beauty = le + direct + rest;
        if (!film_add(acc, sample_index, beauty, le)) le = direct = rest = vec3(0.0);
        a_direct.rgb += le + direct;
        if (first_diffuse) a_indirect.rgb += rest; else a_reflection.rgb += rest;
    }
    acc.beauty_sq.w += float(rays);
    film[pixel] = acc;
    aovs[pixel * AOV_PLANES + AOV_DIRECT] = a_direct;
    aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE] = a_indirect;
    aovs[pixel * AOV_PLANES + AOV_REFLECTION] = a_reflection;
}
