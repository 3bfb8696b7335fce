// Test kernel of glsl/scene/microfacet.glsl (tests/brdf.rs, tests/sampling.rs). Push constants:
// mode, count, seed. Mode 0: `count` samples from brdf_sample() with u = rng(seed, i), each as three
// vec4 (wi, pdf), (weight, brdf_eval(wi).pdf), (brdf_eval(wi).f_cos, valid + 2 delta). Mode 1:
// brdf_eval() of the directions in the input: (f_cos, pdf). Mode 2: lobe_fresnel(input.x): (F, 0).
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "scene/microfacet.glsl"

layout(local_size_x = 64) in;
struct BrdfTestParams {
    GpuLobe lobe;
    vec4 n;
    vec4 t;
    vec4 b;
    vec4 v;
};
layout(scalar, binding = 0) readonly buffer ParamBlock { BrdfTestParams prm; };
layout(scalar, binding = 1) readonly buffer InputBlock { vec4 inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { vec4 outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint mode = pc.x;
    if (i >= pc.y) return;
    vec3 n = prm.n.xyz, t = prm.t.xyz, b = prm.b.xyz, v = prm.v.xyz;
    if (mode == 0u) {
        Rng rng = rng_init(pc.z, 0x5eedu, i, 0u);
        vec2 u = rng_next2(rng);
        BrdfSample s = brdf_sample(prm.lobe, n, t, b, v, u);
        BrdfEval e = brdf_eval(prm.lobe, n, t, b, v, s.wi);
        outputs[3u * i] = vec4(s.wi, s.pdf);
        outputs[3u * i + 1u] = vec4(s.weight, e.pdf);
        outputs[3u * i + 2u] = vec4(e.f_cos, float(s.valid) + 2.0 * float(s.delta));
    } else if (mode == 1u) {
        BrdfEval e = brdf_eval(prm.lobe, n, t, b, v, inputs[i].xyz);
        outputs[i] = vec4(e.f_cos, e.pdf);
    } else {
        outputs[i] = vec4(lobe_fresnel(prm.lobe, inputs[i].x), 0.0);
    }
}
