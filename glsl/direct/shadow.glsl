// Shadow rays of direct lighting (direct.glsl): culling and resampling of the candidates
// (docs/techniques.md, "Shadow culling" and "Shadow resampling"), and the one ray per iteration
// of direct_lighting()'s loop.
//
// Why: the driver inlines every call, so each call site of trace_occluded() is a copy of the
// traversal for LLVM to compile (about a second of CPU each on a cold cache). direct_lighting()
// makes at most one ray per iteration of its loop (a light sample, one light a BRDF sample
// crosses, one pick of a resampling flush) and traces it at one place: one traversal copy.
#ifndef ILLUM_SHADOW_GLSL
#define ILLUM_SHADOW_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "scene/shading.glsl"
#include "trace/trace.glsl"

// Rays traced by this invocation (for the rays-per-second figures).
uint g_rays = 0u;

float max_abs(vec3 v) { return max(abs(v.x), max(abs(v.y), abs(v.z))); }

// Relative float32 error allowed at the end of a shadow segment: ~64 ulp of the larger end's
// coordinates, a quarter of offset_ray_origin's 256-ulp offset, so rounding of the light point
// (and of the tracer's hit on it) cannot put the emitter's surface inside the segment.
const float SHADOW_END_ULPS = 64.0 / 8388608.0;

// Whether the light point p + dist w (dist = INF: the direction w) is visible from the shading
// point. The segment runs from the offset origin to that point and stops short of it by 1e-4 of
// its length plus the end's rounding (pbrt-v4's ShadowEpsilon, with an absolute term for scenes
// far from the camera).
bool shadow_visible(Shading sh, vec3 w, float dist) {
    g_rays += 1u;
    vec3 dir = w;
    float tmax = INF;
    if (dist != INF) {
        vec3 x = sh.p + dist * w;
        vec3 seg = x - sh.origin;
        float len = length(seg);
        tmax = len * (1.0 - 1e-4) - SHADOW_END_ULPS * max(max_abs(x), max_abs(sh.origin));
        if (!(tmax > 0.0)) return true;   // nothing fits between them
        dir = seg / len;
    }
    return !trace_occluded(sh.origin, dir, 0.0, tmax, MASK_OCCLUDERS);
}

// The ray of this iteration of direct_lighting()'s loop (at most one): it adds c if visible, to
// the result or (g_ray_flush) to the running resampling flush's sum, which is added as one term
// (as before the loop, so the arithmetic and hence the image stay the same). A control variate
// sample (cv_s >= 0) is traced even where c is 0 and reports its answer. Scalars, not a queue:
// a private array costs lavapipe ~17% of a direct render's time in dynamic indexing.
bool g_ray_on = false;
vec3 g_ray_w;
float g_ray_dist;
vec3 g_ray_c;
float g_ray_cv;
bool g_ray_flush;

void shadow_ray(vec3 w, float dist, vec3 c, float cv_s, bool flush) {
    if (cv_s < 0.0 && !(max(c.r, max(c.g, c.b)) > 0.0)) return;   // nothing to add: no ray
    g_ray_on = true;
    g_ray_w = w;
    g_ray_dist = dist;
    g_ray_c = c;
    g_ray_cv = cv_s;
    g_ray_flush = flush;
}

// Fewer shadow rays (docs/techniques.md, "Shadow resampling", "Shadow culling"). Every candidate
// (a light or BRDF sample with its unshadowed, MIS-weighted contribution c_i, so that the plain
// estimate is sum_i V_i c_i) goes through shadow_candidate; with neither feature it is traced at
// once, as before.
//
// Culling (FEATURE_SHADOW_CULL, Russian roulette): with p_i = luminance(c_i) and threshold t, the
// candidate is kept with probability q_i = min(1, p_i / t) and then counts c_i / q_i:
// E[kept c_i V_i / q_i] = c_i V_i, so the estimate stays unbiased (a hard cutoff would not be).
//
// Resampling (FEATURE_SHADOW_RESAMPLE): the candidates of a group (below) are held back; of its M
// non-zero ones, K = ceil(pct M) picks are made by systematic resampling on p_i: with
// W = sum_i p_i, one u in [0, 1) and positions (k + u) W / K, k < K, along the running sum of the
// p_i, candidate i gets n_i picks, E[n_i] = K p_i / W exactly. It is traced once and counts
//     n_i (W / K) V_i c_i / p_i,
// so E[. | candidates] = sum_i (K p_i / W)(W / K) V_i c_i / p_i = sum_i V_i c_i: unbiased. At most
// K rays (fewer when a candidate is picked more than once); K >= M traces every candidate as is.
// Groups: the light samples of one looped light; all light samples that pick a light (tree, scan);
// the BRDF samples of one lobe (over every light they hit); and a group closes early when
// SHADOW_GROUP_MAX candidates wait. Any grouping fixed by the candidates keeps the estimate
// unbiased; groups only change its variance.
#define SHADOW_GROUP_MAX 16u
vec3 g_cand_w[SHADOW_GROUP_MAX];
vec3 g_cand_c[SHADOW_GROUP_MAX];
float g_cand_dist[SHADOW_GROUP_MAX];
float g_cand_p[SHADOW_GROUP_MAX];
uint g_cand_n = 0u;

// A flush of the waiting candidates (resampled) runs over several iterations, one ray each:
// shadow_flush_start() draws its random number, shadow_flush_next() makes the next ray (false
// when there is none left: the caller then adds g_fl_part and calls shadow_flush_done()).
bool g_fl_on = false;
bool g_fl_all;       // K >= M: every candidate as is
uint g_fl_m, g_fl_k, g_fl_i, g_fl_taken;
float g_fl_pos, g_fl_cum, g_fl_stride;
vec3 g_fl_part;
// A candidate that found the group full: held once the flush is done.
bool g_hold_on = false;
vec3 g_hold_w, g_hold_c;
float g_hold_dist, g_hold_p;

void shadow_flush_start(inout Rng rng) {
    uint m = g_cand_n;
    g_cand_n = 0u;
    if (m == 0u) return;
    g_fl_on = true;
    g_fl_m = m;
    g_fl_k = clamp(uint(ceil(frame.shadow_resample * float(m))), 1u, m);
    g_fl_all = g_fl_k >= m;
    g_fl_i = 0u;
    g_fl_taken = 0u;
    g_fl_part = vec3(0.0);
    if (g_fl_all) return;
    float wsum = 0.0;
    for (uint i = 0u; i < m; ++i) wsum += g_cand_p[i];
    g_fl_stride = wsum / float(g_fl_k);
    g_fl_pos = rng_next(rng) * g_fl_stride;
    g_fl_cum = 0.0;
}

bool shadow_flush_next() {
    if (g_fl_all) {
        if (g_fl_i == g_fl_m) return false;
        uint i = g_fl_i++;
        shadow_ray(g_cand_w[i], g_cand_dist[i], g_cand_c[i], -1.0, true);
        return true;
    }
    uint m = g_fl_m, k = g_fl_k;
    while (g_fl_i < m && g_fl_taken < k) {
        uint i = g_fl_i++;
        g_fl_cum += g_cand_p[i];
        uint picks = 0u;
        while (g_fl_taken + picks < k && g_fl_pos < g_fl_cum) {
            picks += 1u;
            g_fl_pos += g_fl_stride;
        }
        // The last candidate takes the picks that rounding of the running sum left over.
        if (i + 1u == m) picks = k - g_fl_taken;
        g_fl_taken += picks;
        if (picks > 0u) {
            shadow_ray(g_cand_w[i], g_cand_dist[i], g_cand_c[i] * (float(picks) * g_fl_stride / g_cand_p[i]), -1.0, true);
            return true;
        }
    }
    return false;
}

void shadow_hold(vec3 w, float dist, vec3 c, float p) {
    g_cand_w[g_cand_n] = w;
    g_cand_c[g_cand_n] = c;
    g_cand_dist[g_cand_n] = dist;
    g_cand_p[g_cand_n] = p;
    g_cand_n += 1u;
}

void shadow_flush_done() {
    g_fl_on = false;
    if (g_hold_on) shadow_hold(g_hold_w, g_hold_dist, g_hold_c, g_hold_p);
    g_hold_on = false;
}

// One candidate of contribution c along w (light point at dist): culled, held back for
// resampling (a full group starts a flush first), or this iteration's ray.
void shadow_candidate(vec3 w, float dist, vec3 c, inout Rng rng) {
    if (!(max(c.r, max(c.g, c.b)) > 0.0)) return;
    float p = luminance(c);
    if (has_feature(FEATURE_SHADOW_CULL) && p > 0.0 && p < frame.shadow_cull) {
        float q = p / frame.shadow_cull;
        if (rng_next(rng) >= q) return;
        c /= q;
        p /= q;
    }
    if (has_feature(FEATURE_SHADOW_RESAMPLE) && p > 0.0) {
        if (g_cand_n == SHADOW_GROUP_MAX) {
            shadow_flush_start(rng);
            g_hold_on = true;
            g_hold_w = w;
            g_hold_c = c;
            g_hold_dist = dist;
            g_hold_p = p;
        } else {
            shadow_hold(w, dist, c, p);
        }
        return;
    }
    shadow_ray(w, dist, c, -1.0, false);
}

// Closes a resampling group (nothing without FEATURE_SHADOW_RESAMPLE).
void shadow_group_end(inout Rng rng) {
    if (has_feature(FEATURE_SHADOW_RESAMPLE)) shadow_flush_start(rng);
}

#endif
