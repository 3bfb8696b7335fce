// Multiple importance sampling weights: the power heuristic (beta = 2) in an overflow-safe ratio
// form and the course's per-(lobe, light) specular terms (docs/techniques.md,
// "Multiple importance sampling").
//
// Conventions:
// * Techniques: L = light sampling of one light (N_L samples, solid-angle pdf p_L), B = BRDF
//   sampling of one lobe (N_B samples, pdf p_B). N_B is the lobe's full BRDF sample count (every
//   sample could have hit the light, including those that missed or were invalid); N_L the light's
//   own count. When lights are picked stochastically, pass N_L * P(light) as N_L.
// * A technique that cannot produce the direction has pdf 0: a light sample's direction on a delta
//   lobe (brdf_eval() returns pdf 0 for it), a BRDF direction that misses the light (light_pdf() 0).
//   The other technique then gets weight 1.
// * Delta lights (sun of zero size, LightSample.delta) and delta lobes (BrdfSample.delta) are not
//   MIS-combined: a delta light's sample has weight 1 (contribution f cos * E_perp * V / N_L), and a
//   delta lobe's sample has weight 1 (pass p_L = 0).
// * All functions return finite values for any non-negative input, including 0, denormals, huge
//   values and +inf (ratios are formed before squaring; (n p)^2 is never computed).
#ifndef ILLUM_MIS_GLSL
#define ILLUM_MIS_GLSL

#include "shared/common.glsl"

// 1 / (1 + r^2) for r >= 0, including r = +inf (-> 0).
float mis_inv_one_plus_sq(float r) {
    return r <= 1.0 ? 1.0 / (1.0 + r * r) : (1.0 / r) * (1.0 / r) / (1.0 + (1.0 / r) * (1.0 / r));
}

// r / (1 + r^2) for r >= 0, including r = +inf (-> 0); at most 1/2.
float mis_r_over_one_plus_sq(float r) {
    if (r <= 1.0) return r / (1.0 + r * r);
    float q = 1.0 / r;
    return q / (1.0 + q * q);
}

// x / y within Vulkan's precision guarantee, which covers divisors in [2^-126, 2^126] only: beyond,
// a driver may compute x * (1 / y) with 1 / y flushed to 0 (NVIDIA does), so a huge y is scaled
// down first (by a power of two: exact).
float mis_div(float x, float y) {
    return y > 8.507059e37 ? (0.25 * x) / (0.25 * y) : x / y;
}

// r = n_b p_b / (n_a p_a) as (n_b / n_a) (p_b / p_a), so that (n p) is never formed: sample counts
// are moderate, and when p_b / p_a leaves the float range, 0 or +inf is the right limit for every
// weight below. 0 when n_b p_b == 0; +inf when n_a p_a == 0 < n_b p_b; n_b / n_a for two infinite
// pdfs.
float mis_ratio(float n_a, float p_a, float n_b, float p_b) {
    if (!(n_b > 0.0) || !(p_b > 0.0)) return 0.0;
    if (!(n_a > 0.0) || !(p_a > 0.0)) return INF;
    // Two infinite pdfs (two deltas) compare by their counts.
    return (n_b / n_a) * (p_a == INF && p_b == INF ? 1.0 : mis_div(p_b, p_a));
}

// Power-heuristic weight of technique a at a point x that both techniques may produce:
// (n_a p_a)^2 / ((n_a p_a)^2 + (n_b p_b)^2); 0 when p_a == 0, 1 when p_b == 0.
float mis_power(float n_a, float p_a, float n_b, float p_b) {
    if (!(n_a > 0.0) || !(p_a > 0.0)) return 0.0;
    return mis_inv_one_plus_sq(mis_ratio(n_a, p_a, n_b, p_b));
}

// Weights of a light sample and of a BRDF sample under the power heuristic (they sum to 1 where
// both pdfs are > 0).
float mis_light_weight(float n_l, float p_l, float n_b, float p_b) { return mis_power(n_l, p_l, n_b, p_b); }
float mis_brdf_weight(float n_l, float p_l, float n_b, float p_b) { return mis_power(n_b, p_b, n_l, p_l); }

// The course's per-(lobe, light) specular terms for the D-BRDF, whose f cos = F p_B
// (docs/techniques.md, "The D-BRDF"): with r = N_B p_B / (N_L p_L),
//   light sample:            C_L = (1/N_L) F L_e (N_L^2 p_L p_B) / ((N_L p_L)^2 + (N_B p_B)^2)
//                                = F L_e * (1/N_B) r / (1 + r^2)        <= F L_e / (2 N_B)
//   BRDF sample on the light: C_B = (1/N_B) F L_e (N_B p_B)^2 / ((N_L p_L)^2 + (N_B p_B)^2)
//                                = F L_e * (1/N_B) / (1 + 1/r^2)        <= F L_e / N_B
// These return the factors multiplying F L_e V (so the pdfs enter only as a ratio and the terms are
// bounded). With N_B == 0 (no BRDF samples) the light-sample term is the plain estimator
// F L_e p_B / (N_L p_L) (unbounded; clamped to the float range); with p_L == 0 (a BRDF direction the light sampler cannot produce, or a
// delta lobe) the BRDF term is F L_e / N_B.
float mis_dbrdf_light_factor(float n_l, float p_l, float n_b, float p_b) {
    if (!(n_l > 0.0) || !(p_l > 0.0) || !(p_b > 0.0)) return 0.0;
    if (!(n_b > 0.0)) return min(mis_div(p_b, p_l) / n_l, 3.4e38);
    return mis_r_over_one_plus_sq(mis_ratio(n_l, p_l, n_b, p_b)) / n_b;
}

float mis_dbrdf_brdf_factor(float n_l, float p_l, float n_b, float p_b) {
    if (!(n_b > 0.0) || !(p_b > 0.0)) return 0.0;
    // 1 / (1 + 1/r^2) with 1/r = N_L p_L / (N_B p_B).
    return mis_inv_one_plus_sq(mis_ratio(n_b, p_b, n_l, p_l)) / n_b;
}

#endif
