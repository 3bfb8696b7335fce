// The film's beauty into the host's storage image (RenderSession::record_pass,
// src/render/session.rs): the mean of `spp` samples per pixel in RGB, alpha 1. The float32
// quotient is the one the host's resolve makes (there: the sum in float64 divided, rounded once
// to float32; here: correctly rounded float32 division), so both give the same bits.
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "shared/layout.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_FILM) readonly buffer FilmBlock { FilmPixel film[]; };
layout(binding = BINDING_IMAGE, rgba32f) writeonly uniform image2D target;
layout(push_constant) uniform Push { uvec4 size; };   // width, height, samples per pixel

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= size.x || p.y >= size.y) return;
    vec3 sum = film[p.y * size.x + p.x].beauty.rgb;
    imageStore(target, ivec2(p), vec4(sum / float(size.z), 1.0));
}
