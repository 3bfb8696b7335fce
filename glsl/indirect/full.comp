// illum-variants: rq bvh
// The seed's split of the rendering equation (TECHNIQUES.md §6.5), one camera sample_index at a time:
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
#include "film/film.glsl"

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
    uint pixel = pix.y * frame.width + pix.x;
    FilmPixel acc = film[pixel];
    vec4 a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
    vec4 a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
    vec4 a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    float spread = pixel_spread();
    for (uint k = 0u; k < pc.sample_count; ++k) {
        uint sample_index = pc.first_sample + k;
        Rng rng;
        vec3 d = film_camera_ray(pc, pix, pixel, sample_index, rng);
        vec3 o = frame.cam_origin.xyz;
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        g_rays += 1u;
        vec3 le, direct = vec3(0.0), indirect = vec3(0.0), reflected = vec3(0.0);
        GpuMaterial m;
        Shading sh;
        if (film_camera_hit(h, o, d, acc, le, m, sh)) {
            direct = film_clamp(direct_lighting(sh, m, rng), acc);
            indirect = indirect_diffuse(sh, rng);
            reflected = reflection(sh, m, h.t * spread, spread, rng);
        }
        vec3 beauty = le + direct + indirect + reflected;
        if (!film_add(acc, sample_index, beauty, le)) le = direct = indirect = reflected = vec3(0.0);
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
