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

// The rays of one camera sample, in this order (which fixes the random numbers): at the camera
// hit direct lighting, then its indirect diffuse (the diffuse chain, indirect.glsl), then the
// reflection chain; at each reflected point direct lighting, then its indirect diffuse. One loop
// traces one ray and shades one vertex per iteration: the kernel then holds one closest-hit traversal and one
// direct_lighting() (with its shadow-ray traversal) instead of one per call site (the driver
// inlines every call: each copy is LLVM compile time, issue 15 item 4).
#define RAY_CAMERA 0u
#define RAY_SPECULAR 1u   // a reflection bounce: its hit is a specular vertex
#define RAY_DIFFUSE 2u    // the diffuse chain: its hit is a diffuse vertex

void main() {
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= pc.tile.z || local.y >= pc.tile.w) return;
    uvec2 pix = local + pc.tile.xy;
    uint pixel = pix.y * frame.width + pix.x;
    FilmPixel acc = film[pixel];
    vec4 a_direct = aovs[pixel * AOV_PLANES + AOV_DIRECT];
    vec4 a_indirect = aovs[pixel * AOV_PLANES + AOV_INDIRECT_DIFFUSE];
    vec4 a_reflection = aovs[pixel * AOV_PLANES + AOV_REFLECTION];
    bool cache = radiosity_cache_on();
    for (uint k = 0u; k < pc.sample_count; ++k) {
        uint sample_index = pc.first_sample + k;
        Rng rng;
        vec3 d = film_camera_ray(pc, pix, pixel, sample_index, rng);
        vec3 o = frame.cam_origin.xyz;
        uint mask = MASK_GEOMETRY | MASK_LIGHTS;
        uint ray = RAY_CAMERA;
        vec3 le = vec3(0.0), direct = vec3(0.0), indirect = vec3(0.0);
        GpuMaterial m;
        Shading sh;
        // The specular vertex whose indirect diffuse is being gathered (the camera hit first),
        // and the reflection chain's sum and throughput, and the vertex's direct light.
        Shading sh_s;
        GpuMaterial m_s;
        bool at_camera = true;
        uint depth = 0u;
        vec3 sum_s = vec3(0.0), thr_s = vec3(1.0), direct_s = vec3(0.0);
        // The diffuse chain from it: its sum, throughput and vertex count.
        vec3 sum_d = vec3(0.0), thr_d = vec3(1.0);
        uint vertex_d = 0u;
        for (;;) {
            Hit h = trace_closest(o, d, 0.0, INF, mask);
            g_rays += 1u;
            bool shade = false;        // direct lighting at (sh, m)
            bool diffuse_over = false; // the diffuse chain ends here
            bool specular_over = false;
            if (ray == RAY_CAMERA) {
                if (!film_camera_hit(h, o, d, acc, le, m, sh)) break;
                shade = true;
            } else if (ray == RAY_SPECULAR) {
                specular_over = true;
                if (h.kind != HIT_NONE) {
                    Surface s = surface_at(h, o, d);
                    if (s.material != NONE) {
                        m = get_material(s.material);
                        sh = shading_at(s, m, d);
                        shade = true;
                        specular_over = false;
                    }
                }
            } else {
                diffuse_over = true;
                if (h.kind != HIT_NONE && vertex_d < RADIOSITY_BRUTE_MAX) {
                    Surface s = surface_at(h, o, d);
                    if (s.material != NONE) {
                        m = get_material(s.material);
                        sh = shading_at(s, m, d);
                        if (max3(sh.albedo) > 0.0) {
                            // The cached value where the segment is longer than the cell.
                            float width = h.t * frame.diffuse_spread;
                            vec3 b;
                            if (cache && h.t > radiosity_cell_size(radiosity_level(width)) && radiosity_lookup(sh, width, rng, b)) {
                                sum_d += thr_d * b;
                            } else {
                                m.lobe_count = 0u;   // the diffuse lobe only
                                shade = true;
                                diffuse_over = false;
                            }
                        }
                    }
                }
            }
            vec3 dl = shade ? direct_lighting(sh, m, rng) : vec3(0.0);
            if (shade && ray != RAY_DIFFUSE) {
                // A specular vertex (or the camera hit): its direct light, then its diffuse chain.
                if (ray == RAY_CAMERA) direct = film_clamp(dl, acc);
                else direct_s = dl;
                sh_s = sh;
                m_s = m;
                sum_d = vec3(0.0);
                thr_d = vec3(1.0);
                vertex_d = 0u;
                diffuse_over = true;
                if (max3(sh.albedo) > 0.0) diffuse_over = !diffuse_direction(sh, rng, d);
            } else if (shade) {
                // A diffuse vertex of the chain: its direct light, then the next bounce.
                diffuse_over = !diffuse_chain_next(sh, dl, sum_d, thr_d, vertex_d, rng, d);
            }
            if (diffuse_over) {
                // Back at the specular vertex: its indirect diffuse, then the next reflection.
                vec3 id = sh_s.albedo * sum_d;
                if (at_camera) {
                    indirect = id;
                    at_camera = false;
                } else {
                    sum_s += thr_s * (direct_s + id);
                    depth += 1u;
                }
                specular_over = true;
                if (depth < frame.specular_depth) {
                    Bounce b = sample_bounce(sh_s, m_s, false, true, rng);
                    if (b.valid) {
                        thr_s *= b.weight;
                        d = b.wi;
                        ray = RAY_SPECULAR;
                        specular_over = false;
                    }
                }
            } else if (!specular_over) {
                ray = RAY_DIFFUSE;
            }
            if (specular_over) break;
            o = ray == RAY_SPECULAR ? sh_s.origin : sh.origin;
            mask = MASK_OCCLUDERS;
        }
        vec3 reflected = sum_s;
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
