// illum-variants: rq bvh
// Update samples of the radiosity cache (src/render/indirect/radiosity.rs). One path per block x
// block pixels and update index: a camera ray through a random point of the block, a first bounce
// chosen as the full integrator's camera hit chooses (diffuse or specular lobe), then up to
// pc.vertices diffuse vertices. At each it writes a record of B = rho/pi E: direct lighting of
// the diffuse lobe plus one cosine-sampled bounce whose hit reads the cache's current table (the
// previous generation: one Jacobi iteration of the radiosity equation per generation, TECHNIQUES
// §6.3), filed under its cell's keys at the cone width the render's lookups there will have. The
// host averages the records into the next generation's table.
#version 460
#include "indirect.glsl"
#include "film/film.glsl"

layout(local_size_x = 64) in;
layout(push_constant, scalar) uniform PassBlock { RadiosityPass pc; };
layout(buffer_reference, scalar, buffer_reference_align = 8) writeonly buffer RecordRef { RadiosityRecord v[]; };

#define RAY_CAMERA 0u
#define RAY_VERTEX 1u   // its hit is the path's vertex v
#define RAY_NEXT 2u     // from vertex v: its hit is vertex v + 1 and the diffuse chain's first
#define RAY_CHAIN 3u    // the diffuse chain's next bounce (indirect.glsl)

void main() {
    uint path = gl_GlobalInvocationID.x;
    if (path >= pc.paths) return;
    uint round = gl_GlobalInvocationID.y;
    RecordRef records = RecordRef(pc.records);
    uint base = (round * pc.paths + path) * pc.vertices;
    RadiosityRecord none;
    none.value = vec3(0.0);
    none.valid = 0u;
    none.keys[0] = none.keys[1] = uvec2(0u);
    for (uint v = 0u; v < pc.vertices; ++v) records.v[base + v] = none;

    // A random stream apart from the camera samples' (another seed word).
    Rng rng = rng_init(pc.seed_lo ^ 0x5bd1e995u, pc.seed_hi, path, pc.index + round);
    uint blocks_x = (frame.width + pc.block - 1u) / pc.block;
    vec2 corner = vec2(uvec2(path % blocks_x, path / blocks_x) * pc.block);
    vec2 size = vec2(frame.width, frame.height);
    vec2 film_uv = min(corner + rng_next2(rng) * float(pc.block), size * (1.0 - 1e-6)) / size;
    vec3 d = camera_direction(film_uv);
    vec3 o = frame.cam_origin.xyz;
    uint mask = MASK_GEOMETRY | MASK_LIGHTS;
    // One loop, one ray and one vertex per iteration, in the order (and with the random numbers)
    // of "camera hit, first bounce; at each path vertex direct lighting, then the diffuse chain
    // (indirect.glsl) from the next vertex, which the path then visits itself": the kernel holds one closest-hit
    // traversal and one direct_lighting() (full.comp says why).
    uint ray = RAY_CAMERA;
    bool trace = true;
    Hit h;
    float angle = pixel_spread();
    float width = 0.0;
    uint v = 0u;
    GpuMaterial m;
    Shading sh;
    // The path's vertex v: its shading, record value and cone width; the next vertex's ray and hit.
    Shading sh_v;
    vec3 value = vec3(0.0);
    float width_v = 0.0;
    Hit next;
    vec3 o_next = o, d_next = d;
    // The diffuse chain from the next vertex.
    vec3 sum_d = vec3(0.0), thr_d = vec3(1.0);
    uint vertex_d = 0u;
    for (;;) {
        if (trace) {
            h = trace_closest(o, d, 0.0, INF, mask);
            g_rays += 1u;
        }
        trace = true;
        mask = MASK_OCCLUDERS;
        if (ray == RAY_CAMERA) {
            if (h.kind == HIT_NONE) return;
            Surface s = surface_at(h, o, d);
            if (s.material == NONE) return;
            m = get_material(s.material);
            sh = shading_at(s, m, d);
            width = h.t * angle;
            Bounce b = sample_bounce(sh, m, true, true, rng);
            if (!b.valid) return;
            // Cones as the full integrator's (indirect.glsl): a diffuse bounce starts a new one.
            if (b.diffuse) {
                angle = b.spread;
                width = 0.0;
            } else {
                angle += b.spread;
            }
            o = sh.origin;
            d = b.wi;
            ray = RAY_VERTEX;
            continue;
        }
        bool shade = false;
        bool diffuse_over = true;   // the diffuse chain is done
        if (ray == RAY_VERTEX) {
            if (v >= pc.vertices || h.kind == HIT_NONE) break;
            width += h.t * angle;
            Surface s = surface_at(h, o, d);
            if (s.material == NONE) break;
            m = get_material(s.material);
            sh = shading_at(s, m, d);
            if (!(max3(sh.albedo) > 0.0)) break;
            m.lobe_count = 0u;
            shade = true;
        } else {
            if (ray == RAY_NEXT) {
                next = h;
                o_next = o;
                d_next = d;
                sum_d = vec3(0.0);
                thr_d = vec3(1.0);
                vertex_d = 0u;
            }
            if (h.kind != HIT_NONE && vertex_d < RADIOSITY_BRUTE_MAX) {
                Surface s = surface_at(h, o, d);
                if (s.material != NONE) {
                    m = get_material(s.material);
                    sh = shading_at(s, m, d);
                    if (max3(sh.albedo) > 0.0) {
                        float w = h.t * frame.diffuse_spread;
                        vec3 b;
                        if (radiosity_cache_on() && h.t > radiosity_cell_size(radiosity_level(w)) && radiosity_lookup(sh, w, rng, b)) {
                            sum_d += thr_d * b;
                        } else {
                            m.lobe_count = 0u;
                            shade = true;
                            diffuse_over = false;
                        }
                    }
                }
            }
        }
        vec3 dl = shade ? direct_lighting(sh, m, rng) : vec3(0.0);
        if (ray == RAY_VERTEX) {
            // Vertex v: direct lighting, then one cosine-sampled bounce whose hit returns B.
            value = dl;
            sh_v = sh;
            width_v = width;
            next.kind = HIT_NONE;
            o = sh.origin;
            if (diffuse_direction(sh, rng, d)) {
                ray = RAY_NEXT;
                continue;
            }
        } else if (shade) {
            vec3 wi;
            diffuse_over = !diffuse_chain_next(sh, dl, sum_d, thr_d, vertex_d, rng, wi);
            if (!diffuse_over) {
                o = sh.origin;
                d = wi;
                ray = RAY_CHAIN;
                continue;
            }
        }
        // Vertex v is complete: its record; then the path goes on to the next vertex (hit already).
        if (next.kind != HIT_NONE) value += sh_v.albedo * sum_d;
        RadiosityRecord r;
        r.value = value;
        r.valid = non_finite(value) ? 0u : 1u;
        uint level = radiosity_level(width_v);
        for (uint k = 0u; k < RADIOSITY_RECORD_KEYS; ++k)
            r.keys[k] = radiosity_key(sh_v.p, sh_v.ng, radiosity_record_level(level, k));
        records.v[base + v] = r;
        v += 1u;
        o = o_next;
        d = d_next;
        h = next;
        trace = false;
        ray = RAY_VERTEX;
        angle = frame.diffuse_spread;
        width = 0.0;
    }
}
