// illum-variants: rq bvh
// The seed's split of the rendering equation (TECHNIQUES.md §6.5), one camera sample at a time:
// at the camera hit x1, emission seen directly plus direct lighting exactly as primary.comp does
// (the Direct AOV); the diffuse lobe's indirect light by one cosine-sampled ray whose hit returns
// its outgoing diffuse radiance, from the radiosity cache or by brute force (IndirectDiffuse); and
// the specular lobes' indirect light by the reflection integrator (Reflection): a specular chain of
// up to frame.specular_depth BRDF-sampled bounces, each reflected point shaded like a camera hit
// (direct lighting in full, its indirect diffuse through the cache). Rays that reach a light or
// the sky add nothing: direct lighting has them. Paths light -> specular -> diffuse -> eye
// (caustics) are left out, as in the course.
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

// Light arriving at sh through its specular lobes: the reflection integrator.
vec3 reflection(Shading sh, GpuMaterial m, float width, float angle, inout Rng rng) {
    vec3 sum = vec3(0.0), thr = vec3(1.0);
    for (uint depth = 0u; depth < frame.specular_depth; ++depth) {
        Bounce b = sample_bounce(sh, m, false, true, rng);
        if (!b.valid) break;
        thr *= b.weight;
        Hit h = trace_closest(sh.origin, b.wi, 0.0, INF, MASK_OCCLUDERS);
        g_rays += 1u;
        if (h.kind == HIT_NONE) break;
        Surface s = surface_at(h, sh.origin, b.wi);
        if (s.material == NONE) break;
        angle += b.spread;
        width += h.t * angle;
        m = get_material(s.material);
        sh = shading_at(s, m, b.wi);
        sum += thr * (direct_lighting(sh, m, rng) + indirect_diffuse(sh, rng));
    }
    return sum;
}

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
    float spread = pixel_spread();
    for (uint k = 0u; k < pc.sample_count; ++k) {
        Rng rng = rng_init(pc.seed_lo, pc.seed_hi, pixel, pc.first_sample + k);
        vec2 film_uv = (vec2(pix) + rng_next2(rng)) / vec2(width, height);
        vec3 d = camera_direction(film_uv);
        vec3 o = frame.cam_origin.xyz;
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        g_rays += 1u;
        vec3 le = vec3(0.0), direct = vec3(0.0), indirect = vec3(0.0), reflected = vec3(0.0);
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
                direct = direct_lighting(sh, m, rng);
                float y = luminance(direct);
                if (clamp_luminance > 0.0 && y > clamp_luminance) {
                    direct *= clamp_luminance / y;
                    acc.beauty.w += 1.0;
                }
                indirect = indirect_diffuse(sh, rng);
                reflected = reflection(sh, m, h.t * spread, spread, rng);
            } else {
                acc.albedo.w += 1.0;
            }
        }
        vec3 beauty = le + direct + indirect + reflected;
        if (inject != 0u && (pc.first_sample + k) % inject == 0u) beauty.g = uintBitsToFloat(0x7fc00000u);
        if (non_finite(beauty)) {
            acc.emission.w += 1.0;
            beauty = le = direct = indirect = reflected = vec3(0.0);
        }
        acc.emission.rgb += le;
        acc.beauty.rgb += beauty;
        acc.beauty_sq.rgb += beauty * beauty;
        if (((pc.first_sample + k) & 1u) == 1u) acc.beauty_odd.rgb += beauty;
        a_direct.rgb += le + direct;
        a_indirect.rgb += indirect;
        a_reflection.rgb += reflected;
    }
    acc.beauty_sq.w += float(g_rays);
    film[pixel] = acc;
    aovs[pixel * AOV_PLANES + AOV_DIRECT] = a_direct;
    aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE] = a_indirect;
    aovs[pixel * AOV_PLANES + AOV_REFLECTION] = a_reflection;
}
