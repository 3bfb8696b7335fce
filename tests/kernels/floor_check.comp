// Test kernel of the float-to-int helpers of glsl/shared/common.glsl (tests/sampling_irradiance.rs):
// for each input x: (floor_int(x), floor_uint(x), ceil_uint(x)) as bits, and 0.
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/common.glsl"
layout(local_size_x = 64) in;
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { float inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { uvec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    float x = inputs[i];
    outputs[i] = uvec4(uint(floor_int(x)), floor_uint(x), ceil_uint(x), 0u);
}
