// Which lights light samples take at a shading point (Frame.light_select), as pbrt-v4's
// LightSampler: with LIGHT_SELECT_LOOP (the host's choice up to DIRECT_LOOP_LIGHTS lights, unless
// the allocation pilot measured the tree cheaper; always without a tree) every light is looped
// over, each with its own sample count; otherwise the infinite lights are still looped over and
// each of the other samples picks one light, from the light tree (light_tree.glsl; docs/
// techniques.md, "The light tree") or by the former linear scan of a CDF over every light, infinite
// ones included, kept for comparison. select_light() makes a pick and light_pmf() gives the
// probability of one, so that a BRDF sample's MIS weight uses exactly the sampler's.
#ifndef ILLUM_LIGHT_SELECT_GLSL
#define ILLUM_LIGHT_SELECT_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "lights/lights.glsl"
#include "lights/light_bvh.glsl"
#include "lights/light_tree.glsl"

// Selection weight of a light at p (the scan): luminance x share, with a floor on the cosine
// factor so that every light that may contribute keeps a positive probability.
float light_importance(GpuLight l, vec3 p, vec3 n) {
    float lum = luminance(l.radiance);
    if (l.kind == LIGHT_DOME || l.kind == LIGHT_SUN) return lum * (l.kind == LIGHT_SUN ? 1.0 : 2.0 * PI);
    vec3 c = l.kind == LIGHT_TRIANGLE ? l.p0.xyz + (l.p1.xyz + l.p2.xyz) / 3.0 : l.p0.xyz;
    vec3 d = c - p;
    float len = length(d);
    float cosc = len > 0.0 ? dot(n, d / len) : 1.0;
    return lum * light_share(l, p) * (0.1 + max(cosc, 0.0)) + 1e-20;
}

// The selection at one shading point (p, n).
struct LightSelection {
    uint mode;                // LIGHT_SELECT_*; LOOP when the scene has few lights
    float total_importance;   // the scan's: the sum of every light's importance at p
};

LightSelection light_selection(vec3 p, vec3 n) {
    uint nlights = frame.light_count;
    LightSelection s;
    s.mode = has_feature(FEATURE_MANY_LIGHTS) ? frame.light_select : LIGHT_SELECT_LOOP;
    s.total_importance = 0.0;
    if (s.mode != LIGHT_SELECT_LOOP && s.mode != LIGHT_SELECT_TREE) {
        for (uint i = 0u; i < nlights; ++i) s.total_importance += light_importance(get_light(i), p, n);
    }
    return s;
}

// Whether light samples pick lights at all (else every light is looped over).
bool lights_picked(LightSelection s) { return s.mode != LIGHT_SELECT_LOOP; }

// The lights looped over before any pick, and the k-th of them: every light, the infinite ones
// with the tree, none with the scan.
uint looped_lights(LightSelection s) {
    return !lights_picked(s) ? frame.light_count : s.mode == LIGHT_SELECT_TREE ? frame.infinite_count : 0u;
}
uint looped_light(LightSelection s, uint k) { return s.mode == LIGHT_SELECT_TREE ? infinite_light(k) : k; }

// Whether light l is reached by picks (else it is looped over).
bool light_picked(LightSelection s, GpuLight l) {
    bool infinite = l.kind == LIGHT_DOME || l.kind == LIGHT_SUN;
    return lights_picked(s) && !(s.mode == LIGHT_SELECT_TREE && infinite);
}

// One pick at (p, n), as pbrt-v4's LightSampler::Sample, by uniform u in [0, 1) (u < 0: drawn
// from rng): false when there is no light to pick (the tree's importance is 0 everywhere below a
// node), else `light` and `picks` x its probability in `expected`: the light's expected count
// among `picks` picks (1: the PMF itself), multiplied in the order direct lighting always did, so
// that its MIS weights keep their bits.
bool select_light(LightSelection s, vec3 p, vec3 n, float picks, float u, inout Rng rng, out uint light,
                  out float expected) {
    if (s.mode == LIGHT_SELECT_TREE) {
        float pmf = light_tree_walk(frame.light_tree, p, n, true, 0u, u, rng, light);
        expected = picks * pmf;
        return pmf > 0.0;
    }
    // Inverse CDF over the lights.
    uint nlights = frame.light_count;
    u = (u >= 0.0 ? u : rng_next(rng)) * s.total_importance;
    float acc = 0.0;
    light = nlights - 1u;
    for (uint i = 0u; i < nlights; ++i) {
        acc += light_importance(get_light(i), p, n);
        if (u < acc) { light = i; break; }
    }
    expected = picks * light_importance(get_light(light), p, n) / s.total_importance;
    return true;
}

// `picks` x the probability that select_light() picks light i (l = its GpuLight) at (p, n), as
// pbrt-v4's LightSampler::PMF; for a light that light_picked().
float light_pmf(LightSelection s, vec3 p, vec3 n, float picks, uint i, GpuLight l) {
    if (s.mode == LIGHT_SELECT_TREE) return picks * light_tree_pmf(frame.light_tree, frame.light_trails, p, n, i);
    return picks * light_importance(l, p, n) / s.total_importance;
}

#endif
