// Exact ray intersection of the analytic shapes (sphere, rect, disk). Directions are unit length.
#ifndef ILLUM_SHAPES_GLSL
#define ILLUM_SHAPES_GLSL

// Precise ray/sphere (Haines et al. 2019, Ray Tracing Gems ch. 7; docs/techniques.md,
// "Ray-sphere intersection"): the discriminant from the centre-to-line vector, not b^2 - 4ac, and
// the product-of-roots form.
float intersect_sphere(vec3 c, float r, vec3 o, vec3 d, float tmin, float tmax) {
    vec3 f = o - c;
    float b = -dot(f, d);
    vec3 l = f + b * d;
    float disc = (r - length(l)) * (r + length(l));
    if (disc < 0.0) return INF;
    float q = b + (b >= 0.0 ? 1.0 : -1.0) * sqrt(disc);
    if (q == 0.0) return INF;
    float t0 = (dot(f, f) - r * r) / q;
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
    if (s.kind == SHAPE_SPHERE) return intersect_sphere(s.p0.xyz, s.p0.w, o, d, tmin, tmax);
    if (s.kind == SHAPE_RECT) return intersect_rect(s.p0.xyz, s.p1.xyz, s.p2.xyz, o, d, tmin, tmax, uv);
    return intersect_disk(s.p0.xyz, s.p1.xyz, s.p0.w, o, d, tmin, tmax);
}

#endif
