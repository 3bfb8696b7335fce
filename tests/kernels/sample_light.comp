// Test kernel of glsl/lights/light_sampling.glsl (tests/sampling.rs). Push constants: mode, count,
// seed. Mode 0: `count` samples of sample_light() at p with u = rng(seed, i), each as four vec4
// (wi, pdf), (x, light_pdf(wi)), (uv, dist, light_hit(wi).t), (n, delta); for a dome
// le in place of x (negative where the sampler did not read it). Mode 1: light_hit() of
// the directions in the input: (pdf, t, uv).
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "lights/light_sampling.glsl"

layout(local_size_x = 64) in;
struct LightTestParams {
    GpuDomeSampling dome;
    GpuLight light;
    vec4 p;
};
layout(scalar, binding = 0) readonly buffer ParamBlock { LightTestParams prm; };
layout(scalar, binding = 1) readonly buffer InputBlock { vec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    vec3 p = prm.p.xyz;
    if (pc.x == 0u) {
        Rng rng = rng_init(pc.z, 0x119b7u, i, 0u);
        vec2 u = rng_next2(rng);
        LightSample s = sample_light(prm.light, prm.dome, p, vec3(0.0), u);
        LightHit h = light_hit(prm.light, prm.dome, p, vec3(0.0), s.wi);
        outputs[4u * i] = vec4(s.wi, s.pdf);
        outputs[4u * i + 1u] = vec4(prm.light.kind == LIGHT_DOME ? s.le : s.x, h.pdf);
        outputs[4u * i + 2u] = vec4(s.uv, s.dist, h.t);
        outputs[4u * i + 3u] = vec4(s.n, float(s.delta));
    } else {
        LightHit h = light_hit(prm.light, prm.dome, p, vec3(0.0), inputs[i].xyz);
        outputs[i] = vec4(h.pdf, h.t, h.uv);
    }
}
