// Indirect lighting (docs/techniques.md, "Indirect lighting: the three integrators",
// "Lobe selection and ray cones", "The radiosity cache"): lobe sampling for path continuation, ray
// cones, the radiosity cache's lookups, and the outgoing diffuse radiance of a surface with or
// without the cache. Used by glsl/indirect/{path,full}.comp (src/integrators/indirect/).
//
// Conventions:
// * Emission is only ever added where a camera ray meets it: every other emitter contribution is
//   direct lighting (direct.glsl, light and BRDF samples by MIS) at the vertex before it, so a
//   continuation ray that reaches a light or the sky ends there and adds nothing.
// * A continuation picks one lobe (diffuse or one specular lobe) with probability proportional to
//   an estimate of its albedo and divides that lobe's sample weight by the probability: an unbiased
//   estimate of the sum of the lobes' integrals.
// * Ray cones (Akenine-Möller et al. 2019): a cone's width at a hit is the width at the previous
//   vertex plus the distance times the spread angle, which starts at one pixel's and grows by each
//   specular bounce's lobe spread. A diffuse bounce starts a new cone of frame.diffuse_spread
//   from its vertex: what its hit may blur is set by the angle the bounce integrates over, not by
//   the path before it. The radiosity cache picks its cell size from that width.
#ifndef ILLUM_INDIRECT_GLSL
#define ILLUM_INDIRECT_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/scene.glsl"
#include "scene/shading.glsl"
#include "scene/microfacet.glsl"

// Most diffuse bounces done in place (Russian roulette ends paths long before).
#define RADIOSITY_BRUTE_MAX 256u
// Safety cap on the vertices of one path (Russian roulette ends paths long before).
#define PATH_MAX_VERTICES 1024u

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

// A cosine-distributed direction about sh.n; false where it is not above both sh.n's and
// sh.ng's horizons (no bounce).
bool diffuse_direction(Shading sh, inout Rng rng, out vec3 wi) {
    vec3 c = cosine_hemisphere(rng_next2(rng));
    wi = c.x * sh.t + c.y * sh.b + c.z * sh.n;
    return c.z > 0.0 && dot(wi, sh.ng) > 0.0;
}

// Russian roulette on a path's throughput: goes on with probability min(max3(thr), 0.95), thr
// divided by it (unbiased); false where the path ends.
bool russian_roulette(inout vec3 thr, inout Rng rng) {
    float q = min(max3(thr), 0.95);
    bool go = rng_next(rng) < q;
    thr /= q;
    return go;
}

// A vertex of a diffuse chain (full's brute-force fallback, the cache's update paths): adds its
// direct light dl to sum with throughput thr, draws the next direction wi and starts its ray cone
// (width, angle); false when the chain ends there (below a horizon, or Russian roulette from the
// third vertex on).
bool diffuse_chain_next(Shading sh, vec3 dl, inout vec3 sum, inout vec3 thr, inout uint vertex,
                        inout Rng rng, out vec3 wi, out float width, out float angle) {
    sum += thr * dl;
    bool go = diffuse_direction(sh, rng, wi);
    if (go) {
        thr *= sh.albedo;
        if (vertex >= 2u) go = russian_roulette(thr, rng);
    }
    vertex += 1u;
    width = 0.0;
    angle = frame.diffuse_spread;
    return go;
}

// Spread angle of a camera ray's cone: one pixel's height.
float pixel_spread() { return 2.0 * length(frame.cam_up.xyz) / float(frame.height); }

// ---------------------------------------------------------------------------------------------
// Continuation

struct Bounce {
    vec3 wi;
    vec3 weight;     // f cos / (pdf P(lobe))
    float spread;    // the lobe's cone spread angle
    bool valid;
    bool diffuse;
};

// A specular lobe's share in lobe selection: its Fresnel reflectance toward the viewer.
float lobe_pick_weight(Shading sh, GpuLobe lobe) {
    return luminance(lobe_fresnel(lobe, max(dot(sh.n, sh.v), 1e-4)));
}

// Cone spread of a specular lobe (SHaRC's 2 sqrt(a^2 / (2 (1 - a^2))), a = alpha); 0 for a mirror.
float lobe_spread(GpuLobe lobe) {
    if (lobe_is_delta(lobe)) return 0.0;
    vec2 a2 = lobe_alpha(lobe);
    float a = min(sqrt(a2.x * a2.y), 0.99);
    return 2.0 * sqrt(0.5 * a * a / (1.0 - a * a));
}

// One direction from the diffuse lobe (if `diffuse`) and the specular lobes (if `specular`).
Bounce sample_bounce(Shading sh, GpuMaterial m, bool diffuse, bool specular, inout Rng rng) {
    Bounce b;
    b.wi = sh.n;
    b.weight = vec3(0.0);
    b.spread = 0.0;
    b.valid = false;
    b.diffuse = false;
    uint lobes = min(m.lobe_count, 2u);
    float wd = diffuse ? luminance(sh.albedo) : 0.0;
    float w0 = specular && lobes > 0u ? lobe_pick_weight(sh, m.lobes[0]) : 0.0;
    float w1 = specular && lobes > 1u ? lobe_pick_weight(sh, m.lobes[1]) : 0.0;
    float total = wd + w0 + w1;
    if (!(total > 0.0)) return b;
    float u = rng_next(rng) * total;
    vec2 u2 = rng_next2(rng);
    if (u < wd) {
        vec3 c = cosine_hemisphere(u2);
        b.wi = c.x * sh.t + c.y * sh.b + c.z * sh.n;
        b.weight = sh.albedo * (total / wd);
        b.spread = frame.diffuse_spread;
        b.diffuse = true;
        b.valid = c.z > 0.0;
    } else {
        uint k = u < wd + w0 ? 0u : 1u;
        float p = (k == 0u ? w0 : w1) / total;
        BrdfSample bs = brdf_sample(m.lobes[k], sh.n, sh.t, sh.b, sh.v, u2);
        b.wi = bs.wi;
        b.weight = bs.weight / p;
        b.spread = lobe_spread(m.lobes[k]);
        b.valid = bs.valid;
    }
    // No light leaks through the geometric surface (as for direct lighting's samples).
    b.valid = b.valid && dot(b.wi, sh.ng) > 0.0;
    return b;
}

// A vertex of the diffuse chain whose material has specular lobes (full.comp, with
// INTEGRATOR_CAUSTICS), once its direct light is added and bounce b drawn from its lobes
// (sample_bounce with sh.albedo zero where the cache gave the diffuse lobe's light: from the
// specular lobes only): the throughput and the ray cone (width, angle) follow b, widening as a
// specular bounce does or starting anew at a diffuse bounce; false when the chain ends there (as
// diffuse_chain_next). The caller draws b: full.comp holds one sample_bounce for both its bounces.
bool lobe_chain_next(Bounce b, inout vec3 thr, inout uint vertex, inout Rng rng, inout float width,
                     inout float angle) {
    bool go = b.valid;
    if (go) {
        thr *= b.weight;
        if (vertex >= 2u) go = russian_roulette(thr, rng);
        if (b.diffuse) {
            width = 0.0;
            angle = b.spread;
        } else {
            angle += b.spread;
        }
    }
    vertex += 1u;
    return go;
}

// ---------------------------------------------------------------------------------------------
// The radiosity cache: a hashed grid of cells at power-of-two sizes, keyed by cell coordinates,
// level and the normal's dominant signed axis (both sides of a thin wall, and two walls meeting
// at an edge, stay apart).

layout(buffer_reference, scalar, buffer_reference_align = 8) readonly buffer RadiosityTableRef { RadiosityEntry v[]; };

bool radiosity_cache_on() { return frame.radiosity_table != uint64_t(0); }

// The level whose cells are at most `width` across (and more than half of it).
uint radiosity_level(float width) {
    float r = width / frame.radiosity_cell;
    int l = r <= 1.0 ? 0 : int(floor(log2(r)));
    return uint(clamp(l, 0, int(frame.radiosity_levels) - 1));
}

float radiosity_cell_size(uint level) { return frame.radiosity_cell * exp2(float(level)); }

uvec2 radiosity_key(vec3 p, vec3 n, uint level) {
    ivec3 c = ivec3(clamp(floor(p / radiosity_cell_size(level)), vec3(-2e9), vec3(2e9)));
    uvec3 u = uvec3(c);
    // The normal's dominant axis and its sign: walls that meet at an edge stay apart.
    vec3 a = abs(n);
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
    uint tag = level * 6u + 2u * axis + (n[axis] >= 0.0 ? 1u : 0u);
    uint h1 = hash_u32(u.x ^ hash_u32(u.y ^ hash_u32(u.z ^ hash_u32(tag))));
    uint h2 = hash_u32((u.x * 0x9e3779b1u) ^ hash_u32((u.y * 0x85ebca6bu) ^ hash_u32((u.z * 0xc2b2ae35u) ^ (tag + 0x27d4eb2fu))));
    return uvec2(h1, h2 | 1u);
}

// Level of the r-th key of a record: the footprint's level, then the next coarser one (so that a
// lookup whose footprint is a level off still finds it).
uint radiosity_record_level(uint level, uint r) { return min(level + r, frame.radiosity_levels - 1u); }

bool radiosity_find(uvec2 key, out vec3 value) {
    RadiosityTableRef table = RadiosityTableRef(frame.radiosity_table);
    uint mask = frame.radiosity_mask;
    value = vec3(0.0);
    for (uint i = 0u; i < RADIOSITY_PROBES; ++i) {
        RadiosityEntry e = table.v[(key.x + i) & mask];
        if (e.key.y == 0u) return false;
        if (e.key == key) {
            value = e.value;
            return true;
        }
    }
    return false;
}

// The cached B near sh.p for a cone of `width`: the lookup point is jittered within the tangent
// plane by up to half a cell each way (Binder et al. 2019: noise instead of the grid's seams);
// an empty cell falls back to the coarser levels the records also fill.
bool radiosity_lookup(Shading sh, float width, inout Rng rng, out vec3 value) {
    uint level = radiosity_level(width);
    vec2 j = rng_next2(rng) - 0.5;
    value = vec3(0.0);
    for (uint r = 0u; r < RADIOSITY_RECORD_KEYS; ++r) {
        uint l = radiosity_record_level(level, r);
        vec3 p = sh.p + radiosity_cell_size(l) * (j.x * sh.t + j.y * sh.b);
        if (radiosity_find(radiosity_key(p, sh.ng, l), value)) return true;
    }
    return false;
}

// The diffuse chain: outgoing diffuse radiance B = rho/pi E (emission excluded) at the surface a
// ray hit, for a cone of width h.t * frame.diffuse_spread there. With the cache: the cached value
// where the segment is longer than the cell (SHaRC's rule) and the cell has one; otherwise direct
// lighting of the diffuse lobe plus one more cosine-sampled bounce in place. Without the cache:
// brute force, a diffuse-only path with next-event estimation at every vertex. Either way Russian
// roulette ends paths after three bounces in place (at most RADIOSITY_BRUTE_MAX), so a miss costs
// time, never bias. Indirect diffuse at a vertex: albedo times B along one cosine-sampled ray.
// full.comp walks it inside its one loop of rays, in both of its passes.

#endif
