// Scene data reached through buffer device addresses held in the Frame uniform buffer. Scenes
// without a feature leave its address 0 and the FEATURES specialization constant folds its code away.
#ifndef ILLUM_SCENE_GLSL
#define ILLUM_SCENE_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "layout.glsl"
#include "common.glsl"

layout(constant_id = SPEC_FEATURES) const uint FEATURES = 0xffffffffu;
bool has_feature(uint f) { return (FEATURES & f) != 0u; }

layout(scalar, binding = BINDING_FRAME) uniform FrameBlock { Frame frame; };

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer InstanceRef { GpuInstance v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer VertexRef { GpuVertex v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer IndexRef { uint v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer MaterialRef { GpuMaterial v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer ShapeRef { GpuShape v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer LightRef { GpuLight v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer TextureRef { GpuTexture v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer TexelRef { vec4 v[]; };

GpuInstance get_instance(uint i) { return InstanceRef(frame.instances).v[i]; }
GpuMaterial get_material(uint i) { return MaterialRef(frame.materials).v[i]; }
GpuShape get_shape(uint i) { return ShapeRef(frame.shapes).v[i]; }
GpuLight get_light(uint i) { return LightRef(frame.lights).v[i]; }

// Bilinear lookup with wrapping; uv (0,0) is the top-left corner of the image.
vec4 texture_lookup(uint tex, vec2 uv) {
    if (!has_feature(FEATURE_TEXTURES) || tex == NONE) return vec4(1.0);
    GpuTexture t = TextureRef(frame.textures).v[tex];
    vec2 st = uv * vec2(t.width, t.height) - 0.5;
    vec2 f = st - floor(st);
    ivec2 i0 = ivec2(floor(st));
    ivec2 size = ivec2(t.width, t.height);
    TexelRef texels = TexelRef(frame.texels);
    vec4 acc = vec4(0.0);
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 p = (i0 + o) % size;
        p += ivec2(p.x < 0 ? size.x : 0, p.y < 0 ? size.y : 0);
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        acc += w * texels.v[t.offset + uint(p.y) * t.width + uint(p.x)];
    }
    return acc;
}

vec3 dome_radiance(vec3 dir) {
    if (!has_feature(FEATURE_DOME) || frame.counts.w == NONE) return vec3(0.0);
    GpuLight l = get_light(frame.counts.w);
    vec3 L = l.radiance;
    if (l.texture != NONE) L *= texture_lookup(l.texture, direction_to_latlong(dir, l.p0.xy)).rgb;
    return L;
}

#endif
