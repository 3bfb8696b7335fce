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
    uint width = frame.width, height = frame.height;
    uint pixel = pix.y * width + pix.x;
    FilmPixel acc = film[pixel];
    vec4 a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
    vec4 a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
    vec4 a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    float clamp_luminance = frame.clamp_luminance;
    uint inject = frame.nan_every;
    uint max_depth = frame.max_depth;
    for (uint k = 0u; k < pc.sample_count; ++k) {
        Rng rng = rng_init(pc.seed_lo, pc.seed_hi, pixel, pc.first_sample + k);
        vec2 film_uv = (vec2(pix) + rng_next2(rng)) / vec2(width, height);
        vec3 d = camera_direction(film_uv);
        vec3 o = frame.cam_origin.xyz;
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        g_rays += 1u;
        vec3 le = vec3(0.0), direct = vec3(0.0), rest = vec3(0.0);
        bool first_diffuse = false;
        if (h.kind == HIT_NONE) {
            le = dome_radiance(d);
        } else {
            Surface s = surface_at(h, o, d);
            le = surface_emission(s, d);
            acc.normal += vec4(s.ns, h.t);
            if (s.material != NONE) {
                GpuMaterial m = get_material(s.material);
                Shading sh = shading_at(s, m, d);
                acc.albedo += vec4(sh.albedo, 1.0);
                if (max_depth >= 2u) direct = direct_lighting(sh, m, rng);
                float y = luminance(direct);
                if (clamp_luminance > 0.0 && y > clamp_luminance) {
                    direct *= clamp_luminance / y;
                    acc.beauty.w += 1.0;
                }
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
            } else {
                acc.albedo.w += 1.0;
            }
        }
        vec3 beauty = le + direct + rest;
        if (inject != 0u && (pc.first_sample + k) % inject == 0u) beauty.g = uintBitsToFloat(0x7fc00000u);
        if (non_finite(beauty)) {
            acc.emission.w += 1.0;
            beauty = le = direct = rest = vec3(0.0);
        }
        acc.emission.rgb += le;
        acc.beauty.rgb += beauty;
        acc.beauty_sq.rgb += beauty * beauty;
        if (((pc.first_sample + k) & 1u) == 1u) acc.beauty_odd.rgb += beauty;
        a_direct.rgb += le + direct;
        if (first_diffuse) a_indirect.rgb += rest; else a_reflection.rgb += rest;
    }
    acc.beauty_sq.w += float(g_rays);
    film[pixel] = acc;
    aovs[pixel * AOV_PLANES + AOV_DIRECT] = a_direct;
    aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE] = a_indirect;
    aovs[pixel * AOV_PLANES + AOV_REFLECTION] = a_reflection;
}
