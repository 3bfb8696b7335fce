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
// the result or (flush) to the running resampling flush's sum, which is added as one term (as
// before the loop, so the arithmetic and hence the image stay the same). A control variate sample
// (cv >= 0) is traced even where c is 0 and reports its answer. Scalars, not a queue: a private
// array costs lavapipe ~17% of a direct render's time in dynamic indexing.
struct ShadowRay {
    bool on;
    vec3 w;
    float dist;
    vec3 c;
    float cv;
    bool flush;
};

void shadow_ray(inout ShadowRay r, vec3 w, float dist, vec3 c, float cv_s, bool flush) {
    if (cv_s < 0.0 && !(max(c.r, max(c.g, c.b)) > 0.0)) return;   // nothing to add: no ray
    r.on = true;
    r.w = w;
    r.dist = dist;
    r.c = c;
    r.cv = cv_s;
    r.flush = flush;
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

// A candidate: direction, distance of the light point (INF: none), contribution c and its
// luminance p (set by shadow_candidate()).
struct ShadowCandidate {
    vec3 w;
    float dist;
    vec3 c;
    float p;
};

// No candidate (c = 0: shadow_candidate() drops it).
ShadowCandidate no_shadow_candidate() { return ShadowCandidate(vec3(0.0), 0.0, vec3(0.0), 0.0); }

// A resampling group: how many candidates wait, the flush of them under way, and a candidate
// that found the group full, held until the flush is done. The waiting candidates themselves are
// an array of direct_lighting()'s, which alone writes it: GLSL copies an array passed inout in
// and out at every call, and with the array inside this struct a resampled render took about 7%
// longer on lavapipe (read-only arrays cost nothing measurable). A flush runs over several
// iterations, one ray each: shadow_flush_start() draws its random number, shadow_flush_next()
// makes the next ray (false when there is none left: the caller then adds `part` and calls
// shadow_flush_done()).
struct ShadowGroup {
    uint n;              // waiting candidates
    bool flushing;
    bool all;            // K >= M: every candidate as is
    uint m, k, i, taken;
    float pos, cum, stride;
    vec3 part;           // the flush's visible sum so far
    bool held;
    ShadowCandidate hold;
};

ShadowGroup shadow_group() {
    ShadowGroup g;
    g.n = 0u;
    g.flushing = false;
    g.held = false;
    return g;
}

void shadow_flush_start(inout ShadowGroup g, ShadowCandidate cands[SHADOW_GROUP_MAX], inout Rng rng) {
    uint m = g.n;
    g.n = 0u;
    if (m == 0u) return;
    g.flushing = true;
    g.m = m;
    g.k = clamp(ceil_uint(frame.shadow_resample * float(m)), 1u, m);
    g.all = g.k >= m;
    g.i = 0u;
    g.taken = 0u;
    g.part = vec3(0.0);
    if (g.all) return;
    float wsum = 0.0;
    for (uint i = 0u; i < m; ++i) wsum += cands[i].p;
    g.stride = wsum / float(g.k);
    g.pos = rng_next(rng) * g.stride;
    g.cum = 0.0;
}

bool shadow_flush_next(inout ShadowGroup g, ShadowCandidate cands[SHADOW_GROUP_MAX], inout ShadowRay r) {
    if (g.all) {
        if (g.i == g.m) return false;
        uint i = g.i++;
        shadow_ray(r, cands[i].w, cands[i].dist, cands[i].c, -1.0, true);
        return true;
    }
    uint m = g.m, k = g.k;
    while (g.i < m && g.taken < k) {
        uint i = g.i++;
        g.cum += cands[i].p;
        uint picks = 0u;
        while (g.taken + picks < k && g.pos < g.cum) {
            picks += 1u;
            g.pos += g.stride;
        }
        // The last candidate takes the picks that rounding of the running sum left over.
        if (i + 1u == m) picks = k - g.taken;
        g.taken += picks;
        if (picks > 0u) {
            shadow_ray(r, cands[i].w, cands[i].dist, cands[i].c * (float(picks) * g.stride / cands[i].p), -1.0, true);
            return true;
        }
    }
    return false;
}

// Ends a flush; true when the held candidate (g.hold) now joins the group: the caller appends it.
bool shadow_flush_done(inout ShadowGroup g) {
    bool held = g.held;
    g.flushing = false;
    g.held = false;
    return held;
}

// What became of a candidate (shadow_candidate()).
#define SHADOW_DONE 0u   // dropped, culled, or this iteration's ray
#define SHADOW_JOIN 1u   // it waits in the group: the caller appends it
#define SHADOW_FULL 2u   // the group is full: the caller starts its flush and holds the candidate

// One candidate x: culled (c and p scaled when kept), held back for resampling, or this
// iteration's ray.
uint shadow_candidate(inout ShadowRay r, inout ShadowCandidate x, uint waiting, inout Rng rng) {
    vec3 c = x.c;
    if (!(max(c.r, max(c.g, c.b)) > 0.0)) return SHADOW_DONE;
    float p = luminance(c);
    if (has_feature(FEATURE_SHADOW_CULL) && p > 0.0 && p < frame.shadow_cull) {
        float q = p / frame.shadow_cull;
        if (rng_next(rng) >= q) return SHADOW_DONE;
        c /= q;
        p /= q;
    }
    if (has_feature(FEATURE_SHADOW_RESAMPLE) && p > 0.0) {
        x.c = c;
        x.p = p;
        return waiting == SHADOW_GROUP_MAX ? SHADOW_FULL : SHADOW_JOIN;
    }
    shadow_ray(r, x.w, x.dist, c, -1.0, false);
    return SHADOW_DONE;
}

// Closes a resampling group (nothing without FEATURE_SHADOW_RESAMPLE).
void shadow_group_end(inout ShadowGroup g, ShadowCandidate cands[SHADOW_GROUP_MAX], inout Rng rng) {
    if (has_feature(FEATURE_SHADOW_RESAMPLE)) shadow_flush_start(g, cands, rng);
}

#endif
