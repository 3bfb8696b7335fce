// Specular microfacet lobes (GpuLobe): the course's D-BRDF and two Cook-Torrance models, with
// their Fresnel terms, evaluation (f cos and pdf) and importance sampling (docs/techniques.md,
// "The D-BRDF", "Cook-Torrance lobes", "Fresnel" and "Roughness floor and delta lobes").
//
// Conventions (every function here):
// * Directions are unit vectors pointing away from the surface: v toward the viewer, l (wi) toward
//   the light. The local frame is (t, b, n): unit tangent, bitangent and shading normal, right-
//   handed or not (only dot products are taken). alpha.x is the roughness along t, alpha.y along b.
// * Evaluation returns f cos(theta_l) (never f alone: the D-BRDF's f has 1/(n.l)) and the pdf, per
//   steradian, with which brdf_sample() produces l. brdf_sample() returns the direction, the weight
//   f cos / pdf, and the pdf. A sample with valid == false (l below the horizon, v.h <= 0, n.v <= 0)
//   contributes 0 but still counts in the number of samples N (never re-draw, never renormalise).
// * Only the shading-normal hemisphere is tested here. The geometric-normal test
//   sign(ng.l) == sign(ng.v), against light leaks, is the kernel's job.
// * alpha is clamped to >= 1e-4 (Mitsuba 3's floor) and stays a Beckmann/GGX lobe down to there,
//   where float32 still represents it: D's peak 1 / (pi alpha^2) = 3.2e7, pdf^2 in the MIS weights
//   1e15, and the half vector's rounding (~6e-8) is 6e-4 of alpha. Only a lobe uploaded with
//   alpha = 0 (the scene's roughness 0: a perfect mirror) is a delta mirror
//   lobe: brdf_sample() returns the mirror direction with weight F, pdf = 1 (a probability, not a
//   density) and delta = true; brdf_eval() returns 0 for it (a light sample never hits it), and MIS
//   must give its samples weight 1 (mis.glsl).
// * F is evaluated at the angle between v and the half vector h (= l.h).
//
// Models (GpuLobe.distribution):
// * DIST_DBRDF, the course's D-BRDF: Beckmann D, f cos = F D(h) (n.h) / (4 (v.h)). Sampled from
//   D(h)(n.h) with the Box-Muller slope form (docs/techniques.md, "The D-BRDF"), so that the
//   weight is exactly F; pdf = D(h)(n.h) / (4 |v.h|) computed from (1 - u1), without exp().
// * DIST_BECKMANN_SMITH: Cook-Torrance with Beckmann D and the separable Smith G = G1(v) G1(l),
//   G1 by Walter et al. 2007's rational approximation (the Mitsuba 3 `roughconductor` convention).
//   Sampled like the D-BRDF (plain D(h)(n.h), not visible normals); weight F G (v.h)/((n.v)(n.h)).
//   Its albedo differs from the exact-Lambda separable model (docs/techniques.md,
//   "Reference values") by the approximation error of the rational G1 (below 1e-3; tests/brdf.rs
//   measures it).
// * DIST_GGX_SMITH: Cook-Torrance with GGX (Trowbridge-Reitz) D and the height-correlated Smith
//   G2 = 1 / (1 + Lambda(v) + Lambda(l)) (the pbrt-v4 `ConductorBxDF` convention; pbrt's
//   "roughness" is sqrt(alpha), this alpha is alpha). Sampled with visible normals (Heitz 2018):
//   pdf = G1(v) D(h) / (4 (n.v)), weight = F G2 / G1(v).
// * DIST_GGX_SMITH_SEPARABLE: the same with the separable G = G1(v) G1(l) (Mitsuba 3's GGX).
//
// Fresnel (GpuLobe.fresnel): FRESNEL_CONSTANT (fresnel0.rgb), FRESNEL_SCHLICK (f0 = fresnel0.rgb),
// FRESNEL_CONDUCTOR (exact, complex IOR eta = fresnel0.rgb, k = fresnel1.rgb per channel; Mitsuba 3
// `fresnel_conductor`).
#ifndef ILLUM_MICROFACET_GLSL
#define ILLUM_MICROFACET_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"

const float MF_ALPHA_MIN = 1e-4;     // clamp (mitsuba3 configure(), pbrt-v4 TrowbridgeReitz)
const float MF_DELTA_ALPHA = 5e-5;   // below this along both axes (i.e. uploaded as 0): a delta mirror

struct BrdfEval {
    vec3 f_cos;   // f(l, v) cos(theta_l)
    float pdf;    // solid-angle pdf of l under brdf_sample(); 0 where it never goes
};

struct BrdfSample {
    vec3 wi;       // sampled direction l (world space, unit)
    vec3 weight;   // f cos / pdf; 0 when !valid; F for a delta lobe
    float pdf;     // solid-angle pdf of wi (0 when !valid; 1 for a delta lobe)
    bool valid;    // false: the sample contributes 0 but counts in N
    bool delta;    // delta mirror lobe (no MIS; light samples cannot hit it)
};

// ---------------------------------------------------------------------------------------------
// Fresnel

vec3 fresnel_schlick(vec3 f0, float cos_theta) {
    float m = clamp(1.0 - cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

// Unpolarised reflectance of a conductor with complex IOR eta + i k (relative to the outside
// medium), per channel; Mitsuba 3 `fresnel_conductor` (exact, no Schlick).
vec3 fresnel_conductor(float cos_theta, vec3 eta, vec3 k) {
    float c = clamp(cos_theta, 0.0, 1.0);
    float c2 = c * c;
    float s2 = 1.0 - c2;
    float s4 = s2 * s2;
    vec3 t1 = eta * eta - k * k - s2;
    vec3 a2pb2 = sqrt(max(t1 * t1 + 4.0 * k * k * eta * eta, 0.0));
    vec3 a = sqrt(max(0.5 * (a2pb2 + t1), 0.0));
    vec3 term1 = a2pb2 + c2;
    vec3 term2 = 2.0 * c * a;
    vec3 rs = (term1 - term2) / (term1 + term2);
    vec3 term3 = a2pb2 * c2 + s4;
    vec3 term4 = term2 * s2;
    vec3 rp = rs * (term3 - term4) / (term3 + term4);
    return 0.5 * (rs + rp);
}

// F of a lobe at cos_theta = v.h (= l.h).
vec3 lobe_fresnel(GpuLobe lobe, float cos_theta) {
    if (lobe.fresnel == FRESNEL_SCHLICK) return fresnel_schlick(lobe.fresnel0.rgb, cos_theta);
    if (lobe.fresnel == FRESNEL_CONDUCTOR) return fresnel_conductor(cos_theta, lobe.fresnel0.rgb, lobe.fresnel1.rgb);
    return lobe.fresnel0.rgb;
}

// ---------------------------------------------------------------------------------------------
// Distributions and Smith terms, in the local frame (x along t, y along b, z along n).

vec2 lobe_alpha(GpuLobe lobe) { return max(lobe.alpha, vec2(MF_ALPHA_MIN)); }
bool lobe_is_delta(GpuLobe lobe) {
    return max(lobe.alpha.x, lobe.alpha.y) < MF_DELTA_ALPHA;
}
bool lobe_is_ggx(GpuLobe lobe) {
    return has_feature(FEATURE_GGX)
        && (lobe.distribution == DIST_GGX_SMITH || lobe.distribution == DIST_GGX_SMITH_SEPARABLE);
}

// Anisotropic Beckmann D(h), h local (docs/techniques.md, "The D-BRDF").
float beckmann_d(vec3 h, vec2 a) {
    if (h.z <= 0.0) return 0.0;
    float c2 = h.z * h.z;
    vec2 s = h.xy / a;
    float e = dot(s, s) / c2;
    return exp(-e) / (PI * a.x * a.y * c2 * c2);
}

// Anisotropic GGX D(h) = 1 / (pi a1 a2 ((hx/a1)^2 + (hy/a2)^2 + hz^2)^2).
float ggx_d(vec3 h, vec2 a) {
    if (h.z <= 0.0) return 0.0;
    vec2 s = h.xy / a;
    float q = dot(s, s) + h.z * h.z;
    return 1.0 / (PI * a.x * a.y * q * q);
}

// alpha_w^2 tan^2(theta_w): the projected roughness of direction w (local, w.z > 0).
float smith_a2t2(vec3 w, vec2 a) {
    vec2 s = a * w.xy;
    return dot(s, s) / (w.z * w.z);
}

// GGX Lambda = (sqrt(1 + a^2 tan^2) - 1) / 2, written without the cancellation at small angles.
float ggx_lambda(vec3 w, vec2 a) {
    float t2 = smith_a2t2(w, a);
    return t2 / (2.0 * (sqrt(1.0 + t2) + 1.0));
}

// Beckmann G1 by Walter et al. 2007's rational fit of 1 / (1 + Lambda) (Mitsuba 3 smith_g1).
float beckmann_g1_walter(vec3 w, vec2 a) {
    float t2 = smith_a2t2(w, a);
    if (t2 <= 0.0) return 1.0;
    float x = inversesqrt(t2);   // 1 / (alpha_w tan(theta_w))
    if (x >= 1.6) return 1.0;
    return (3.535 * x + 2.181 * x * x) / (1.0 + 2.276 * x + 2.577 * x * x);
}

// ---------------------------------------------------------------------------------------------
// Evaluation

vec3 to_local(vec3 w, vec3 n, vec3 t, vec3 b) { return vec3(dot(w, t), dot(w, b), dot(w, n)); }

// f cos(theta_l) and the sampling pdf of l, for a lobe in the frame (n, t, b).
BrdfEval brdf_eval(GpuLobe lobe, vec3 n, vec3 t, vec3 b, vec3 v, vec3 l) {
    BrdfEval e;
    e.f_cos = vec3(0.0);
    e.pdf = 0.0;
    vec3 vl = to_local(v, n, t, b);
    vec3 ll = to_local(l, n, t, b);
    if (vl.z <= 0.0 || ll.z <= 0.0 || lobe_is_delta(lobe)) return e;
    vec3 hs = vl + ll;
    float len2 = dot(hs, hs);
    if (len2 <= 1e-12) return e;
    vec3 h = hs * inversesqrt(len2);
    if (h.z <= 0.0) return e;
    float vh = max(dot(vl, h), 1e-7);
    vec2 a = lobe_alpha(lobe);
    vec3 F = lobe_fresnel(lobe, vh);
    if (lobe.distribution == DIST_DBRDF) {
        e.pdf = beckmann_d(h, a) * h.z / (4.0 * vh);
        e.f_cos = F * e.pdf;
    } else if (lobe.distribution == DIST_BECKMANN_SMITH) {
        float D = beckmann_d(h, a);
        float G = beckmann_g1_walter(vl, a) * beckmann_g1_walter(ll, a);
        e.pdf = D * h.z / (4.0 * vh);
        e.f_cos = F * (D * G / (4.0 * vl.z));
    } else if (lobe_is_ggx(lobe)) {
        float D = ggx_d(h, a);
        float lv = ggx_lambda(vl, a);
        float ll_ = ggx_lambda(ll, a);
        float G1v = 1.0 / (1.0 + lv);
        float G = lobe.distribution == DIST_GGX_SMITH_SEPARABLE ? G1v / (1.0 + ll_) : 1.0 / (1.0 + lv + ll_);
        e.pdf = G1v * D / (4.0 * vl.z);
        e.f_cos = F * (D * G / (4.0 * vl.z));
    }
    return e;
}

float brdf_pdf(GpuLobe lobe, vec3 n, vec3 t, vec3 b, vec3 v, vec3 l) {
    return brdf_eval(lobe, n, t, b, v, l).pdf;
}

// ---------------------------------------------------------------------------------------------
// Sampling. u in [0,1)^2; u.x = 1 is tolerated (clamped so that log(0) never happens).

BrdfSample brdf_sample(GpuLobe lobe, vec3 n, vec3 t, vec3 b, vec3 v, vec2 u) {
    BrdfSample s;
    s.wi = n;
    s.weight = vec3(0.0);
    s.pdf = 0.0;
    s.valid = false;
    s.delta = false;
    vec3 vl = to_local(v, n, t, b);
    if (vl.z <= 0.0) return s;
    if (lobe_is_delta(lobe)) {
        s.wi = 2.0 * vl.z * n - v;
        s.weight = lobe_fresnel(lobe, vl.z);
        s.pdf = 1.0;
        s.valid = true;
        s.delta = true;
        return s;
    }
    vec2 a = lobe_alpha(lobe);
    vec3 h;
    float pdf;
    if (lobe_is_ggx(lobe)) {
        // Visible normals (Heitz 2018, JCGT 7(4)): warp to the hemisphere configuration.
        vec3 Vh = normalize(vec3(a.x * vl.x, a.y * vl.y, vl.z));
        float lensq = Vh.x * Vh.x + Vh.y * Vh.y;
        vec3 T1 = lensq > 1e-14 ? vec3(-Vh.y, Vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
        vec3 T2 = cross(Vh, T1);
        float r = sqrt(u.x);
        float phi = 2.0 * PI * u.y;
        float t1 = r * cos(phi);
        float t2 = r * sin(phi);
        float sw = 0.5 * (1.0 + Vh.z);
        t2 = (1.0 - sw) * sqrt(max(0.0, 1.0 - t1 * t1)) + sw * t2;
        vec3 Nh = t1 * T1 + t2 * T2 + sqrt(max(0.0, 1.0 - t1 * t1 - t2 * t2)) * Vh;
        h = normalize(vec3(a.x * Nh.x, a.y * Nh.y, max(1e-7, Nh.z)));
        pdf = 0.0;  // set below, once l is known to be valid
    } else {
        // Beckmann D(h)(n.h) by Box-Muller slopes (docs/techniques.md, "The D-BRDF"): exponent =
        // r^2 = -log(1 - u1).
        float om = max(1.0 - u.x, 5.9604645e-8);
        float r = sqrt(-log(om));
        float psi = 2.0 * PI * u.y;
        vec2 slope = r * vec2(a.x * cos(psi), a.y * sin(psi));
        float hz = inversesqrt(1.0 + dot(slope, slope));
        h = vec3(-slope * hz, hz);
        // p_h = D(h)(n.h) = (1 - u1) / (pi a1 a2 cos^3(theta_h)), no exp().
        pdf = om / (PI * a.x * a.y * hz * hz * hz);
    }
    float vh = dot(vl, h);
    if (vh <= 0.0) return s;
    vec3 ll = 2.0 * vh * h - vl;
    if (ll.z <= 0.0) return s;
    vec3 wi = normalize(ll.x * t + ll.y * b + ll.z * n);
    // brdf_eval() tests the world direction, not ll: a grazing ll.z > 0 can round to <= 0 there
    // (seen on NVIDIA), and a sample whose pdf() is 0 breaks MIS. The same test on the same bits.
    if (to_local(wi, n, t, b).z <= 0.0) return s;
    s.wi = wi;
    vec3 F = lobe_fresnel(lobe, vh);
    if (lobe.distribution == DIST_DBRDF) {
        s.pdf = pdf / (4.0 * vh);
        s.weight = F;
    } else if (lobe.distribution == DIST_BECKMANN_SMITH) {
        s.pdf = pdf / (4.0 * vh);
        float G = beckmann_g1_walter(vl, a) * beckmann_g1_walter(ll, a);
        s.weight = F * (G * vh / (vl.z * h.z));
    } else if (lobe_is_ggx(lobe)) {
        float lv = ggx_lambda(vl, a);
        float l2 = ggx_lambda(ll, a);
        float G1v = 1.0 / (1.0 + lv);
        s.pdf = G1v * ggx_d(h, a) / (4.0 * vl.z);
        // weight = F G2 / G1(v)
        s.weight = lobe.distribution == DIST_GGX_SMITH_SEPARABLE ? F / (1.0 + l2) : F * ((1.0 + lv) / (1.0 + lv + l2));
    }
    s.valid = s.pdf > 0.0;
    if (!s.valid) s.weight = vec3(0.0);
    return s;
}

#endif
