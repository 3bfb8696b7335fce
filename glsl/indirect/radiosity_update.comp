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
    Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
    g_rays += 1u;
    if (h.kind == HIT_NONE) return;
    Surface s = surface_at(h, o, d);
    if (s.material == NONE) return;
    GpuMaterial m = get_material(s.material);
    Shading sh = shading_at(s, m, d);
    float angle = pixel_spread();
    float width = h.t * angle;
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
    h = trace_closest(o, d, 0.0, INF, MASK_OCCLUDERS);
    g_rays += 1u;
    for (uint v = 0u; v < pc.vertices; ++v) {
        if (h.kind == HIT_NONE) break;
        width += h.t * angle;
        s = surface_at(h, o, d);
        if (s.material == NONE) break;
        m = get_material(s.material);
        sh = shading_at(s, m, d);
        if (!(max3(sh.albedo) > 0.0)) break;
        m.lobe_count = 0u;
        vec3 value = direct_lighting(sh, m, rng);
        vec3 c = cosine_hemisphere(rng_next2(rng));
        vec3 wi = c.x * sh.t + c.y * sh.b + c.z * sh.n;
        Hit next;
        next.kind = HIT_NONE;
        float next_angle = frame.diffuse_spread;
        if (c.z > 0.0 && dot(wi, sh.ng) > 0.0) {
            next = trace_closest(sh.origin, wi, 0.0, INF, MASK_OCCLUDERS);
            g_rays += 1u;
            if (next.kind != HIT_NONE)
                value += sh.albedo * radiosity_along(next, sh.origin, wi, next.t * next_angle, next_angle, rng);
        }
        RadiosityRecord r;
        r.value = value;
        r.valid = non_finite(value) ? 0u : 1u;
        uint level = radiosity_level(width);
        for (uint k = 0u; k < RADIOSITY_RECORD_KEYS; ++k)
            r.keys[k] = radiosity_key(sh.p, sh.ng, radiosity_record_level(level, k));
        records.v[base + v] = r;
        o = sh.origin;
        d = wi;
        h = next;
        angle = next_angle;
        width = 0.0;
    }
}
