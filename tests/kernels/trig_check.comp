// Test kernel of the accurate inverse trigonometry of glsl/shared/common.glsl (tests/sampling.rs):
// for each input (y, x, c, t): (atan2_accurate(y, x), acos_accurate(c), atan2_accurate(t, 1),
// asin_accurate(c)).
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/common.glsl"
layout(local_size_x = 64) in;
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { vec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    vec4 q = inputs[i];
    outputs[i] = vec4(atan2_accurate(q.x, q.y), acos_accurate(q.z), atan2_accurate(q.w, 1.0), asin_accurate(q.z));
}
