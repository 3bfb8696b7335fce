// Light sampling: for every light kind a sampler and the pdf() of an arbitrary direction, with
// pdf() equal to the density the sampler produces (what MIS needs: docs/techniques.md,
// "Light sampling: conventions"; one section per kind below, from "Rect lights" to
// "Dome importance sampling").
//
// Conventions:
// * p is the shading point (camera-relative world space, like GpuLight). Directions are unit.
// * Every pdf is per steradian at p and independent of the radiance. pdf == 0 in a LightSample means
//   "no sample" (p behind a one-sided emitter, inside a one-sided sphere, in the plane of a rect...):
//   it contributes 0 and still counts in the light's sample count N_L.
// * One-sided emitters (rect, disk, triangle, sphere seen from inside) emit toward their normal only,
//   unless LIGHT_FLAG_TWO_SIDED: from behind, sample_*() returns no sample and light_pdf() is 0.
// * Directions on an emitter's silhouette (edges, rims, cone boundaries) are accepted with a margin
//   of 1e-5 of the emitter's size plus ~2 ulp of the hit distance, so that float rounding never
//   makes pdf() 0 for a direction the sampler produced. The extra support has relative measure
//   ~1e-5 (the emitter's own radiance lookup decides whether such a ray hits).
// * LightSample.n is the emitter's geometric normal at x (not flipped toward p); the emitted side
//   is the one with dot(n, -wi) > 0. LightSample.uv follows glsl/scene/surface.glsl's uv of the
//   light's shape (rect: (0,0) at centre - u/2 - v/2; disk: 0.5 + local xy / (2R); sphere: lat-long
//   of the outward normal), the dome's lat-long uv, and barycentrics (b1, b2) for triangles.
//
// Samplers:
// * rect (p0 centre, p1/p2 full edges): solid-angle sampling (Urena et al. 2013, spherical
//   rectangle) when its solid angle Omega is in [1e-3, 6.22] sr, with Omega from two Van Oosterom-
//   Strackee triangles whose triple product comes from the light's own edges (float32-robust,
//   "Rect lights"); area sampling below 1e-3 sr; above 6.22 sr (a rect that nearly encloses p's
//   hemisphere) uniform sampling of the hemisphere facing the rect, a direction that misses it being
//   no sample (>= 99% hit). pdf() takes the same decision from the same Omega.
// * sphere (p0 centre, radius): uniform cone of the visible cap with the stable 1 - cos(theta_max)
//   ("Sphere lights"); from inside (two-sided only) uniform area sampling.
// * disk (p0 centre, radius; p1 normal; p2 tangent): area sampling, concentric map; near a
//   disk large for its distance, the planar mixture below.
// * sun (p0 direction, cos(theta_max); p1.x = 1 - cos(theta_max)): uniform cone; delta light
//   (delta = true, pdf = 1, no MIS) when p1.x == 0 ("Sun lights").
// * triangle (LIGHT_TRIANGLE: p0 vertex 0, p1/p2 edges to vertices 1 and 2): uniform area sampling
//   (b1, b2) = sqrt(u1) (1 - u2, u2). Chosen over spherical-triangle sampling for robustness (no
//   angle differences; the same float32 pitfalls as the rect's angle sum); MIS with BRDF samples
//   covers the grazing configurations where area sampling is noisy; near a triangle large for its
//   distance, the planar mixture below.
// * Planar mixture (disk, triangle): where the emitter's bounding radius rb about its centre is at
//   least p's distance to the emitter's plane and to its bounding sphere (p close to a large
//   emitter: a radius-20 disk 1 unit above), area sampling puts few samples where most light comes
//   from and gives fireflies (weights up to area / d^2). There the sampler draws half its samples by
//   area and half uniformly over the hemisphere facing the emitter (a miss is no sample); pdf =
//   (p_area + 1 / (2 pi)) / 2 bounds every weight by 4 pi times the integrand. The decision
//   depends on p and the light only, and pdf() repeats it.
// * dome: piecewise-constant sampling of the map's cells ("Dome importance sampling";
//   glsl/lights/dome_map.glsl) with the marginal/conditional CDFs of GpuDomeSampling (searched
//   from guide tables), then a uniform position inside the cell:
//   pdf = P(row) P(cell | row) W H / (dω / du dv), 2 pi^2 sin(theta) for lat-long maps, 4 pi for
//   the equal-area square. Probabilities are differences of the stored float CDFs, which is
//   exactly the mass the binary search gives each cell. Without a table (width == 0) the dome is
//   sampled uniformly (pdf = 1 / (4 pi)). LightSample.uv / LightHit.uv are map coordinates.
//   Defensive mixture (GpuDomeSampling.defensive = a > 0, under control variates): a share a of
//   the samples is uniform over the sphere, pdf = a / (4 pi) + (1 - a) p_table, positive in every
//   direction (the SH9 control is nonzero where the table's pdf is 0); a = 0 is the table alone,
//   bit for bit.
#ifndef ILLUM_LIGHT_SAMPLING_GLSL
#define ILLUM_LIGHT_SAMPLING_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "scene/features.glsl"
#include "shared/common.glsl"
#include "lights/dome_map.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeCdfRef { float v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeGuideRef { uvec2 v[]; };

struct LightSample {
    vec3 wi;      // unit direction from p toward the light
    float dist;   // distance from p to x along wi; INF for the dome and the sun
    vec3 x;       // the sampled point on the emitter (area lights)
    float pdf;    // solid-angle pdf of wi; 0: no sample
    vec3 n;       // geometric normal of the emitter at x (area lights)
    bool delta;   // delta light (sun of zero angular size): pdf is 1, no MIS
    vec2 uv;      // texture coordinates on the light (see above)
};

// What a direction w from p sees of one light: the pdf the light's sampler has for w (0 if it never
// produces w), and where w meets the emitter.
struct LightHit {
    float pdf;
    float t;      // hit distance (INF for the dome and the sun, and on a miss)
    vec3 n;       // geometric normal at the hit
    vec2 uv;
};

const float LIGHT_EDGE_MARGIN = 1e-5;      // relative silhouette margin (see the header)
const float LIGHT_POSITION_ULPS = 2.5e-7;  // float32 error of a point at distance t: ~2 ulp of t

// Whether unit w lies in the cone of 1 - cos(theta_max) = om about unit z: |w - z|^2 = 2 (1 - cos)
// (no cancellation), with the relative margin and ~2 ulp of direction error.
bool in_cone(vec3 w, vec3 z, float om) {
    vec3 wz = w - z;
    return dot(wz, wz) <= 2.0 * om * (1.0 + LIGHT_EDGE_MARGIN) + 4.0 * LIGHT_POSITION_ULPS * sqrt(2.0 * om);
}
const float RECT_OMEGA_MIN = 1e-3;         // solid-angle sampling range of rects ("Rect lights")
const float RECT_OMEGA_MAX = 6.22;
const float HEMISPHERE_PDF = 0.5 / PI;     // uniform hemisphere, 1 / (2 pi)

LightSample no_light_sample() {
    LightSample s;
    s.wi = vec3(0.0, 0.0, 1.0);
    s.dist = 0.0;
    s.x = vec3(0.0);
    s.pdf = 0.0;
    s.n = vec3(0.0, 0.0, 1.0);
    s.delta = false;
    s.uv = vec2(0.0);
    return s;
}

LightHit light_miss() {
    LightHit h;
    h.pdf = 0.0;
    h.t = INF;
    h.n = vec3(0.0, 0.0, 1.0);
    h.uv = vec2(0.0);
    return h;
}

bool light_two_sided(GpuLight l) { return (l.flags & LIGHT_FLAG_TWO_SIDED) != 0u; }
bool light_self(GpuLight l) { return (l.flags & LIGHT_FLAG_SELF) != 0u; }

// Completes an area sample at point x with normal nl and area density 1 / area: converts the pdf to
// solid angle (docs/techniques.md, "Light sampling: conventions").
LightSample area_light_sample(vec3 p, vec3 x, vec3 nl, float area, vec2 uv) {
    LightSample s = no_light_sample();
    vec3 q = x - p;
    float d2 = dot(q, q);
    if (!(d2 > 0.0)) return s;
    float d = sqrt(d2);
    s.wi = q / d;
    float cl = abs(dot(nl, s.wi));
    if (!(cl > 0.0)) return s;
    s.dist = d;
    s.x = x;
    s.n = nl;
    s.uv = uv;
    s.pdf = d2 / (area * cl);
    return s;
}

// Uniform direction on the hemisphere about unit z; pdf = 1 / (2 pi).
vec3 uniform_hemisphere(vec3 z, vec2 u) {
    float ct = u.x;
    float st = sqrt(max(0.0, 1.0 - ct * ct));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    make_basis(z, t, b);
    return normalize(st * cos(phi) * t + st * sin(phi) * b + ct * z);
}

// Completes a direction sample w whose hit h (the light's *_hit(), pdf included) is known: a miss
// is no sample.
LightSample light_sample_from_hit(vec3 p, vec3 w, LightHit h) {
    LightSample s = no_light_sample();
    if (!(h.pdf > 0.0) || h.t == INF) return s;
    s.wi = w;
    s.dist = h.t;
    s.x = p + h.t * w;
    s.n = h.n;
    s.uv = h.uv;
    s.pdf = h.pdf;
    return s;
}

// Whether p (pc = emitter centre - p, h = p's signed distance to the emitter's plane) is close to a
// planar emitter of bounding radius rb about that centre: the planar mixture of the header.
bool planar_mixture(vec3 pc, float h, float rb) {
    return rb >= max(abs(h), length(pc) - rb);
}

// The mixture's pdf from the area pdf of the same direction.
float planar_mixture_pdf(float area_pdf) {
    return 0.5 * (area_pdf + HEMISPHERE_PDF);
}

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
    vec3 n1 = normalize(vec3(-z0, 0.0, x1));
    vec3 n2 = normalize(vec3(0.0, -z0, y1));
    vec3 n3 = normalize(vec3(z0, 0.0, -x0));
    float g0 = acos_accurate(-dot(n0, n1));
    float g1 = acos_accurate(-dot(n1, n2));
    float g2 = acos_accurate(-dot(n2, n3));
    float g3 = acos_accurate(-dot(n3, n0));
    float b0 = n0.z, b1 = n2.z;
    float k = 2.0 * PI - g2 - g3;
    float S = g0 + g1 - k;
    float au = u.x * S + k;
    float sau = sin(au);
    float fu = (cos(au) * b0 - b1) / (sau != 0.0 ? sau : 1e-30);
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
// Sun

LightSample sample_sun(GpuLight l, vec2 u) {
    LightSample s = no_light_sample();
    vec3 d = l.p0.xyz;
    float om = l.p1.x;
    s.dist = INF;
    s.n = -d;
    if (om <= 0.0) {
        s.wi = d;
        s.pdf = 1.0;
        s.delta = true;
        return s;
    }
    float omc = u.x * om;
    float st = sqrt(max(0.0, omc * (2.0 - omc)));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    make_basis(d, t, b);
    s.wi = normalize(st * cos(phi) * t + st * sin(phi) * b + (1.0 - omc) * d);
    s.pdf = 1.0 / (2.0 * PI * om);
    return s;
}

LightHit sun_hit(GpuLight l, vec3 w) {
    LightHit h = light_miss();
    float om = l.p1.x;
    if (om <= 0.0) return h;   // a delta light is never hit by a BRDF sample
    if (!in_cone(w, l.p0.xyz, om)) return h;
    h.n = -l.p0.xyz;
    h.pdf = 1.0 / (2.0 * PI * om);
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

// ---------------------------------------------------------------------------------------------
// Dome

// Index i with cdf[i] <= u < cdf[i + 1] among n intervals (cdf[0] = 0, cdf[n] = 1, non-decreasing);
// only intervals of positive width can be returned for u in [0, 1). The guide (one uvec2 per bucket
// of width 1/n in u, src/gpu_scene/dome.rs) bounds the binary search to the few intervals that
// bucket can reach: it returns the same index as a search over all n, in O(1) expected steps.
uint cdf_find(DomeCdfRef cdf, uint base, DomeGuideRef guide, uint gbase, uint n, float u) {
    uvec2 r = guide.v[gbase + min(uint(u * float(n)), n - 1u)];
    uint lo = r.x, hi = r.y;   // invariant: cdf[lo] <= u < cdf[hi] (cdf[n] = 1 > u)
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1u;
        if (cdf.v[base + mid] <= u) lo = mid; else hi = mid;
    }
    return lo;
}

// The table's density at direction w of map coordinates uv (0 where it gives none).
float dome_table_pdf(GpuLight l, GpuDomeSampling ds, vec3 w, vec2 uv) {
    uint W = ds.width, H = ds.height;
    float cu = uv.x - dome_cell_offset(l, W);
    if (cu < 0.0) cu += 1.0;
    uint i = min(uint(max(cu, 0.0) * float(W)), W - 1u);
    uint j = min(uint(max(uv.y, 0.0) * float(H)), H - 1u);
    DomeCdfRef marg = DomeCdfRef(ds.marginal);
    DomeCdfRef cond = DomeCdfRef(ds.conditional);
    uint base = j * (W + 1u);
    float pm = marg.v[j + 1u] - marg.v[j];
    float pc = cond.v[base + i + 1u] - cond.v[base + i];
    float jacobian = dome_jacobian(l, w);
    if (!(jacobian > 0.0)) return 0.0;
    return pm * pc * float(W * H) / jacobian;
}

// The defensive mixture's density from the table's (see the header).
float dome_mix_pdf(GpuDomeSampling ds, float table_pdf) {
    return ds.defensive > 0.0 ? ds.defensive / (4.0 * PI) + (1.0 - ds.defensive) * table_pdf : table_pdf;
}

LightSample sample_dome(GpuLight l, GpuDomeSampling ds, vec2 u) {
    LightSample s = no_light_sample();
    s.dist = INF;
    if (ds.width == 0u) {
        s.wi = uniform_sphere(u);
        s.n = -s.wi;
        s.uv = dome_uv(l, s.wi);
        s.pdf = 1.0 / (4.0 * PI);
        return s;
    }
    if (ds.defensive > 0.0) {
        if (u.x < ds.defensive) {
            s.wi = uniform_sphere(vec2(u.x / ds.defensive, u.y));
            s.n = -s.wi;
            s.uv = dome_uv(l, s.wi);
            s.pdf = dome_mix_pdf(ds, dome_table_pdf(l, ds, s.wi, s.uv));
            return s;
        }
        u.x = (u.x - ds.defensive) / (1.0 - ds.defensive);
    }
    uint W = ds.width, H = ds.height;
    float ux = min(u.x, 0.99999994);
    float uy = min(u.y, 0.99999994);
    DomeCdfRef marg = DomeCdfRef(ds.marginal);
    DomeCdfRef cond = DomeCdfRef(ds.conditional);
    // The guides follow the conditional CDFs: H buckets of the marginal, then W per row.
    DomeGuideRef guide = DomeGuideRef(ds.conditional + 4ul * uint64_t(H * (W + 1u)));
    uint j = cdf_find(marg, 0u, guide, 0u, H, ux);
    float m0 = marg.v[j], m1 = marg.v[j + 1u];
    uint base = j * (W + 1u);
    uint i = cdf_find(cond, base, guide, H + j * W, W, uy);
    float c0 = cond.v[base + i], c1 = cond.v[base + i + 1u];
    float pm = m1 - m0, pc = c1 - c0;
    if (!(pm > 0.0) || !(pc > 0.0)) return s;
    float fy = clamp((ux - m0) / pm, 0.0, 1.0);
    float fx = clamp((uy - c0) / pc, 0.0, 1.0);
    vec2 uv = vec2((float(i) + fx) / float(W) + dome_cell_offset(l, W), (float(j) + fy) / float(H));
    if (uv.x >= 1.0) uv.x -= 1.0;
    float jacobian;
    s.wi = dome_direction(l, uv, jacobian);
    if (!(jacobian > 0.0)) return s;
    s.n = -s.wi;
    s.uv = uv;
    s.pdf = dome_mix_pdf(ds, pm * pc * float(W * H) / jacobian);
    return s;
}

LightHit dome_hit(GpuLight l, GpuDomeSampling ds, vec3 w) {
    LightHit h = light_miss();
    h.n = -w;
    h.uv = dome_uv(l, w);
    if (ds.width == 0u) {
        h.pdf = 1.0 / (4.0 * PI);
        return h;
    }
    h.pdf = dome_mix_pdf(ds, dome_table_pdf(l, ds, w, h.uv));
    return h;
}

// ---------------------------------------------------------------------------------------------
// Any light. `dome` is only read for LIGHT_DOME. Each kind behind its feature bit: a scene's
// kernel holds the samplers of the kinds it has (10% less LLVM time for a rect and a dome).

LightSample sample_light(GpuLight l, GpuDomeSampling dome, vec3 p, vec2 u) {
    if (light_is(l, LIGHT_RECT)) return sample_rect(l, p, u);
    if (light_is(l, LIGHT_SPHERE)) return sample_sphere(l, p, u);
    if (light_is(l, LIGHT_DISK)) return sample_disk(l, p, u);
    if (light_is(l, LIGHT_SUN)) return sample_sun(l, u);
    if (light_is(l, LIGHT_TRIANGLE)) return sample_triangle(l, p, u);
    if (light_is(l, LIGHT_DOME)) return sample_dome(l, dome, u);
    return no_light_sample();
}

LightHit light_hit(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 w) {
    if (light_is(l, LIGHT_RECT)) return rect_hit(l, p, w);
    if (light_is(l, LIGHT_SPHERE)) return sphere_hit(l, p, w);
    if (light_is(l, LIGHT_DISK)) return disk_hit(l, p, w);
    if (light_is(l, LIGHT_SUN)) return sun_hit(l, w);
    if (light_is(l, LIGHT_TRIANGLE)) return triangle_hit(l, p, w);
    if (light_is(l, LIGHT_DOME)) return dome_hit(l, dome, w);
    return light_miss();
}

// The solid-angle density with which sample_light() produces w (0 where it never does).
float light_pdf(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 w) {
    return light_hit(l, dome, p, w).pdf;
}

#endif
