// Test kernel of glsl/lights/light_tree.glsl (tests/light_tree.rs). Push constants: mode, count,
// seed. Mode 0: item i draws a light at its own point (inputs 2i: p, 2i + 1: n) and writes
// (light, sampled pmf, the pmf replayed from that light's trail, 0) as uints (floats as bits).
// Mode 1: `count` draws at the point of inputs 0 and 1, each writing (light, pmf bits, 0, 0);
// mode 2 the same with a first uniform for the top levels (light_tree_walk's u).
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "lights/light_tree.glsl"

layout(local_size_x = 64) in;
struct TreeTestParams {
    uint64_t tree;
    uint64_t trails;
};
layout(scalar, binding = 0) readonly buffer ParamBlock { TreeTestParams prm; };
layout(scalar, binding = 1) readonly buffer InputBlock { vec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { uvec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    uint k = pc.x == 0u ? i : 0u;
    float u = -1.0;
    vec3 p = inputs[2u * k].xyz, n = inputs[2u * k + 1u].xyz;
    Rng rng = rng_init(pc.z, 0x7ee5u, i, 0u);
    uint light;
    if (pc.x == 2u) u = rng_next(rng);
    float pmf = light_tree_walk(prm.tree, p, n, true, 0u, u, rng, light);
    float replay = light == NONE ? 0.0 : light_tree_pmf(prm.tree, prm.trails, p, n, light);
    outputs[i] = uvec4(light, floatBitsToUint(pmf), floatBitsToUint(replay), 0u);
}
