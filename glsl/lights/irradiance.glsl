// Analytic unshadowed irradiance of the light shapes at a point p with normal n, for the control
// variates (the course's diffConvolution; docs/techniques.md, "Analytic unshadowed irradiance"
// and "Control variates").
//
// Conventions:
// * irradiance_*() of an area light returns E / L for a uniform emitter of radiance L, i.e.
//   pi * form factor (integral over the visible emitter of max(0, n.w) dw). Multiply by the light's
//   (mean) radiance. The sun returns E / E_perp (GpuLight.radiance holds E_perp). The dome's
//   control is SH9: sh9_irradiance() of its coefficients; light_irradiance() gives 0.
// * The same one-sidedness as light_sampling.glsl: p behind a one-sided emitter (or inside a
//   one-sided sphere) gets 0; the receiver hemisphere is clipped at n's horizon (max(0, n.w)),
//   so the result is the exact integral the samples of light_sampling.glsl estimate with
//   g = L max(0, n.wi) / pdf.
// Formulas:
// * sphere and sun: the cap formula of Snyder 1996 in the Frostbite form, exact including the
//   horizon crossing; sin^2 and cos of the cap's angular radius come in precomputed without
//   cancellation. Inside a two-sided sphere: pi.
// * rect, triangle: Lambert's polygon formula with the Hill & Heitz 2017 rational edge term (1/(2 pi)
//   included) after Sutherland-Hodgman clipping against n's tangent plane, done edge by edge while
//   streaming the vertices (a convex polygon crosses the plane at most twice: the clipped polygon is
//   the visible parts of its edges plus one closing edge in the plane). Lights that subtend less
//   than 1e-4 sr (area / d^2) use the point approximation A cos_l max(0, cos_r) / d^2, which is more
//   accurate in float32 there (8e-8 vs 4e-3 at size/distance 1e-3).
// * disk: the closed-form vector irradiance, written without cancellation, while the whole
//   disk is above the horizon; across the horizon a regular 32-gon with the disk's area, clipped
//   as above (error O(1/N^2): below 2e-3 relative in tests/sampling.rs's cases).
#ifndef ILLUM_IRRADIANCE_GLSL
#define ILLUM_IRRADIANCE_GLSL

#include "shared/layout.glsl"
#include "scene/features.glsl"
#include "shared/common.glsl"

const float IRR_POINT_SOLID_ANGLE = 1e-4;   // below: point approximation for rects and triangles
const int IRR_DISK_SIDES = 32;

// E / L of a uniform spherical cap of angular radius sigma (sin^2 sigma = s2, cos sigma = cs >= 0)
// whose centre makes cos(theta) = ct with the normal; exact, including the horizon crossing.
// Snyder's crossing term (ct acos(y) - x z) s2 + atan(z / x), x = cot(sigma), cancels badly for small
// caps (the sun: atan(z/x) and x z s2 agree to 1 part in 1e4), so it is evaluated as
// ct acos(y) s2 + u s2 + (atan(u) - u) with u = z / x, using x z s2 = u - u s2 exactly and a series
// for atan(u) - u at small u.
float irradiance_cap(float ct, float s2, float cs) {
    if (ct * ct >= s2) return PI * s2 * max(ct, 0.0);   // entirely above or below the horizon
    float st = sqrt(max(1.0 - ct * ct, 1e-12));
    float x = cs * inversesqrt(s2);                     // cot(sigma)
    float y = clamp(-x * ct / st, -1.0, 1.0);
    float z = st * sqrt(max(0.0, (1.0 - y) * (1.0 + y)));
    if (cs < 1e-3) return max(0.0, (ct * acos_accurate(y) - x * z) * s2 + atan2_accurate(z, x));
    float u = z / x;
    float d;   // atan(u) - u
    if (u < 0.3) {
        float u2 = u * u;
        d = u * u2 * (-1.0 / 3.0 + u2 * (1.0 / 5.0 + u2 * (-1.0 / 7.0 + u2 * (1.0 / 9.0 + u2 * (-1.0 / 11.0 + u2 * (1.0 / 13.0 - u2 / 15.0))))));
    } else {
        d = atan2_accurate(z, x) - u;
    }
    return max(0.0, ct * acos_accurate(y) * s2 + u * s2 + d);
}

float irradiance_sphere(vec3 p, vec3 n, vec3 c, float r, bool two_sided) {
    vec3 dc = c - p;
    float d2 = dot(dc, dc);
    float r2 = r * r;
    if (d2 <= r2) return two_sided ? PI : 0.0;
    float s2 = r2 / d2;
    float cs = sqrt(max(0.0, 1.0 - s2));
    return irradiance_cap(dot(n, dc) * inversesqrt(d2), s2, cs);
}

// Sun: E / E_perp for the uniform cone of 1 - cos(theta_s) = om about the unit direction s; the
// delta sun (om == 0) gives max(0, n.s).
float irradiance_sun(vec3 n, vec3 s, float om) {
    float ct = dot(n, s);
    if (om <= 0.0) return max(ct, 0.0);
    float s2 = om * (2.0 - om);
    return irradiance_cap(ct, s2, 1.0 - om) / (PI * s2);
}

// n . (edge term of a polygon edge from a to b), a and b relative to p (Hill & Heitz 2017 fit of
// theta / (2 pi sin(theta)); includes the 1/(2 pi)). b - a is passed in when known exactly.
float polygon_edge(vec3 n, vec3 a, vec3 b, vec3 ab) {
    float la = length(a), lb = length(b);
    if (!(la > 0.0) || !(lb > 0.0)) return 0.0;
    float x = dot(a, b) / (la * lb);
    float y = abs(x);
    float v = (0.8543985 + (0.4965155 + 0.0145206 * y) * y) / (3.4175940 + (4.1616724 + y) * y);
    float k = x > 0.0 ? v : 0.5 * inversesqrt(max(1.0 - x * x, 1e-7)) - v;
    // a x b = a x (b - a): the cross product of two nearly parallel directions from the exact edge.
    return dot(n, cross(a, ab)) * (k / (la * lb));
}

// Streaming Sutherland-Hodgman against the plane n.x >= 0: adds the visible part of the edge a -> b
// to `sum` and records where the polygon leaves (exit) and re-enters (entry) the upper side.
void polygon_clip_edge(vec3 n, vec3 a, vec3 b, inout float sum, inout vec3 exit_p, inout vec3 entry_p, inout int crossings) {
    float da = dot(n, a), db = dot(n, b);
    if (da >= 0.0 && db >= 0.0) {
        sum += polygon_edge(n, a, b, b - a);
    } else if (da >= 0.0) {
        vec3 x = a + (da / (da - db)) * (b - a);
        sum += polygon_edge(n, a, x, x - a);
        exit_p = x;
        crossings += 1;
    } else if (db >= 0.0) {
        vec3 x = a + (da / (da - db)) * (b - a);
        sum += polygon_edge(n, x, b, b - x);
        entry_p = x;
        crossings += 1;
    }
}

float polygon_close(vec3 n, float sum, vec3 exit_p, vec3 entry_p, int crossings) {
    if (crossings >= 2) sum += polygon_edge(n, exit_p, entry_p, entry_p - exit_p);
    return PI * abs(sum);
}

// Quad with vertices q0..q3 relative to p (convex, either winding), clipped at n's horizon.
float irradiance_quad(vec3 n, vec3 q0, vec3 q1, vec3 q2, vec3 q3) {
    float sum = 0.0;
    vec3 ex = vec3(0.0), en = vec3(0.0);
    int c = 0;
    polygon_clip_edge(n, q0, q1, sum, ex, en, c);
    polygon_clip_edge(n, q1, q2, sum, ex, en, c);
    polygon_clip_edge(n, q2, q3, sum, ex, en, c);
    polygon_clip_edge(n, q3, q0, sum, ex, en, c);
    return polygon_close(n, sum, ex, en, c);
}

float irradiance_tri(vec3 n, vec3 q0, vec3 q1, vec3 q2) {
    float sum = 0.0;
    vec3 ex = vec3(0.0), en = vec3(0.0);
    int c = 0;
    polygon_clip_edge(n, q0, q1, sum, ex, en, c);
    polygon_clip_edge(n, q1, q2, sum, ex, en, c);
    polygon_clip_edge(n, q2, q0, sum, ex, en, c);
    return polygon_close(n, sum, ex, en, c);
}

// Point approximation of a small planar emitter of area A, unnormalised normal N (|N| = A), centre
// offset pc = centre - p.
float irradiance_point(vec3 n, vec3 pc, vec3 N) {
    float d2 = dot(pc, pc);
    return abs(dot(N, pc)) * max(0.0, dot(n, pc)) / (d2 * d2);
}

// Rect with centre c and full edges eu, ev (normal normalize(eu x ev)).
float irradiance_rect(vec3 p, vec3 n, vec3 c, vec3 eu, vec3 ev, bool two_sided) {
    vec3 N = cross(eu, ev);
    vec3 pc = c - p;
    float side = -dot(pc, N);
    if (side == 0.0 || (side < 0.0 && !two_sided)) return 0.0;
    float area = length(N);
    if (area < IRR_POINT_SOLID_ANGLE * dot(pc, pc)) return irradiance_point(n, pc, N);
    vec3 a = pc - 0.5 * eu - 0.5 * ev;
    return irradiance_quad(n, a, a + eu, a + eu + ev, a + ev);
}

// Triangle with vertex v0 and edges e1, e2 (normal normalize(e1 x e2)).
float irradiance_triangle(vec3 p, vec3 n, vec3 v0, vec3 e1, vec3 e2, bool two_sided) {
    vec3 N = cross(e1, e2);
    vec3 a = v0 - p;
    float side = -dot(a, N);
    if (side == 0.0 || (side < 0.0 && !two_sided)) return 0.0;
    vec3 pc = a + (e1 + e2) / 3.0;
    if (0.5 * length(N) < IRR_POINT_SOLID_ANGLE * dot(pc, pc)) return irradiance_point(n, pc, 0.5 * N);
    return irradiance_tri(n, a, a + e1, a + e2);
}

// Disk with centre c, unit normal nd, unit tangent td, radius R.
float irradiance_disk(vec3 p, vec3 n, vec3 c, vec3 nd, vec3 td, float R, bool two_sided) {
    vec3 pc = c - p;
    float h = -dot(pc, nd);   // height of p above the disk plane, on the normal's side
    if (h == 0.0 || (h < 0.0 && !two_sided)) return 0.0;
    if (h < 0.0) { nd = -nd; h = -h; }
    // Whole disk above (or below) n's horizon: n.(x - p) over the rim ranges over
    // n.pc +- R |n - (n.nd) nd|.
    float nn = dot(n, nd);
    float reach = R * sqrt(max(0.0, 1.0 - nn * nn));
    float np = dot(n, pc);
    if (np <= -reach) return 0.0;
    if (np >= reach) {
        // Vector irradiance (docs/techniques.md, "Analytic unshadowed irradiance") with S - Q and
        // Q - A formed without cancellation:
        // Q^2 = A^2 + 4 h^2 R^2 = S^2 - 4 a^2 R^2, A = h^2 + a^2 - R^2, S = h^2 + a^2 + R^2.
        vec3 radial = -pc - h * nd;              // from the axis to p, in the disk plane
        float a2 = dot(radial, radial);
        float a = sqrt(a2);
        float h2 = h * h, R2 = R * R;
        float A = h2 + a2 - R2;
        float S = h2 + a2 + R2;
        float Q = sqrt(A * A + 4.0 * h2 * R2);
        // E_z / L = (pi/2)(1 - A/Q): toward the disk plane (-nd).
        float ez = A > 0.0 ? 2.0 * PI * h2 * R2 / (Q * (Q + A)) : 0.5 * PI * (1.0 - A / Q);
        // E_r / L = (pi/2)(h/a)(S/Q - 1) = 2 pi h a R^2 / (Q (S + Q)): toward the axis (-radial/a).
        float er_over_a = 2.0 * PI * h * R2 / (Q * (S + Q));
        return max(0.0, -ez * nn - er_over_a * dot(n, radial));
    }
    // Across the horizon: a regular N-gon of the same area, clipped.
    const float N_SIDES = float(IRR_DISK_SIDES);
    float Rn = R * sqrt(2.0 * PI / (N_SIDES * sin(2.0 * PI / N_SIDES)));
    vec3 bd = cross(nd, td);
    float sum = 0.0;
    vec3 ex = vec3(0.0), en = vec3(0.0);
    int cr = 0;
    vec3 first = pc + Rn * td;
    vec3 prev = first;
    for (int k = 1; k <= IRR_DISK_SIDES; ++k) {
        float phi = 2.0 * PI * float(k) / N_SIDES;
        vec3 q = k == IRR_DISK_SIDES ? first : pc + Rn * (cos(phi) * td + sin(phi) * bd);
        polygon_clip_edge(n, prev, q, sum, ex, en, cr);
        prev = q;
    }
    return polygon_close(n, sum, ex, en, cr);
}

// Real SH9 of order (l, m) = 00, 1-1, 10, 11, 2-2, 2-1, 20, 21, 22 (src/gpu_scene/dome_sh.rs
// `basis`): sum_lm k_l c_lm Y_lm(d), band l scaled by k[l].
vec3 sh9_sum(vec4 c[9], vec3 d, vec3 k) {
    float x = d.x, y = d.y, z = d.z;
    vec3 b1 = 0.48860251 * (y * c[1].xyz + z * c[2].xyz + x * c[3].xyz);
    vec3 b2 = 1.09254843 * (x * y * c[4].xyz + y * z * c[5].xyz + x * z * c[7].xyz)
        + 0.31539157 * (3.0 * z * z - 1.0) * c[6].xyz + 0.54627422 * (x * x - y * y) * c[8].xyz;
    return k.x * 0.28209479 * c[0].xyz + k.y * b1 + k.z * b2;
}

// L_SH(d): the SH9 function of coefficients c in direction d.
vec3 sh9_eval(vec4 c[9], vec3 d) { return sh9_sum(c, d, vec3(1.0)); }

// Its exact clamped-cosine integral about n (Funk-Hecke, Ramamoorthi & Hanrahan 2001):
// E(n) = sum A_l c_lm Y_lm(n), A = pi, 2 pi / 3, pi / 4.
vec3 sh9_irradiance(vec4 c[9], vec3 n) { return sh9_sum(c, n, vec3(PI, 2.0 * PI / 3.0, 0.25 * PI)); }

// The factor by which GpuLight.radiance multiplies: E / L for rect, disk, sphere and triangle
// lights, E / E_perp for the sun, 0 for the dome (see the header).
float light_irradiance(GpuLight l, vec3 p, vec3 n) {
    bool two = (l.flags & LIGHT_FLAG_TWO_SIDED) != 0u;
    if (light_is(l, LIGHT_RECT)) return irradiance_rect(p, n, l.p0.xyz, l.p1.xyz, l.p2.xyz, two);
    if (light_is(l, LIGHT_DISK)) return irradiance_disk(p, n, l.p0.xyz, l.p1.xyz, l.p2.xyz, l.p0.w, two);
    if (light_is(l, LIGHT_SPHERE)) return irradiance_sphere(p, n, l.p0.xyz, l.p0.w, two);
    if (light_is(l, LIGHT_SUN)) return irradiance_sun(n, l.p0.xyz, l.p1.x);
    if (light_is(l, LIGHT_TRIANGLE)) return irradiance_triangle(p, n, l.p0.xyz, l.p1.xyz, l.p2.xyz, two);
    return 0.0;
}

#endif
