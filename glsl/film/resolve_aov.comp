// One AOV plane of the film into a host storage image (RenderSession::record_pass,
// src/render/session.rs): the plane's mean over `spp` samples per pixel in RGB, alpha 1, divided
// as glsl/film/resolve_image.comp divides the beauty (so it matches the host's resolve bit for bit).
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "shared/layout.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_AOVS) readonly buffer AovBlock { vec4 aovs[]; };
layout(binding = BINDING_IMAGE, rgba32f) writeonly uniform image2D target;
// size: width, height, samples per pixel; plane: its index, the film's plane count
layout(push_constant) uniform Push { uvec4 size; uvec4 plane; };

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= size.x || p.y >= size.y) return;
    vec3 sum = aovs[(p.y * size.x + p.x) * plane.y + plane.x].rgb;
    imageStore(target, ivec2(p), vec4(sum / float(size.z), 1.0));
}
