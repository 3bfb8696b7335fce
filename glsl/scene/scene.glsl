// Scene data reached through buffer device addresses held in the Frame uniform buffer. Scenes
// without a feature leave its address 0 and the FEATURES specialization constant folds its code away.
#ifndef ILLUM_SCENE_GLSL
#define ILLUM_SCENE_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"

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
// All zero: what get_material() fills in, and path.comp's per-iteration material before a hit
// sets it.
GpuMaterial no_material() {
    GpuLobe z = GpuLobe(vec4(0.0), vec4(0.0), vec2(0.0), 0u, 0u);
    return GpuMaterial(vec3(0.0), 0u, vec3(0.0), 0u, vec3(0.0), 0u, 0u, 0u, 0.0, 0.0, vec4(0.0), GpuLobe[2](z, z));
}
// Material i. The lobes a material does not have are not read (zero): each word read is a gather
// of every lane on lavapipe, and the lobes are 24 of a material's 44 words.
GpuMaterial get_material(uint i) {
    MaterialRef r = MaterialRef(frame.materials);
    GpuMaterial m = no_material();
    m.diffuse = r.v[i].diffuse;
    m.diffuse_texture = r.v[i].diffuse_texture;
    m.emission = r.v[i].emission;
    m.emission_texture = r.v[i].emission_texture;
    m.tangent_dir = r.v[i].tangent_dir;
    m.flags = r.v[i].flags;
    m.lobe_count = r.v[i].lobe_count;
    m.metallic_roughness_texture = r.v[i].metallic_roughness_texture;
    m.roughness = r.v[i].roughness;
    m.dielectric_f0 = r.v[i].dielectric_f0;
    m.base_metallic = r.v[i].base_metallic;
    if (m.lobe_count > 0u) m.lobes[0] = r.v[i].lobes[0];
    if (m.lobe_count > 1u) m.lobes[1] = r.v[i].lobes[1];
    return m;
}
GpuShape get_shape(uint i) { return ShapeRef(frame.shapes).v[i]; }
GpuLight get_light(uint i) { return LightRef(frame.lights).v[i]; }

GpuTexture get_texture(uint i) { return TextureRef(frame.textures).v[i]; }

// Texel index i along an axis of n texels, wrapped by mode (TEXTURE_WRAP_*; Mitsuba 3's
// semantics: mirror repeats the edge texel).
int wrap_texel(int i, int n, uint mode) {
    if (mode == TEXTURE_WRAP_CLAMP) return clamp(i, 0, n - 1);
    int m = mode == TEXTURE_WRAP_MIRROR ? 2 * n : n;
    // i mod m by a float quotient (CPU drivers have no vector integer division), corrected to be
    // exact: the quotient is off by at most one for the indices textures have (|i| < 2^22).
    int p = i - m * floor_int(float(i) / float(m));
    if (p < 0) p += m;
    if (p >= m) p -= m;
    return p < n ? p : m - 1 - p;
}

// Texel p of t, wrapped per axis.
vec4 texel_at(GpuTexture t, ivec2 p, uvec2 wrap) {
    int x = wrap_texel(p.x, int(t.width), wrap.x);
    int y = wrap_texel(p.y, int(t.height), wrap.y);
    return TexelRef(frame.texels).v[t.offset + uint(y) * t.width + uint(x)];
}

// The texture at texel coordinates st (texel (i, j) covers [i, i + 1) x [j, j + 1), its centre at
// (i + 1/2, j + 1/2)): the texel containing st, or the bilinear blend of the four nearest centres.
vec4 texture_at(GpuTexture t, vec2 st, bool nearest, uvec2 wrap) {
    if (nearest) return texel_at(t, floor_int(st), wrap);
    vec2 c = st - 0.5;
    vec2 f = c - floor(c);
    ivec2 i0 = floor_int(c);
    // Each row and column wrapped once (not once per texel).
    int x0 = wrap_texel(i0.x, int(t.width), wrap.x), x1 = wrap_texel(i0.x + 1, int(t.width), wrap.x);
    uint r0 = t.offset + uint(wrap_texel(i0.y, int(t.height), wrap.y)) * t.width;
    uint r1 = t.offset + uint(wrap_texel(i0.y + 1, int(t.height), wrap.y)) * t.width;
    TexelRef texels = TexelRef(frame.texels);
    return mix(mix(texels.v[r0 + uint(x0)], texels.v[r0 + uint(x1)], f.x),
               mix(texels.v[r1 + uint(x0)], texels.v[r1 + uint(x1)], f.x), f.y);
}

// Brings a coordinate into a range its wrap mode maps the same way, so that the integer texel
// index stays small: [0, 1) for repeat, [0, 2) for mirror, [-1, 2] for clamp.
float reduce_coordinate(float x, uint mode) {
    if (mode == TEXTURE_WRAP_REPEAT) return x - floor(x);
    if (mode == TEXTURE_WRAP_MIRROR) return x - 2.0 * floor(0.5 * x);
    return clamp(x, -1.0, 2.0);
}

// Lookup with the texture's own filter and wrap modes; uv (0,0) is the top-left corner of the
// image. NONE (or a scene without textures) reads 1.
vec4 texture_lookup(uint tex, vec2 uv) {
    if (!has_feature(FEATURE_TEXTURES) || tex == NONE) return vec4(1.0);
    GpuTexture t = get_texture(tex);
    uvec2 wrap = uvec2(t.flags >> TEXTURE_WRAP_SHIFT_U, t.flags >> TEXTURE_WRAP_SHIFT_V) & 3u;
    vec2 r = vec2(reduce_coordinate(uv.x, wrap.x), reduce_coordinate(uv.y, wrap.y));
    return texture_at(t, r * vec2(t.width, t.height), (t.flags & TEXTURE_FLAG_NEAREST) != 0u, wrap);
}

#endif
