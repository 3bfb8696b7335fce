// What direct lighting asks of a light besides its sampler (light_sampling.glsl): its radiance
// toward the shading point (textures included, the dome's through its map convention), its share
// of the hemisphere, and the dome's sampling tables as the sampler takes them.
#ifndef ILLUM_LIGHTS_GLSL
#define ILLUM_LIGHTS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "scene/surface.glsl"
#include "lights/dome_map.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeSamplingRef { GpuDomeSampling v; };

// Share of a textured dome's samples drawn uniformly over the sphere under control variates
// (light_sampling.glsl: its SH9 control needs a pdf > 0 everywhere; docs/control-variates.md).
const float DOME_CV_DEFENSIVE = 0.1;

GpuDomeSampling dome_sampling() {
    GpuDomeSampling d;
    d.marginal = 0ul; d.conditional = 0ul; d.width = 0u; d.height = 0u; d.integral = 0.0; d.defensive = 0.0;
    for (int k = 0; k < 9; ++k) d.sh[k] = vec4(0.0);
    if (has_feature(FEATURE_DOME) && frame.dome_sampling != 0ul) {
        d = DomeSamplingRef(frame.dome_sampling).v;
        if (has_feature(FEATURE_CONTROL_VARIATES)) d.defensive = DOME_CV_DEFENSIVE;
    }
    return d;
}

// A dome's map at map coordinates uv, looked up as its convention does (glsl/lights/dome_map.glsl).
vec4 dome_texture(GpuLight l, vec2 uv) {
    if (!has_feature(FEATURE_TEXTURES) || l.texture == NONE) return vec4(1.0);
    if (dome_is_pbrt(l)) {
        GpuTexture t = get_texture(l.texture);
        uvec2 clamped = uvec2(TEXTURE_WRAP_CLAMP);
        return texture_at(t, clamp(uv, 0.0, 1.0) * vec2(t.width, t.height), true, clamped);
    }
    if (dome_is_mitsuba(l)) {
        // Column centres at (i + 1/2) / W, rows at j / (H - 1): st.y - 1/2 = v (H - 1).
        GpuTexture t = get_texture(l.texture);
        vec2 st = vec2(uv.x * float(t.width), clamp(uv.y, 0.0, 1.0) * float(t.height - 1u) + 0.5);
        return texture_at(t, st, false, uvec2(TEXTURE_WRAP_REPEAT, TEXTURE_WRAP_CLAMP));
    }
    return texture_lookup(l.texture, uv);
}

// What a ray that leaves the scene along dir sees of the dome.
vec3 dome_radiance(vec3 dir) {
    if (!has_feature(FEATURE_DOME) || frame.dome_light == NONE) return vec3(0.0);
    GpuLight l = get_light(frame.dome_light);
    return l.radiance * dome_texture(l, dome_uv(l, dir)).rgb;
}

// Texture coordinates of a point of a triangle light, from its barycentrics (b1, b2) and the
// mesh's vertex uvs, as surface_at interpolates them for camera rays (so that an emissive mesh
// looks the same seen directly and as a light).
vec2 triangle_light_texcoord(GpuLight l, vec2 bc) {
    if (!has_feature(FEATURE_MESHES)) return vec2(0.0);
    GpuInstance inst = get_instance(l.shape);
    if ((inst.flags & INSTANCE_FLAG_UVS) == 0u) return vec2(0.0);
    GpuVertex v0, v1, v2;
    instance_triangle(inst, l.triangle, v0, v1, v2);
    return (1.0 - bc.x - bc.y) * vec2(v0.u, v0.v) + bc.x * vec2(v1.u, v1.v) + bc.y * vec2(v2.u, v2.v);
}

// Emitted radiance of light l toward the shading point, at light-surface coordinates uv.
vec3 light_radiance(GpuLight l, vec2 uv, bool delta) {
    if (l.kind == LIGHT_SUN) {
        // The sun's E_perp spread over its cone: L = E / (pi sin^2 theta_s); a delta sun gives E.
        if (delta) return l.radiance;
        float om = l.p1.x;
        return l.radiance / (PI * om * (2.0 - om));
    }
    if (l.kind == LIGHT_DOME) return l.radiance * dome_texture(l, uv).rgb;
    if (l.kind == LIGHT_TRIANGLE) {
        if (l.texture == NONE) return l.radiance;
        uv = triangle_light_texcoord(l, uv);
    }
    return l.radiance * texture_lookup(l.texture, uv).rgb;
}

// Share of the hemisphere's solid angle a light covers from p (an estimate for sample counts and
// light selection: any positive function is unbiased).
float light_share(GpuLight l, vec3 p) {
    if (l.kind == LIGHT_DOME) return 1.0;
    if (l.kind == LIGHT_SUN) return max(l.p1.x, 1e-6);
    if (l.kind == LIGHT_SPHERE) {
        vec3 d = l.p0.xyz - p;
        float d2 = dot(d, d), r2 = l.p0.w * l.p0.w;
        if (d2 <= r2) return 1.0;
        float s2 = r2 / d2;
        return s2 / (1.0 + sqrt(max(0.0, 1.0 - s2)));   // 1 - cos(theta_max), stable
    }
    vec3 c = l.kind == LIGHT_TRIANGLE ? l.p0.xyz + (l.p1.xyz + l.p2.xyz) / 3.0 : l.p0.xyz;
    vec3 d = c - p;
    float d2 = max(dot(d, d), 1e-30);
    return min(l.area / (2.0 * PI * d2), 1.0);
}

#endif
