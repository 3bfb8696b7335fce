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
#include "indirect.glsl"
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
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= pc.tile.z || local.y >= pc.tile.w) return;
    uvec2 pix = local + pc.tile.xy;
    uint pixel = pix.y * frame.width + pix.x;
    FilmPixel acc = film[pixel];
    vec4 a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
    vec4 a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
    vec4 a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    uint max_depth = frame.max_depth;
    for (uint k = 0u; k < pc.sample_count; ++k) {
        uint sample_index = pc.first_sample + k;
        Rng rng;
        vec3 d = film_camera_ray(pc, pix, pixel, sample_index, rng);
        vec3 o = frame.cam_origin.xyz;
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        g_rays += 1u;
        vec3 le, direct = vec3(0.0), rest = vec3(0.0);
        bool first_diffuse = false;
        GpuMaterial m;
        Shading sh;
        if (film_camera_hit(h, o, d, acc, le, m, sh)) {
            if (max_depth >= 2u) direct = direct_lighting(sh, m, rng);
            direct = film_clamp(direct, acc);
            vec3 thr = vec3(1.0);
            // sh is vertex `depth` (the camera hit is 1); direct lighting at the next vertex
            // takes depth + 2 segments.
            for (uint depth = 1u; depth < PATH_MAX_VERTICES && depth + 2u <= max_depth; ++depth) {
                Bounce b = sample_bounce(sh, m, true, true, rng);
                if (!b.valid) break;
                if (depth == 1u) first_diffuse = b.diffuse;
                thr *= b.weight;
                if (depth >= 3u) {
                    float q = min(max3(thr), 0.95);
                    if (rng_next(rng) >= q) break;
                    thr /= q;
                }
                Hit hn = trace_closest(sh.origin, b.wi, 0.0, INF, MASK_OCCLUDERS);
                g_rays += 1u;
                if (hn.kind == HIT_NONE) break;
                Surface sn = surface_at(hn, sh.origin, b.wi);
                if (sn.material == NONE) break;
                m = get_material(sn.material);
                sh = shading_at(sn, m, b.wi);
                rest += thr * direct_lighting(sh, m, rng);
            }
        }
        vec3 beauty = le + direct + rest;
        if (!film_add(acc, sample_index, beauty, le)) le = direct = rest = vec3(0.0);
        a_direct.rgb += le + direct;
        if (first_diffuse) a_indirect.rgb += rest; else a_reflection.rgb += rest;
    }
    acc.beauty_sq.w += float(g_rays);
    film[pixel] = acc;
    aovs[pixel * AOV_PLANES + AOV_DIRECT] = a_direct;
    aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE] = a_indirect;
    aovs[pixel * AOV_PLANES + AOV_REFLECTION] = a_reflection;
}
