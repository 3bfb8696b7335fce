// Test kernel of glsl/lights/irradiance.glsl (tests/sampling.rs): light_irradiance() for each
// (light, p, n) of the input.
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "lights/irradiance.glsl"

layout(local_size_x = 64) in;
struct IrradianceCase {
    GpuLight light;
    vec4 p;
    vec4 n;
};
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { IrradianceCase cases[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    IrradianceCase c = cases[i];
    outputs[i] = vec4(light_irradiance(c.light, c.p.xyz, c.n.xyz), 0.0, 0.0, 0.0);
}
