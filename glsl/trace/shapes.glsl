// Exact ray intersection of the analytic shapes (sphere, rect, disk). Directions are unit length.
#ifndef ILLUM_SHAPES_GLSL
#define ILLUM_SHAPES_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"

// |v| without overflow or underflow of the squares (a sphere may be 1e30 across).
float safe_length(vec3 v) {
    float m = max(max(abs(v.x), abs(v.y)), abs(v.z));
    return m > 0.0 ? m * length(v / m) : 0.0;
}

// The signed distance |o - c| - r of o to a sphere, with |o - c| = fl (see intersect_sphere).
float sphere_distance(vec3 c, vec2 hc, vec3 o, float fl) {
    float den = fl + hc.y;
    return hc.x + (den > 0.0 ? dot(o, (o - 2.0 * c) / den) : 0.0);
}

// Precise ray/sphere (Haines et al. 2019, Ray Tracing Gems ch. 7; docs/techniques.md,
// "Ray-sphere intersection"): the discriminant from the centre-to-line vector l, not b^2 - 4ac,
// and the near root from the product of the roots, c = |f|^2 - r^2 = h (|f| + r) with
// h = |o - c| - r the signed distance of the origin to the surface. h comes from the host's
// double-precision h0 = |c| - r and |c| (hc, for the frame's origin, where camera rays start)
// and the exact identity |o - c| - |c| = o . (o - 2c) / (|o - c| + |c|), so that it keeps the
// precision of o, not of the sphere's size: a camera 1.5 above a sphere of radius 1e8 gets
// h = 1.5, where f.f - r^2 rounds to a multiple of 1e9. No intermediate exceeds O(r) (r^2
// overflows from 1.8e19).
float intersect_sphere(vec3 c, float r, vec2 hc, vec3 o, vec3 d, float tmin, float tmax) {
    vec3 f = o - c;
    float fl = safe_length(f);
    float h = sphere_distance(c, hc, o, fl);
    float b = -dot(f, d);
    float ll = safe_length(f + b * d);
    if (ll > r) return INF;
    float root = sqrt(r - ll) * sqrt(r + ll);
    float q = b + (b >= 0.0 ? root : -root);
    if (q == 0.0) return INF;
    float t0 = h * ((fl + r) / q);
    float t1 = q;
    float lo = min(t0, t1), hi = max(t0, t1);
    if (lo > tmin && lo < tmax) return lo;
    if (hi > tmin && hi < tmax) return hi;
    return INF;
}

// Rect with centre c and full edges u, v; returns t and the uv in [0,1]^2 of the hit.
float intersect_rect(vec3 c, vec3 u, vec3 v, vec3 o, vec3 d, float tmin, float tmax, out vec2 uv) {
    vec3 n = cross(u, v);
    float dn = dot(d, n);
    uv = vec2(0.0);
    if (dn == 0.0) return INF;
    float t = dot(c - o, n) / dn;
    if (!(t > tmin && t < tmax)) return INF;
    vec3 q = o + t * d - c;
    vec2 a = vec2(dot(q, u) / dot(u, u), dot(q, v) / dot(v, v));
    if (abs(a.x) > 0.5 || abs(a.y) > 0.5) return INF;
    uv = a + 0.5;
    return t;
}

float intersect_disk(vec3 c, vec3 n, float r, vec3 o, vec3 d, float tmin, float tmax) {
    float dn = dot(d, n);
    if (dn == 0.0) return INF;
    float t = dot(c - o, n) / dn;
    if (!(t > tmin && t < tmax)) return INF;
    vec3 q = o + t * d - c;
    return dot(q, q) <= r * r ? t : INF;
}

float intersect_shape(GpuShape s, vec3 o, vec3 d, float tmin, float tmax) {
    vec2 uv;
    if (s.kind == SHAPE_SPHERE) return intersect_sphere(s.p0.xyz, s.p0.w, s.p2.xy, o, d, tmin, tmax);
    if (s.kind == SHAPE_RECT) return intersect_rect(s.p0.xyz, s.p1.xyz, s.p2.xyz, o, d, tmin, tmax, uv);
    return intersect_disk(s.p0.xyz, s.p1.xyz, s.p0.w, o, d, tmin, tmax);
}

#endif
