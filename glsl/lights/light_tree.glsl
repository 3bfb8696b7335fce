// The light tree's importance and descent (docs/techniques.md, "The light tree"; built by
// src/gpu_scene/light_tree.rs, which also holds the float64 twin that the tests compare with). One
// function serves the sampler and the PMF of a given light, so that the MIS weight of a BRDF sample
// uses exactly the probability the sampler had. Only buffer addresses come in: test kernels call it
// too.
#ifndef ILLUM_LIGHT_TREE_GLSL
#define ILLUM_LIGHT_TREE_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer LightTreeRef { GpuLightTreeNode v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer LightTrailRef { uint v[]; };

// cos and sin of max(0, a - b) from the angles' cosines and sines (no trig calls).
float cos_sub_clamped(float sa, float ca, float sb, float cb) { return ca > cb ? 1.0 : ca * cb + sa * sb; }
float sin_sub_clamped(float sa, float ca, float sb, float cb) { return ca > cb ? 0.0 : sa * cb - ca * sb; }

// Importance of a node seen from p with normal n (CK18; pbrt-v4 LightBounds::Importance): zero only
// where provably nothing is emitted toward p (the orientation cone) or everything lies below p's
// horizon (the integrand's cosine, which eval_lobes makes zero there). The bounding sphere's
// sin(theta_u) is r/d, exact for tiny nodes; inside it nothing bounds the directions.
float light_tree_importance(GpuLightTreeNode nd, vec3 p, vec3 n) {
    vec3 c = 0.5 * (nd.lo + nd.hi);
    vec3 h = 0.5 * (nd.hi - nd.lo);
    float r2 = dot(h, h);
    vec3 pc = p - c;
    float d2 = dot(pc, pc);
    if (d2 <= r2) return nd.power / max(r2, 1e-30);
    float d = sqrt(d2);
    vec3 wi = pc / d;
    float sin_u = sqrt(r2 / d2);
    float cos_u = sqrt(max(0.0, 1.0 - sin_u * sin_u));
    float cos_w = dot(nd.axis, wi);
    if ((nd.flags & LIGHT_TREE_TWO_SIDED) != 0u) cos_w = abs(cos_w);
    float sin_w = sqrt(max(0.0, 1.0 - cos_w * cos_w));
    float sin_o = sqrt(max(0.0, 1.0 - nd.cos_o * nd.cos_o));
    float cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, nd.cos_o);
    float sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, nd.cos_o);
    float cos_p = cos_sub_clamped(sin_x, cos_x, sin_u, cos_u);
    if (cos_p <= nd.cos_e) return 0.0;
    float cos_i = -dot(n, wi);
    float sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
    float cos_ip = cos_sub_clamped(sin_i, cos_i, sin_u, cos_u);
    if (cos_ip <= 0.0) return 0.0;
    return nd.power * cos_p * cos_ip / d2;
}

// One descent from the root at (p, n): with `draw`, children are drawn by importance; without,
// the descent follows `trail` (bit k: second child at depth k). Drawing, u in [0, 1) decides the
// first levels, rescaled to [0, 1) within the child taken (pbrt-v4's LightSampler does this at
// every level), while the path's probability is at least 2^-8, so that u keeps 16 of its 24 bits;
// then a fresh uniform per level, so that no PMF is out of reach after many levels. A u
// stratified over a shading point's picks (direct.glsl, DirectPlan.pick_dim) stratifies them over
// the tree's top levels. u < 0: fresh uniforms from the first level. Returns the probability of
// the path, 0 where both children of a node have importance 0 (no light; `light` = NONE).
float light_tree_walk(uint64_t tree, vec3 p, vec3 n, bool draw, uint trail, float u, inout Rng rng, out uint light) {
    LightTreeRef nodes = LightTreeRef(tree);
    GpuLightTreeNode nd = nodes.v[0];
    uint i = 0u;
    float pmf = 1.0;
    light = NONE;
    for (uint depth = 0u; depth <= LIGHT_TREE_MAX_DEPTH; ++depth) {
        if ((nd.link & LIGHT_TREE_LEAF) != 0u) {
            light = nd.link & ~LIGHT_TREE_LEAF;
            return pmf;
        }
        GpuLightTreeNode n0 = nodes.v[i + 1u], n1 = nodes.v[nd.link];
        float c0 = light_tree_importance(n0, p, n);
        float c1 = light_tree_importance(n1, p, n);
        float sum = c0 + c1;
        if (!(sum > 0.0)) return 0.0;
        float p0 = c0 / sum;
        bool right;
        if (!draw) {
            right = (trail & 1u) != 0u;
        } else if (u >= 0.0 && pmf >= 1.0 / 256.0) {
            right = u >= p0;
            u = min(right ? (u - p0) / (1.0 - p0) : u / p0, 0.99999994);
        } else {
            right = rng_next(rng) >= p0;
        }
        trail >>= 1u;
        pmf *= right ? c1 / sum : p0;
        i = right ? nd.link : i + 1u;
        nd = right ? n1 : n0;
    }
    return 0.0;
}

// The probability that light_tree_walk's sampler picks `light` at (p, n).
float light_tree_pmf(uint64_t tree, uint64_t trails, vec3 p, vec3 n, uint light) {
    Rng unused = Rng(0u, 0u, RNG_PCG);
    uint found;
    float pmf = light_tree_walk(tree, p, n, false, LightTrailRef(trails).v[light], -1.0, unused, found);
    return found == light ? pmf : 0.0;
}

#endif
