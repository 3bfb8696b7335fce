// The samplers of the area lights (light_sampling.glsl states the conventions and what each
// sampler does): rect, sphere, disk and triangle, each with its *_hit() of a direction.
#ifndef ILLUM_AREA_LIGHTS_GLSL
#define ILLUM_AREA_LIGHTS_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "lights/light_sample.glsl"

// ---------------------------------------------------------------------------------------------
// Rect

// Solid angle of a triangle (a, b, c relative to the viewpoint), Van Oosterom & Strackee 1983,
// with the triple product a.(e1 x e2) passed in (computed from exact edge vectors).
float vos_triangle(vec3 a, vec3 b, vec3 c, float triple) {
    float la = length(a), lb = length(b), lc = length(c);
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    float num = abs(triple);
    if (num == 0.0) return 0.0;
    return 2.0 * atan2_accurate(num, den);
}

// Solid angle of the rect with corner s and full edges ex, ey, seen from p.
float rect_solid_angle(vec3 p, vec3 s, vec3 ex, vec3 ey) {
    vec3 a = s - p;
    vec3 b = a + ex;
    vec3 c = b + ey;
    vec3 d = a + ey;
    float triple = dot(a, cross(ex, ey));   // = a.((b-a) x (c-a)) = a.((c-a) x (d-a))
    return vos_triangle(a, b, c, triple) + vos_triangle(a, c, d, triple);
}

bool rect_use_solid_angle(float omega) { return omega >= RECT_OMEGA_MIN && omega <= RECT_OMEGA_MAX; }

LightHit rect_hit(GpuLight l, vec3 p, vec3 w);

LightSample sample_rect(GpuLight l, vec3 p, vec2 u) {
    LightSample s = no_light_sample();
    vec3 ex = l.p1.xyz, ey = l.p2.xyz;
    vec3 corner = l.p0.xyz - 0.5 * ex - 0.5 * ey;
    vec3 N = cross(ex, ey);
    float area = length(N);
    if (!(area > 0.0)) return s;
    vec3 nl = N / area;
    float side = dot(p - l.p0.xyz, nl);
    if (side == 0.0 || (side < 0.0 && !light_two_sided(l))) return s;
    float omega = rect_solid_angle(p, corner, ex, ey);
    if (omega > RECT_OMEGA_MAX) {
        vec3 w = uniform_hemisphere(side > 0.0 ? -nl : nl, u);
        return light_sample_from_hit(p, w, rect_hit(l, p, w));
    }
    if (!rect_use_solid_angle(omega)) {
        return area_light_sample(p, corner + u.x * ex + u.y * ey, nl, area, u);
    }
    // Urena, Fajardo, King 2013 (docs/techniques.md, "Rect lights"), in the rect's frame with p at
    // the origin.
    float exl = length(ex), eyl = length(ey);
    vec3 X = ex / exl, Y = ey / eyl, Z = cross(X, Y);
    vec3 dd = corner - p;
    float x0 = dot(dd, X), y0 = dot(dd, Y), z0 = dot(dd, Z);
    if (z0 > 0.0) { z0 = -z0; Z = -Z; }
    float x1 = x0 + exl, y1 = y0 + eyl;
    vec3 n0 = normalize(vec3(0.0, z0, -y0));
    vec3 n2 = normalize(vec3(0.0, -z0, y1));
    vec3 n3 = normalize(vec3(z0, 0.0, -x0));
    float b0 = n0.z, b1 = n2.z;
    // The paper's au = u S + k, k = 2 pi - g2 - g3 with g_i the interior angles (acos of -n_i.n_j),
    // S = g0 + g1 + g2 + g3 - 2 pi the solid angle. S is omega (Van Oosterom & Strackee, the pdf's
    // own, exact also where the angles' sum cancels), and cos au, sin au follow from those of
    // t = u S and of g = g2 + g3 by the angle sums, g's from the dot products: no inverse
    // trigonometry (four acos were a tenth of a diffuse room's path tracing time on lavapipe).
    float c2 = clamp(-dot(n2, n3), -1.0, 1.0), c3 = clamp(-dot(n3, n0), -1.0, 1.0);
    float s2 = sqrt(max(0.0, (1.0 - c2) * (1.0 + c2))), s3 = sqrt(max(0.0, (1.0 - c3) * (1.0 + c3)));
    float cg = c2 * c3 - s2 * s3, sg = s2 * c3 + c2 * s3;
    float t = u.x * omega;
    float ct = cos(t), st = sin(t);
    float cau = ct * cg + st * sg;   // cos(t - g) = cos(au)
    float sau = st * cg - ct * sg;   // sin(t - g) = sin(au)
    float fu = (cau * b0 - b1) / (sau != 0.0 ? sau : 1e-30);
    float cu = (fu >= 0.0 ? 1.0 : -1.0) * inversesqrt(fu * fu + b0 * b0);
    cu = clamp(cu, -1.0, 1.0);
    float xu = -(cu * z0) * inversesqrt(max(1.0 - cu * cu, 1e-30));
    xu = clamp(xu, x0, x1);
    float dl = sqrt(xu * xu + z0 * z0);
    float h0 = y0 * inversesqrt(dl * dl + y0 * y0);
    float h1 = y1 * inversesqrt(dl * dl + y1 * y1);
    float hv = h0 + u.y * (h1 - h0);
    float hv2 = hv * hv;
    float yv = hv2 < 1.0 - 1e-6 ? hv * dl * inversesqrt(1.0 - hv2) : (hv > 0.0 ? y1 : y0);
    yv = clamp(yv, y0, y1);
    vec3 q = xu * X + yv * Y + z0 * Z;
    float dist = length(q);
    if (!(dist > 0.0)) return s;
    s.wi = q / dist;
    s.dist = dist;
    s.x = p + q;
    s.n = nl;
    s.uv = vec2((xu - x0) / exl, (yv - y0) / eyl);
    s.pdf = 1.0 / omega;
    return s;
}

LightHit rect_hit(GpuLight l, vec3 p, vec3 w) {
    LightHit h = light_miss();
    vec3 eu = l.p1.xyz, ev = l.p2.xyz;
    vec3 N = cross(eu, ev);
    float area = length(N);
    float dn = dot(w, N);
    if (!(area > 0.0) || dn == 0.0) return h;
    vec3 pc = l.p0.xyz - p;
    float side = -dot(pc, N);
    if (side == 0.0 || (side < 0.0 && !light_two_sided(l))) return h;
    float t = dot(pc, N) / dn;
    if (!(t > 0.0)) return h;
    vec3 q = t * w - pc;
    vec2 a = vec2(dot(q, eu) / dot(eu, eu), dot(q, ev) / dot(ev, ev));
    vec2 margin = LIGHT_EDGE_MARGIN + LIGHT_POSITION_ULPS * t * inversesqrt(vec2(dot(eu, eu), dot(ev, ev)));
    if (any(greaterThan(abs(a), 0.5 + margin))) return h;
    h.t = t;
    h.n = N / area;
    h.uv = clamp(a + 0.5, 0.0, 1.0);
    float omega = rect_solid_angle(p, l.p0.xyz - 0.5 * eu - 0.5 * ev, eu, ev);
    h.pdf = omega > RECT_OMEGA_MAX ? HEMISPHERE_PDF
          : rect_use_solid_angle(omega) ? 1.0 / omega : t * t / abs(dn);   // |dn| = area |cos|
    return h;
}

// ---------------------------------------------------------------------------------------------
// Sphere

LightSample sample_sphere(GpuLight l, vec3 p, vec2 u) {
    LightSample s = no_light_sample();
    vec3 c = l.p0.xyz;
    float r = l.p0.w;
    vec3 dc = c - p;
    float d2 = dot(dc, dc);
    float r2 = r * r;
    if (d2 <= r2 || light_self(l)) {
        // Inside (or on) the sphere: it sees only the inner side.
        if (!light_two_sided(l)) return s;
        vec3 nl = uniform_sphere(u);
        return area_light_sample(p, c + r * nl, nl, 4.0 * PI * r2, direction_to_latlong(nl, vec2(1.0, 0.0)));
    }
    float s2max = r2 / d2;
    float cmax = sqrt(max(0.0, 1.0 - s2max));
    float om = s2max / (1.0 + cmax);     // 1 - cos(theta_max) without cancellation
    float omc = u.x * om;                // 1 - cos(theta)
    float ct = 1.0 - omc;
    float st2 = omc * (2.0 - omc);
    float st = sqrt(max(0.0, st2));
    float phi = 2.0 * PI * u.y;
    float dl = sqrt(d2);
    vec3 z = dc / dl, t, b;
    make_basis(z, t, b);
    s.wi = normalize(st * cos(phi) * t + st * sin(phi) * b + ct * z);
    // Near intersection by the product of the roots: (d^2 - r^2) / (d cos + sqrt(r^2 - d^2 sin^2)).
    s.dist = (dl - r) * (dl + r) / (dl * ct + sqrt(max(0.0, r2 - d2 * st2)));
    s.x = p + s.dist * s.wi;
    s.n = normalize(s.x - c);
    s.uv = direction_to_latlong(s.n, vec2(1.0, 0.0));
    s.pdf = 1.0 / (2.0 * PI * om);
    return s;
}

LightHit sphere_hit(GpuLight l, vec3 p, vec3 w) {
    LightHit h = light_miss();
    vec3 c = l.p0.xyz;
    float r = l.p0.w;
    vec3 dc = c - p;
    float d2 = dot(dc, dc);
    float r2 = r * r;
    if (d2 <= r2 || light_self(l)) {
        if (!light_two_sided(l)) return h;
        // Far root from inside (Haines et al. 2019 discriminant). From a point on the surface, a
        // direction leaving the sphere has a far root of ~0 (rounding): not a hit.
        float bq = dot(dc, w);
        vec3 lq = bq * w - dc;
        float disc = max(0.0, r2 - dot(lq, lq));
        float t = bq + sqrt(disc);
        if (!(t > (light_self(l) ? 1e-4 * r : 0.0))) return h;
        vec3 nl = normalize(p + t * w - c);
        float cl = abs(dot(nl, w));
        if (!(cl > 0.0)) return h;
        h.t = t;
        h.n = nl;
        h.uv = direction_to_latlong(nl, vec2(1.0, 0.0));
        h.pdf = t * t / (4.0 * PI * r2 * cl);
        return h;
    }
    float s2max = r2 / d2;
    float cmax = sqrt(max(0.0, 1.0 - s2max));
    float om = s2max / (1.0 + cmax);
    float dl = sqrt(d2);
    vec3 z = dc / dl;
    if (!in_cone(w, z, om)) return h;
    float ct = dot(w, z);
    vec3 cr = cross(w, z);
    float st2 = dot(cr, cr);
    h.t = (dl - r) * (dl + r) / (dl * max(ct, 0.0) + sqrt(max(0.0, r2 - d2 * st2)));
    h.n = normalize(p + h.t * w - c);
    h.uv = direction_to_latlong(h.n, vec2(1.0, 0.0));
    h.pdf = 1.0 / (2.0 * PI * om);
    return h;
}

// ---------------------------------------------------------------------------------------------
// Disk

LightHit disk_hit(GpuLight l, vec3 p, vec3 w);

LightSample sample_disk(GpuLight l, vec3 p, vec2 u) {
    vec3 c = l.p0.xyz;
    float R = l.p0.w;
    vec3 nl = l.p1.xyz, td = l.p2.xyz, bd = cross(nl, td);
    float side = dot(p - c, nl);
    if (side == 0.0 || (side < 0.0 && !light_two_sided(l))) return no_light_sample();
    bool mixture = planar_mixture(c - p, side, R);
    if (mixture) {
        if (u.x >= 0.5) {
            vec3 w = uniform_hemisphere(side > 0.0 ? -nl : nl, vec2(2.0 * u.x - 1.0, u.y));
            return light_sample_from_hit(p, w, disk_hit(l, p, w));
        }
        u.x *= 2.0;
    }
    vec2 dk = concentric_disk(u);
    LightSample s = area_light_sample(p, c + R * (dk.x * td + dk.y * bd), nl, PI * R * R, 0.5 * dk + 0.5);
    if (mixture && s.pdf > 0.0) s.pdf = planar_mixture_pdf(s.pdf);
    return s;
}

LightHit disk_hit(GpuLight l, vec3 p, vec3 w) {
    LightHit h = light_miss();
    vec3 c = l.p0.xyz;
    float R = l.p0.w;
    vec3 nl = l.p1.xyz;
    vec3 pc = c - p;
    float side = -dot(pc, nl);
    float dn = dot(w, nl);
    if (dn == 0.0 || side == 0.0 || (side < 0.0 && !light_two_sided(l))) return h;
    float t = dot(pc, nl) / dn;
    if (!(t > 0.0)) return h;
    vec3 q = t * w - pc;
    float rm = R * (1.0 + LIGHT_EDGE_MARGIN) + LIGHT_POSITION_ULPS * t;
    if (dot(q, q) > rm * rm) return h;
    h.t = t;
    h.n = nl;
    h.uv = clamp(vec2(dot(q, l.p2.xyz), dot(q, cross(nl, l.p2.xyz))) / (2.0 * R) + 0.5, 0.0, 1.0);
    h.pdf = t * t / (PI * R * R * abs(dn));
    if (planar_mixture(pc, side, R)) h.pdf = planar_mixture_pdf(h.pdf);
    return h;
}

// ---------------------------------------------------------------------------------------------
// Triangle

// The triangle's planar-mixture decision (header): centroid and bounding radius about it, with
// p's signed distance to the plane along the unit normal nl.
bool triangle_mixture(vec3 v0, vec3 e1, vec3 e2, vec3 p, float side) {
    vec3 g = (e1 + e2) / 3.0;
    float rb = sqrt(max(dot(g, g), max(dot(e1 - g, e1 - g), dot(e2 - g, e2 - g))));
    return planar_mixture(v0 + g - p, side, rb);
}

LightHit triangle_hit(GpuLight l, vec3 p, vec3 w);

LightSample sample_triangle(GpuLight l, vec3 p, vec2 u) {
    vec3 v0 = l.p0.xyz, e1 = l.p1.xyz, e2 = l.p2.xyz;
    vec3 N = cross(e1, e2);
    float len = length(N);
    if (!(len > 0.0)) return no_light_sample();
    vec3 nl = N / len;
    float side = dot(p - v0, nl);
    if (side == 0.0 || (side < 0.0 && !light_two_sided(l))) return no_light_sample();
    bool mixture = triangle_mixture(v0, e1, e2, p, side);
    if (mixture) {
        if (u.x >= 0.5) {
            vec3 w = uniform_hemisphere(side > 0.0 ? -nl : nl, vec2(2.0 * u.x - 1.0, u.y));
            return light_sample_from_hit(p, w, triangle_hit(l, p, w));
        }
        u.x *= 2.0;
    }
    float su = sqrt(u.x);
    vec2 bc = vec2(su * (1.0 - u.y), su * u.y);
    LightSample s = area_light_sample(p, v0 + bc.x * e1 + bc.y * e2, nl, 0.5 * len, bc);
    if (mixture && s.pdf > 0.0) s.pdf = planar_mixture_pdf(s.pdf);
    return s;
}

LightHit triangle_hit(GpuLight l, vec3 p, vec3 w) {
    LightHit h = light_miss();
    vec3 v0 = l.p0.xyz, e1 = l.p1.xyz, e2 = l.p2.xyz;
    vec3 N = cross(e1, e2);
    float len = length(N);
    float dn = dot(w, N);
    if (!(len > 0.0) || dn == 0.0) return h;
    float side = dot(p - v0, N);
    if (side == 0.0 || (side < 0.0 && !light_two_sided(l))) return h;
    // Moeller-Trumbore.
    vec3 pv = cross(w, e2);
    float det = dot(e1, pv);
    if (det == 0.0) return h;
    vec3 tv = p - v0;
    float b1 = dot(tv, pv) / det;
    vec3 qv = cross(tv, e1);
    float b2 = dot(w, qv) / det;
    float t = dot(e2, qv) / det;
    float m = LIGHT_EDGE_MARGIN + LIGHT_POSITION_ULPS * t * inversesqrt(min(dot(e1, e1), dot(e2, e2)));
    if (!(t > 0.0) || b1 < -m || b2 < -m || b1 + b2 > 1.0 + m) return h;
    h.t = t;
    h.n = N / len;
    h.uv = clamp(vec2(b1, b2), 0.0, 1.0);   // hits within the edge margin
    h.pdf = 2.0 * t * t / abs(dn);   // t^2 / (area |cos|), area = |N| / 2
    // The sampler's own expression for p's distance to the plane, so both decide alike.
    if (triangle_mixture(v0, e1, e2, p, dot(p - v0, N / len))) h.pdf = planar_mixture_pdf(h.pdf);
    return h;
}

#endif
