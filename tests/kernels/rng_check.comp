// Test kernel of the camera-sample streams of glsl/shared/common.glsl (tests/sampling_sequences.rs):
// for each input (seed, pixel, sample index, w), with w = k | j << 8 | s << 24 | one << 31, draw
// pair k of the stream rng_init_camera(seed, 0, pixel, sample index, split = !one) (pairs 0..k-1 drawn and dropped
// first) as point j of a group of 2^s samples (rng_sobol2_group; j = s = 0: rng_next2's draw):
// (pair.x, pair.y, 0, 0).
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/common.glsl"

layout(local_size_x = 64) in;
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { uvec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    uvec4 q = inputs[i];
    Rng r = rng_init_camera(q.x, 0u, q.y, q.z, (q.w >> 31) == 0u);
    uint pair = q.w & 0xffu, j = (q.w >> 8) & 0xffffu, s = (q.w >> 24) & 0x7fu;
    for (uint k = 0u; k < pair; ++k) rng_next2(r);
    vec2 a = rng_sobol2_group(r, r.dim, j, 1u << s);
    outputs[i] = vec4(a, 0.0, 0.0);
}
