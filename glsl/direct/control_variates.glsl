// Control variates for the diffuse light samples of looped lights (docs/techniques.md, "Control
// variates"): the control radiance, its analytic unshadowed irradiance, and the correction that
// direct lighting adds once a light round's shadow rays have answered.
#ifndef ILLUM_CONTROL_VARIATES_GLSL
#define ILLUM_CONTROL_VARIATES_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "scene/shading.glsl"
#include "lights/light_sampling.glsl"
#include "lights/lights.glsl"
#include "lights/irradiance.glsl"

// Control variates (FEATURE_CONTROL_VARIATES): for a looped light, the N light
// samples' diffuse terms g_j = (rho/pi) Lc(w_j) max(0, n.w_j) / (pdf_j N), with Lc a control
// radiance (zero where eval_lobes gives zero: below n's or ng's horizon), have the analytic
// unshadowed sum G = (rho/pi) control_irradiance() = E[sum_j g_j], exactly when ns = ng (a shading
// normal that differs from ng zeroes samples that G counts) and the pdf is > 0 wherever
// Lc max(0, n.w) is not 0. Lc is constant except on a textured dome: its SH9 projection L_SH,
// G from the SH9 irradiance formula; its sampler then mixes in a uniform share (dome_sampling()).
// With V_j the shadow rays' answers:
//   avgvis (the course):  sum_j s_j V_j + a (G - sum_j g_j),  a = visible / traced:
//     biased (-Cov(a, sum_j g_j)), consistent; zero variance where fully lit and s_j = g_j.
//   loo (leave one out):  sum_j [s_j V_j + a_j (G/N - g_j)],  a_j = a without sample j:
//     a_j is independent of sample j, so E[a_j (G/N - g_j)] = E[a_j] * 0: unbiased.
// s_j is the sample's own contribution, with the light's true radiance: for an untextured light
// Lc is that radiance (s_j = g_j on the diffuse part); a textured light uses its mean radiance
// Lc = GpuLight.mean (condition 2: any constant control is exact, the mean is the one that cancels
// most of the variance). A sample is "traced" when max(0, n.w_j) / pdf_j > 0 (whatever Lc);
// a_j = 0 when no other sample was traced; other samples count in N and take a_j = a. Below, the
// sums are RGB in units of rho / pi: sv, so = sum of Lc(w_j) max(0, n.w_j) / (pdf_j N) over the
// visible / occluded traced samples (each an estimate of E), vis and tr the counts. The specular
// terms are left as they are.
// Kinds: rect, disk, sphere, triangle (Lambert's polygon formula) and sun (the cap formula with
// sin^2 sigma = sin^2 theta_s; delta sun: E_perp max(0, n.s), where g_j = G and the control adds
// nothing) and the dome (SH9; constant: G = pi L). Not covered: lights picked from the tree or
// the scan (one sample per pick; see docs/control-variates.md).
bool control_variate_applies(Shading sh, GpuLight l, uint technique, bool diffuse_mis) {
    if (light_self(l) || (l.kind == LIGHT_DOME && !has_feature(FEATURE_DOME))) return false;
    if (technique == TECHNIQUE_BRDF || (technique == TECHNIQUE_MIS && diffuse_mis)) return false;
    return max(sh.albedo.r, max(sh.albedo.g, sh.albedo.b)) > 0.0;
}

// The control radiance Lc toward w (see above): the radiance light_radiance() gives everywhere on
// an untextured light, the host's exact mean of it on a textured one, L_SH(w) on a textured dome.
vec3 control_radiance(GpuLight l, GpuDomeSampling dome, vec3 w) {
    if (l.kind == LIGHT_SUN) return light_radiance(l, vec2(0.0), l.p1.x <= 0.0);
    if (light_is(l, LIGHT_DOME) && dome.width > 0u) return sh9_eval(dome.sh, w);
    return l.texture == NONE ? l.radiance : l.mean;
}

// E, the integral of Lc max(0, n.w) over the light as its sampler covers it.
vec3 control_irradiance(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 n) {
    if (light_is(l, LIGHT_DOME))
        return dome.width > 0u ? sh9_irradiance(dome.sh, n) : PI * l.radiance;
    vec3 lc = control_radiance(l, dome, vec3(0.0));
    if (l.kind == LIGHT_SUN && l.p1.x > 0.0) {
        float om = l.p1.x;
        return lc * irradiance_cap(dot(n, l.p0.xyz), om * (2.0 - om), 1.0 - om);
    }
    return lc * light_irradiance(l, p, n);
}

vec3 control_variate(Shading sh, GpuLight l, GpuDomeSampling dome, float n, vec3 sv, vec3 so, float vis, float tr) {
    vec3 g = control_irradiance(l, dome, sh.p, sh.n);   // the expectation of sv + so unshadowed
    float a = tr > 0.0 ? vis / tr : 0.0;
    vec3 k;
    if (frame.control_variates == CONTROL_VARIATES_LOO) {
        // sum_j a_j (G/N - g_j): untraced samples a G/N; visible ones (vis-1)/(tr-1) (G/N - g_j);
        // occluded ones vis/(tr-1) (G/N - g_j).
        k = (n - tr) * a * g / n;
        if (tr > 1.0) {
            k += (vis - 1.0) / (tr - 1.0) * (vis * g / n - sv);
            k += vis / (tr - 1.0) * ((tr - vis) * g / n - so);
        }
    } else {
        k = a * (g - sv - so);
    }
    return sh.albedo * k * INV_PI;
}

#endif
