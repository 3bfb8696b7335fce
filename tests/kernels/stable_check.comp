// Test kernel of the numerically stable helpers of glsl/shared/ at their extremes (tests/stable.rs).
// Each input record is five vec4 (a, b, c, d, e) with the case in uint(e.w); each output record is
// two vec4 (r0, r1). Unused components are 0.
// * Case 0, sphere light (sample_sphere, light_pdf): a = (centre, radius), b = (p, u.x),
//   c = (unit w, u.y). r0 = (sample pdf, light_pdf(sample wi), light_pdf(w), sample dist),
//   r1 = (sample wi, light_hit(w).t).
// * Case 1, rect solid angle: a = p, b = corner, c = edge x, d = edge y.
//   r0.x = rect_solid_angle(p, corner, ex, ey).
// * Case 2, ray/sphere: a = (centre, radius), b = origin, c = direction, d.xy = (|c| - r, |c|)
//   in double precision. r0.x = intersect_sphere(centre, radius, d.xy, o, d, 0, INF).
// * Case 3, offset from a rect: a = (p, side), b = rect centre, c = edge u, d = edge v, e.xyz = ray
//   direction. ng = side * normalize(u x v); o = offset_ray_origin(p, ng).
//   r0 = (o, intersect_rect(centre, u, v, o, dir, 0, INF)), r1 = (ng, 0).
// * Case 4, offset from a disk: a = (p, side), b = (disk centre, radius), c = disk normal,
//   e.xyz = ray direction. ng = side * normal; r0 = (o, intersect_disk(..., o, dir, 0, INF)),
//   r1 = (ng, 0).
// * Case 5, sun cone: a = (unit direction, 1 - cos(theta_max)), b.xy = u.
//   r0 = (sample wi, sample pdf), r1 = (light_pdf(sample wi), delta, 0, 0).
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "lights/light_sampling.glsl"
#include "trace/shapes.glsl"

layout(local_size_x = 64) in;
struct Record {
    vec4 a, b, c, d, e;
};
struct Result {
    vec4 r0, r1;
};
layout(scalar, binding = 0) readonly buffer ParamBlock { uvec4 unused; };
layout(scalar, binding = 1) readonly buffer InputBlock { Record inputs[]; };
layout(scalar, binding = 2) writeonly buffer OutputBlock { Result outputs[]; };
layout(push_constant) uniform Push { uvec4 pc; };

GpuLight make_light(uint kind, vec4 p0, vec4 p1) {
    return GpuLight(p0, p1.xyz, 0u, vec4(0.0), vec3(1.0), kind, 0xffffffffu, 0xffffffffu, 0u, 0.0, vec3(0.0), 0u);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.y) return;
    Record q = inputs[i];
    uint kind = uint(q.e.w);
    GpuDomeSampling no_dome = GpuDomeSampling(0ul, 0ul, 0ul, 0ul, 0u, 0u, 0.0, 0.0, 0u, 0u, 0u, 0u, vec4[9](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0)));
    Result res;
    res.r0 = vec4(0.0);
    res.r1 = vec4(0.0);
    if (kind == 0u) {
        GpuLight l = make_light(LIGHT_SPHERE, q.a, vec4(0.0));
        vec3 p = q.b.xyz;
        LightSample s = sample_sphere(l, p, vec2(q.b.w, q.c.w));
        LightHit h = light_hit(l, no_dome, p, vec3(0.0), q.c.xyz);
        res.r0 = vec4(s.pdf, light_pdf(l, no_dome, p, vec3(0.0), s.wi), h.pdf, s.dist);
        res.r1 = vec4(s.wi, h.t);
    } else if (kind == 1u) {
        res.r0.x = rect_solid_angle(q.a.xyz, q.b.xyz, q.c.xyz, q.d.xyz);
    } else if (kind == 2u) {
        res.r0.x = intersect_sphere(q.a.xyz, q.a.w, q.d.xy, q.b.xyz, q.c.xyz, 0.0, INF);
    } else if (kind == 3u) {
        vec3 ng = q.a.w * normalize(cross(q.c.xyz, q.d.xyz));
        vec3 o = offset_ray_origin(q.a.xyz, ng);
        vec2 uv;
        res.r0 = vec4(o, intersect_rect(q.b.xyz, q.c.xyz, q.d.xyz, o, q.e.xyz, 0.0, INF, uv));
        res.r1 = vec4(ng, 0.0);
    } else if (kind == 4u) {
        vec3 ng = q.a.w * q.c.xyz;
        vec3 o = offset_ray_origin(q.a.xyz, ng);
        res.r0 = vec4(o, intersect_disk(q.b.xyz, q.c.xyz, q.b.w, o, q.e.xyz, 0.0, INF));
        res.r1 = vec4(ng, 0.0);
    } else if (kind == 5u) {
        GpuLight l = make_light(LIGHT_SUN, vec4(q.a.xyz, 1.0 - q.a.w), vec4(q.a.w, 0.0, 0.0, 0.0));
        LightSample s = sample_sun(l, q.b.xy);
        res.r0 = vec4(s.wi, s.pdf);
        res.r1 = vec4(light_pdf(l, no_dome, vec3(0.0), vec3(0.0), s.wi), s.delta ? 1.0 : 0.0, 0.0, 0.0);
    }
    outputs[i] = res;
}
