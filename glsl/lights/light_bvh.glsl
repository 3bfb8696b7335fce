// The light BVH (src/gpu_scene/lights.rs): the finite lights whose bounds a ray crosses, which is
// how a BRDF sample finds the lights it may hit without testing every light; then the infinite
// lights (dome, sun), which every direction meets.
#ifndef ILLUM_LIGHT_BVH_GLSL
#define ILLUM_LIGHT_BVH_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "scene/scene.glsl"

// At most this many lights along one direction are counted.
#define DIRECT_MAX_CROSSED 16u
#define LIGHT_BVH_STACK 32u

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer LightNodeRef { GpuLightNode v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer LightRefRef { uint v[]; };

bool ray_box(vec3 o, vec3 inv_d, vec3 lo, vec3 hi) {
    vec3 t0 = (lo - o) * inv_d, t1 = (hi - o) * inv_d;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float leave = min(min(tf.x, tf.y), tf.z);
    return enter <= leave * 1.00001;
}

// The lights whose bounds the ray from p along w crosses (candidates for light_hit), then the
// infinite lights. Returns the count written to `ids`.
uint lights_along(vec3 p, vec3 w, out uint ids[DIRECT_MAX_CROSSED]) {
    uint n = 0u;
    LightRefRef refs = LightRefRef(frame.light_refs);
    if (frame.light_bvh_nodes > 0u) {
        LightNodeRef nodes = LightNodeRef(frame.light_nodes);
        vec3 inv_d = 1.0 / w;
        uint stack[LIGHT_BVH_STACK];
        uint sp = 0u;
        stack[sp++] = 0u;
        while (sp > 0u && n < DIRECT_MAX_CROSSED) {
            GpuLightNode node = nodes.v[stack[--sp]];
            if (!ray_box(p, inv_d, node.lo, node.hi)) continue;
            if (node.count == 0u) {
                if (sp + 2u <= LIGHT_BVH_STACK) {
                    stack[sp++] = node.index;
                    stack[sp++] = node.index + 1u;
                }
            } else {
                for (uint k = 0u; k < node.count && n < DIRECT_MAX_CROSSED; ++k) ids[n++] = refs.v[node.index + k];
            }
        }
    }
    for (uint k = 0u; k < frame.infinite_count && n < DIRECT_MAX_CROSSED; ++k) ids[n++] = refs.v[frame.infinite_first + k];
    return n;
}

// Infinite light k (k < frame.infinite_count).
uint infinite_light(uint k) { return LightRefRef(frame.light_refs).v[frame.infinite_first + k]; }

#endif
