// Test kernel of glsl/direct/mis.glsl (tests/sampling.rs): for each input (N_L, p_L, N_B, p_B),
// (mis_light_weight, mis_brdf_weight, mis_dbrdf_light_factor, mis_dbrdf_brdf_factor).
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "direct/mis.glsl"

layout(local_size_x = 64) in;
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { vec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    vec4 q = inputs[i];
    outputs[i] = vec4(mis_light_weight(q.x, q.y, q.z, q.w), mis_brdf_weight(q.x, q.y, q.z, q.w),
                      mis_dbrdf_light_factor(q.x, q.y, q.z, q.w), mis_dbrdf_brdf_factor(q.x, q.y, q.z, q.w));
}
