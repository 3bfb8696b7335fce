// Test kernel of the camera-sample streams of glsl/shared/common.glsl (tests/sampling/
// camera_streams.rs): for each input (seed, pixel, sample index, k), draw pair k of the stream
// rng_init_camera(seed, 0, pixel, sample index) (pairs 0..k-1 drawn and dropped first):
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
    Rng r = rng_init_camera(q.x, 0u, q.y, q.z);
    for (uint k = 0u; k < q.w; ++k) rng_next2(r);
    vec2 a = rng_next2(r);
    outputs[i] = vec4(a, 0.0, 0.0);
}
