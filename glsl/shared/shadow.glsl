// Shadow rays of direct lighting (direct.glsl): culling and resampling of the candidates
// (TECHNIQUES.md 4.2, 4.3), and the queue every shadow ray of a shading point is traced from.
//
// Why a queue: the driver inlines every call, so each call site of trace_occluded() is a copy of
// the traversal for LLVM to compile (about a second of CPU each on a cold cache). The candidates
// of one sample (light sample, BRDF sample, resampling flush) are pushed here and traced by
// shadow_trace(), which direct_lighting() calls once: one traversal copy per direct_lighting().
// Needs the Shading struct (direct.glsl).
#ifndef ILLUM_SHADOW_GLSL
#define ILLUM_SHADOW_GLSL

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

// The queue. An entry adds c if its ray is visible; entries pushed with `join` add to the
// previous entry's sum, which is added to the result as one term (a resampling flush's picks,
// summed as before the queue, so the arithmetic and hence the image stay the same). A control
// variate sample (cv_s >= 0) is traced even where c is 0 and reports its answer (shadow_trace).
// Capacity: one sample pushes at most DIRECT_MAX_CROSSED = 16 candidates or one resampling flush
// of at most SHADOW_GROUP_MAX = 16 picks, and the group it ends at most one more flush: 32.
#define SHADOW_QUEUE_MAX 32u
vec3 g_sq_w[SHADOW_QUEUE_MAX];
float g_sq_dist[SHADOW_QUEUE_MAX];
vec3 g_sq_c[SHADOW_QUEUE_MAX];
float g_sq_cv[SHADOW_QUEUE_MAX];
bool g_sq_join[SHADOW_QUEUE_MAX];
uint g_sq_n = 0u;

void shadow_push(vec3 w, float dist, vec3 c, float cv_s, bool join) {
    if (cv_s < 0.0 && !(max(c.r, max(c.g, c.b)) > 0.0)) return;   // nothing to add: no ray
    if (g_sq_n == SHADOW_QUEUE_MAX) return;   // not reached (see the capacity above)
    g_sq_w[g_sq_n] = w;
    g_sq_dist[g_sq_n] = dist;
    g_sq_c[g_sq_n] = c;
    g_sq_cv[g_sq_n] = cv_s;
    g_sq_join[g_sq_n] = join;
    g_sq_n += 1u;
}

// Traces the queue and empties it: adds the visible entries' c to `result`, and for control
// variate samples their s to sv (visible) or so (occluded), and 1 to vis where visible.
void shadow_trace(Shading sh, inout vec3 result, inout float sv, inout float so, inout float vis) {
    uint n = g_sq_n;
    g_sq_n = 0u;
    vec3 part = vec3(0.0);
    for (uint i = 0u; i < n; ++i) {
        bool visible = shadow_visible(sh, g_sq_w[i], g_sq_dist[i]);
        float s = g_sq_cv[i];
        if (s >= 0.0) {
            if (visible) {
                vis += 1.0;
                sv += s;
            } else {
                so += s;
            }
        }
        if (visible) part += g_sq_c[i];
        if (i + 1u == n || !g_sq_join[i + 1u]) {
            result += part;
            part = vec3(0.0);
        }
    }
}

// Fewer shadow rays (TECHNIQUES.md 4.2, 4.3). Every candidate (a light or BRDF sample with its
// unshadowed, MIS-weighted contribution c_i, so that the plain estimate is sum_i V_i c_i) goes
// through shadow_candidate; with neither feature it is queued at once, as before.
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

// Queues shadow rays for the waiting candidates (resampled), as one term of the result.
void shadow_flush(inout Rng rng) {
    uint m = g_cand_n;
    g_cand_n = 0u;
    if (m == 0u) return;
    uint k = clamp(uint(ceil(frame.shadow_resample * float(m))), 1u, m);
    uint first = g_sq_n;   // the entries from here on are one term
    if (k >= m) {
        for (uint i = 0u; i < m; ++i) shadow_push(g_cand_w[i], g_cand_dist[i], g_cand_c[i], -1.0, g_sq_n > first);
        return;
    }
    float wsum = 0.0;
    for (uint i = 0u; i < m; ++i) wsum += g_cand_p[i];
    float stride = wsum / float(k);
    float pos = rng_next(rng) * stride;
    float cum = 0.0;
    uint taken = 0u;
    for (uint i = 0u; i < m && taken < k; ++i) {
        cum += g_cand_p[i];
        uint picks = 0u;
        while (taken + picks < k && pos < cum) {
            picks += 1u;
            pos += stride;
        }
        // The last candidate takes the picks that rounding of the running sum left over.
        if (i + 1u == m) picks = k - taken;
        taken += picks;
        if (picks > 0u)
            shadow_push(g_cand_w[i], g_cand_dist[i], g_cand_c[i] * (float(picks) * stride / g_cand_p[i]), -1.0, g_sq_n > first);
    }
}

// One candidate of contribution c along w (light point at dist): culled, held back for
// resampling, or queued now.
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
        if (g_cand_n == SHADOW_GROUP_MAX) shadow_flush(rng);
        g_cand_w[g_cand_n] = w;
        g_cand_c[g_cand_n] = c;
        g_cand_dist[g_cand_n] = dist;
        g_cand_p[g_cand_n] = p;
        g_cand_n += 1u;
        return;
    }
    shadow_push(w, dist, c, -1.0, false);
}

// Closes a resampling group (nothing without FEATURE_SHADOW_RESAMPLE).
void shadow_group_end(inout Rng rng) {
    if (has_feature(FEATURE_SHADOW_RESAMPLE)) shadow_flush(rng);
}

#endif
