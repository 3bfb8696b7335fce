// The direct-lighting integrator of "Physically Based Lighting at Pixar" (Hery & Villemin 2013),
// docs/techniques.md, "The direct-lighting estimator": per light and per lobe, light samples and
// BRDF samples combined by multiple importance sampling (power heuristic), BRDF samples pruned to
// those that hit a light, and shadow rays traced only for the samples whose MIS-weighted
// contribution is not zero.
//
// Conventions:
// * Light sample counts follow the course: a light takes N_L = ceil(share x N_max) samples, with
//   `share` its solid angle over the hemisphere's 2 pi (1 for the dome), N_L in [floor, N_max]
//   (floor 1 unless the allocation pilot raised it, src/render/allocation/); a
//   textured dome takes dome_samples N_max (2 by default; measured at equal time, light_count_for). With the light tree
//   (LIGHT_SELECT_TREE: above DIRECT_LOOP_LIGHTS lights, or where the allocation pilot chose it),
//   the infinite lights are still looped over that way and N_max samples are spread over the finite lights, each picking a light by descending the
//   light tree (select_light(), lights/light_select.glsl): light l then has the expected count
//   n_l = N_max P(l | p, n) in every MIS weight, light_pmf() replaying P from l's trail for BRDF
//   samples. LIGHT_SELECT_SCAN keeps the former pick (a linear CDF scan over all lights, infinite
//   ones included) for comparison.
// * BRDF samples: N_B per specular lobe, drawn once and shared by all lights (N_B counts every
//   sample, also those that miss all lights or fall below the horizon). The diffuse lobe takes N_B
//   cosine samples under TECHNIQUE_BRDF, or under MIS with INTEGRATOR_DIFFUSE_MIS; otherwise light
//   samples only, as in the course.
// * Lights are opaque objects (Mitsuba 3, pbrt-v4): shadow rays see geometry and the light
//   surfaces that cast shadows (MASK_OCCLUDERS), so a BRDF sample counts only the first light it
//   meets, and a light hides what is behind it, exactly like emissive geometry. A light with
//   "shadows": false is transparent: BRDF samples count it and every light behind it. Both
//   techniques use the same shadow rays, so the MIS weights sum to one.
// * A shadow ray runs from the offset origin to the light point itself (not along the shading
//   point's direction for the shading point's distance), ending short of it by a margin that
//   scales like the float error of both ends, so it never reaches the emitter's own surface.
// * A shading point on an emitter's own surface (emissive geometry lit by itself) sees that
//   emitter as a sphere from inside (LIGHT_FLAG_SELF) or, for a planar emitter, not at all.
// * A BRDF sample finds the finite lights it crosses by traversing the light BVH (a tree over their
//   bounds, src/gpu_scene/lights.rs); the infinite lights (dome, sun) are always tested. At most
//   DIRECT_MAX_CROSSED lights along one direction are counted.
#ifndef ILLUM_DIRECT_GLSL
#define ILLUM_DIRECT_GLSL

#extension GL_EXT_control_flow_attributes : require
#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "scene/shading.glsl"
#include "scene/microfacet.glsl"
#include "lights/light_sampling.glsl"
#include "lights/lights.glsl"
#include "lights/light_bvh.glsl"
#include "lights/light_tree.glsl"
#include "lights/light_select.glsl"
#include "direct/mis.glsl"
#include "direct/shadow.glsl"
#include "direct/control_variates.glsl"
#include "shared/profile.glsl"

uint light_count_for(GpuLight l, vec3 p, uint n_max) {
    // A textured dome (a sky with its sun) varies far more over its directions than any other
    // light: dome_samples N_max samples, 2 N_max by default since its groups are nets stratified
    // across camera samples (docs/performance-sampling.md, "A group's samples from one dimension
    // pair"; 8 N_max before, "The dome's sample count again"). The pilot moves it.
    if (l.kind == LIGHT_DOME && l.texture != NONE) return frame.dome_samples * n_max;
    // The floor (src/render/allocation/) lifts small lights above their share when a pilot
    // measured that it pays: the share alone gives every small light one sample.
    return clamp(ceil_uint(light_share(l, p) * float(n_max)), clamp(frame.light_floor, 1u, n_max), n_max);
}

// Light i as seen from the shading point: flagged LIGHT_FLAG_SELF when p lies on its surface.
GpuLight light_seen_from(Shading sh, uint i) {
    GpuLight l = get_light(i);
    if (i == sh.self_light) l.flags |= LIGHT_FLAG_SELF;
    return l;
}

// Whether light l can light the shading point at all (a planar emitter cannot light itself).
bool light_reaches(GpuLight l) {
    return !light_self(l) || l.kind == LIGHT_SPHERE;
}

// Sum of the lobes' f cos for direction l (light samples), with each specular lobe's MIS weight
// against its own BRDF samples. `n_l_pdf` is n_l p_l of the light technique (0 for a delta light).
vec3 eval_lobes(Shading sh, GpuMaterial m, vec3 l, float n_l_pdf, uint technique, bool diffuse_mis, uint n_b) {
    float cs = dot(sh.n, l);
    if (cs <= 0.0 || dot(sh.ng, l) <= 0.0) return vec3(0.0);
    vec3 sum = vec3(0.0);
    // Diffuse: light samples alone, or MIS with n_b cosine samples.
    float wd = 1.0;
    if (technique == TECHNIQUE_MIS && diffuse_mis && n_l_pdf > 0.0)
        wd = mis_power(1.0, n_l_pdf, float(n_b), cs * INV_PI);
    sum += sh.albedo * (cs * INV_PI) * wd;
    [[dont_unroll]] for (uint k = 0u; k < min(m.lobe_count, 2u); ++k) {
        BrdfEval e = brdf_eval(m.lobes[k], sh.n, sh.t, sh.b, sh.v, l);
        float w = 1.0;
        if (technique == TECHNIQUE_MIS && n_l_pdf > 0.0) w = mis_power(1.0, n_l_pdf, float(n_b), e.pdf);
        sum += e.f_cos * w;
    }
    return sum;
}

// A group's samples other than 2^m on a camera stream (those take rng_sobol2_group, group_u),
// and every group on PCG streams (the radiosity cache's update paths): sample i of a group of
// n, u jittered within cell i of an nx x ny
// grid over [0, 1)^2. The cells partition the square and each sample is uniform in its own, so
// the group's average stays unbiased, and so do MIS weights (they use one sample's density),
// resampling and culling (unbiased for any candidates given). Not under leave-one-out control
// variates, which need the samples independent. Jittered sampling (Cook 1986). `rows` (a textured dome's marginal-
// conditional warp): x in n strata, whose cumulative row mass this stratifies exactly, and y in
// stratum (i + shift) mod n, `shift` uniform per group: a Latin hypercube whose random cyclic
// order keeps each sample uniform over its x stratum (a fixed order would be biased). Measured on
// scenes/bench/dome.json, relMSE at 64 spp: 2.3e-3 for a 2 x 2 grid, 1.9e-3 for rows alone,
// 8.5e-4 with 8 samples and the shifted columns (9.8e-4 without). Otherwise nx * ny = n,
// nx >= ny, as square as n's divisors allow: area lights, cones, lobes and a constant dome's
// sphere warp both dimensions alike.
vec2 stratify(vec2 u, uint i, uint n, uint shift, bool rows) {
    if (n <= 1u) return u;
    uvec2 cell = uvec2(i, (i + shift) % n), cells = uvec2(n);
    if (!rows) {
        uint ny = floor_uint(sqrt(float(n) + 0.5));
        while (n % ny != 0u) ny -= 1u;
        cells = uvec2(n / ny, ny);
        cell = uvec2(i % cells.x, i / cells.x);
    }
    // (k + u) / n can round up to 1 in float: the samplers expect u < 1.
    return min((vec2(cell) + u) / vec2(cells), vec2(0.99999994));
}

// Whether light l's samples take stratify()'s rows: a dome with sampling tables (a textured one).
bool stratify_rows(GpuLight l, GpuDomeSampling dome) { return l.kind == LIGHT_DOME && dome.width > 0u; }

// What every sample of one direct_lighting() call shares: the settings, the dome's tables, the
// light selection and the groups' layout. Samples come in groups, in this order: the light
// samples of each round (a looped light, or one pick from the tree or the scan), a closing group
// (the picks' resampling, with FEATURE_SHADOW_RESAMPLE), then the BRDF samples of each lobe (the
// specular ones, then the diffuse lobe where it is BRDF-sampled).
struct DirectPlan {
    uint technique;
    uint n_max;            // most light samples per light
    uint n_b;              // BRDF samples per lobe
    bool diffuse_mis;
    GpuDomeSampling dome;
    LightSelection sel;
    uint looped;           // light rounds that loop over a light; each later one picks a light
    uint rounds;           // light rounds
    uint lobes;            // specular lobes (BRDF group `lobes` is the diffuse lobe)
    bool diffuse_brdf;     // whether the diffuse lobe takes BRDF samples
    uint first_brdf;       // the first lobe's group (after the closing group, if any)
    uint groups;
    uint pick_dim;         // N_max = 2^m picks on a camera stream: the two pairs they share
};

DirectPlan direct_plan(Shading sh, GpuMaterial m) {
    DirectPlan plan;
    plan.technique = frame.technique;
    plan.n_max = frame.light_samples;
    plan.n_b = frame.brdf_samples;
    plan.diffuse_mis = (frame.integrator_flags & INTEGRATOR_DIFFUSE_MIS) != 0u;
    plan.dome = dome_sampling();
    plan.sel = light_selection(sh.p, sh.n);
    plan.looped = looped_lights(plan.sel);
    plan.rounds = plan.technique == TECHNIQUE_BRDF ? 0u : plan.looped + (lights_picked(plan.sel) ? plan.n_max : 0u);
    plan.lobes = min(m.lobe_count, 2u);
    plan.diffuse_brdf = plan.technique == TECHNIQUE_BRDF || plan.diffuse_mis;
    // Only groups with something to do: the closing group where picks may wait for resampling,
    // the diffuse lobe's where it takes BRDF samples (each group costs every lane at least one
    // pass through direct_lighting()'s loop).
    bool closing = has_feature(FEATURE_SHADOW_RESAMPLE) && plan.technique != TECHNIQUE_BRDF;
    plan.first_brdf = plan.rounds + (closing ? 1u : 0u);
    plan.groups = plan.first_brdf + (plan.technique == TECHNIQUE_LIGHT ? 0u : plan.lobes + (plan.diffuse_brdf ? 1u : 0u));
    plan.pick_dim = NONE;
    return plan;
}

// The picks' pairs: with N_max = 2^m > 1 picks on a camera stream, pick r takes point r of the
// camera sample's block of one pair for its selection (x) and of another for its light sample, as
// a group's samples do (group_u): the picks are stratified over the lights' importance (the
// tree's top levels, light_tree_walk) within a shading point and across the pixel's samples.
void direct_plan_picks(inout DirectPlan plan, inout Rng rng) {
    uint n = plan.n_max;
    if (plan.rounds > plan.looped && n > 1u && (n & (n - 1u)) == 0u && rng.dim != RNG_PCG) {
        plan.pick_dim = rng.dim;
        rng.dim += 2u;
    }
}

// A BRDF sample's direction, shared by every light it crosses.
struct BrdfDir {
    vec3 wi, weight;
    float pdf;
    bool delta;
};

// The group being worked through and where it stands.
struct DirectGroup {
    uint g;              // its index
    bool opened;         // whether direct_open() has run for it
    uint j, count;       // the next sample, and its samples (0: none)
    uint shift;          // a textured dome's column order (stratify)
    uint dim;            // a 2^m group on a camera stream: the pair its samples share (group_u)
    bool close;          // whether it ends with shadow_group_end
    bool closed;         // whether its closing flush has started
    GpuLight l;          // a light round's light
    float n_l;           // its expected samples per shading point
    bool cv;             // with a control variate, whose sums (control_variate) follow
    vec3 cv_sv, cv_so;
    float cv_vis, cv_tr;
    BrdfDir bdir;        // a BRDF sample's direction; of the lights it crosses, q are done
    uint crossed, q;
};

// A light round: its light, looped over or picked (select_light()), its sample count, control
// variate and, for a textured dome, its column order.
void direct_open_light_round(DirectPlan plan, Shading sh, inout DirectGroup grp, inout Rng rng) {
    uint li;
    bool picked = grp.g >= plan.looped;
    bool reached = true;
    float u = picked && plan.pick_dim != NONE ? rng_sobol2_group(rng, plan.pick_dim, grp.g - plan.looped, plan.n_max).x : -1.0;
    if (picked) reached = select_light(plan.sel, sh.p, sh.n, float(plan.n_max), u, rng, li, grp.n_l);
    else li = looped_light(plan.sel, grp.g);
    if (reached) {
        grp.l = light_seen_from(sh, li);
        reached = light_reaches(grp.l);
    }
    if (!reached) return;
    grp.count = picked ? 1u : light_count_for(grp.l, sh.p, plan.n_max);
    if (!picked) grp.n_l = float(grp.count);
    grp.close = !picked;
    grp.cv = has_feature(FEATURE_CONTROL_VARIATES) && !picked && control_variate_applies(sh, grp.l, plan.technique, plan.diffuse_mis);
}

// Opens group grp.g: a light round, the closing group, or a lobe's BRDF samples.
void direct_open(DirectPlan plan, Shading sh, inout DirectGroup grp, inout Rng rng) {
    grp.opened = true;
    grp.j = 0u;
    grp.count = 0u;
    grp.shift = 0u;
    grp.dim = NONE;
    grp.close = false;
    grp.cv = false;
    grp.cv_sv = grp.cv_so = vec3(0.0);
    grp.cv_vis = grp.cv_tr = 0.0;
    grp.closed = false;
    grp.crossed = grp.q = 0u;
    if (grp.g < plan.rounds) {
        direct_open_light_round(plan, sh, grp, rng);
    } else if (grp.g < plan.first_brdf) {
        grp.close = true;
    } else {
        bool diffuse = grp.g - plan.first_brdf == plan.lobes;
        if (!diffuse || (plan.diffuse_brdf && max(sh.albedo.r, max(sh.albedo.g, sh.albedo.b)) > 0.0)) {
            grp.count = plan.n_b;
            grp.close = true;
        }
    }
    // On a camera stream a group of 2^m samples shares one dimension pair (group_u). Other
    // counts keep a pair per sample: a block's first 3 of 4 points leave out a quarter that
    // changes from block to block, which undoes the stratification across samples. Leave-one-out
    // control variates need the samples independent, one pair each.
    if (grp.count > 1u && (grp.count & (grp.count - 1u)) == 0u && !grp.cv && rng.dim != RNG_PCG) {
        grp.dim = rng.dim;
        rng.dim += 1u;
    }
    // Otherwise a textured dome's column order (stratify), drawn once per group.
    if (grp.dim == NONE && !grp.cv && grp.count > 1u && grp.g < plan.rounds && stratify_rows(grp.l, plan.dome))
        grp.shift = min(floor_uint(rng_next(rng) * float(grp.count)), grp.count - 1u);
}

// The 2D sample of the group's sample j: for 2^m samples on a camera stream, point j of the
// group's block of its dimension pair (rng_sobol2_group: stratified within the group and across
// the pixel's samples at once), else an independent draw jittered into cell j (stratify). Measured against
// stratify() on camera streams (its own pair per sample; a textured dome's rows with a random
// column order, which the across-sample stratification did not survive): docs/performance-sampling.md,
// "A group's samples from one dimension pair".
vec2 group_u(DirectGroup grp, inout Rng rng, uint j, bool rows) {
    if (grp.dim != NONE) return rng_sobol2_group(rng, grp.dim, j, grp.count);
    return stratify(rng_next2(rng), j, grp.count, grp.shift, rows);
}

// What the loop does next in a group: the next light the BRDF sample crosses, else the next
// sample, else the closing flush, else the group's end.
#define DIRECT_CROSS 0u
#define DIRECT_SAMPLE 1u
#define DIRECT_CLOSE 2u
#define DIRECT_END 3u

uint direct_step(DirectGroup grp) {
    if (grp.q < grp.crossed) return DIRECT_CROSS;
    if (grp.j < grp.count) return DIRECT_SAMPLE;
    return grp.closed ? DIRECT_END : DIRECT_CLOSE;
}

// Light sample j - 1 of the group's light: its candidate, or with a control variate its ray and
// g_j (in cv_tr and the ray's s).
ShadowCandidate direct_light_sample(DirectPlan plan, Shading sh, GpuMaterial m, inout DirectGroup grp,
                                    inout ShadowRay ray, inout Rng rng) {
    GpuLight l = grp.l;
    float n_l = grp.n_l;
    bool pick = grp.g >= plan.looped && plan.pick_dim != NONE;
    vec2 u = grp.cv ? rng_next2(rng)
           : pick ? rng_sobol2_group(rng, plan.pick_dim + 1u, grp.g - plan.looped, plan.n_max)
           : group_u(grp, rng, grp.j - 1u, stratify_rows(l, plan.dome));
    LightSample ls = sample_light(l, plan.dome, sh.p, sh.n, u);
    if (!(ls.pdf > 0.0)) return no_shadow_candidate();
    vec3 le = ls.le.x >= 0.0 ? ls.le : light_radiance(l, ls.uv, ls.delta);
    vec3 f = eval_lobes(sh, m, ls.wi, ls.delta ? 0.0 : n_l * ls.pdf, plan.technique, plan.diffuse_mis, plan.n_b);
    // Divide by the expected count n_l (many lights: the selection probability is in it).
    vec3 c = f * le / (ls.pdf * n_l);
    if (!grp.cv) return ShadowCandidate(ls.wi, ls.dist, c, 0.0);
    // g_j / (rho Lc(w_j) / pi), zero exactly where eval_lobes (and so c) is. V_j is the ray's
    // answer, also where c is 0 (a black texel): V_j must not depend on L.
    float cs = dot(sh.n, ls.wi);
    float s = cs > 0.0 && dot(sh.ng, ls.wi) > 0.0 ? cs / (ls.pdf * n_l) : 0.0;
    if (s > 0.0) {
        grp.cv_tr += 1.0;
        shadow_ray(ray, ls.wi, ls.dist, c, s, false);
    }
    return no_shadow_candidate();
}

// The BRDF sample of lobe k (k == lobes: the diffuse lobe) for 2D sample u (group_u): its
// direction and the lights it crosses (ids, their count; 0 when the sample is invalid: the
// pruning, nothing to trace).
uint direct_brdf_sample(Shading sh, GpuMaterial m, uint k, vec2 u, out BrdfDir s, out uint ids[DIRECT_MAX_CROSSED]) {
    s.delta = false;
    if (k == min(m.lobe_count, 2u)) {
        vec3 c = cosine_hemisphere(u);
        s.wi = c.x * sh.t + c.y * sh.b + c.z * sh.n;
        s.pdf = c.z * INV_PI;
        s.weight = sh.albedo;
    } else {
        BrdfSample bs = brdf_sample(m.lobes[k], sh.n, sh.t, sh.b, sh.v, u);
        if (!bs.valid) return 0u;
        s.wi = bs.wi; s.weight = bs.weight; s.pdf = bs.pdf; s.delta = bs.delta;
    }
    if (!(s.pdf > 0.0) || dot(s.wi, sh.ng) <= 0.0) return 0u;
    return lights_along(sh.p, s.wi, ids);
}

// The candidate of BRDF sample s for light `id` it crosses, MIS-weighted against that light's
// samples (light_pmf() for a light reached by picks).
ShadowCandidate direct_brdf_light(DirectPlan plan, Shading sh, BrdfDir s, uint id) {
    GpuLight l = light_seen_from(sh, id);
    if (!light_reaches(l)) return no_shadow_candidate();
    LightHit lh = light_hit(l, plan.dome, sh.p, sh.n, s.wi);
    if (!(lh.pdf > 0.0)) return no_shadow_candidate();
    float w = 1.0;
    if (plan.technique == TECHNIQUE_MIS && !s.delta) {
        float n_l = light_picked(plan.sel, l)
            ? light_pmf(plan.sel, sh.p, sh.n, float(plan.n_max), id, l)
            : float(light_count_for(l, sh.p, plan.n_max));
        w = mis_power(float(plan.n_b), s.pdf, n_l, lh.pdf);
    }
    vec3 c = s.weight * light_radiance(l, lh.uv, false) * (w / float(plan.n_b));
    return ShadowCandidate(s.wi, lh.t, c, 0.0);
}

// The iteration's shadow ray, traced (the one call site of trace_occluded in direct lighting):
// its contribution if visible, to the result or the running flush, and a control variate
// sample's answer.
void direct_trace(DirectPlan plan, Shading sh, ShadowRay ray, inout DirectGroup grp, inout ShadowGroup group,
                  inout vec3 result, inout uint rays) {
    rays += 1u;
    bool visible = shadow_visible(sh, ray.w, ray.dist);
    if (ray.cv >= 0.0) {
        // g_j / (rho / pi): the ray came from this light round's direct_light_sample().
        vec3 gj = ray.cv * control_radiance(grp.l, plan.dome, ray.w);
        if (visible) {
            grp.cv_vis += 1.0;
            grp.cv_sv += gj;
        } else {
            grp.cv_so += gj;
        }
    }
    if (visible && ray.flush) group.part += ray.c;
    else if (visible) result += ray.c;
}

// One loop iteration opens the group if need be, then makes at most one shadow ray (a light
// sample; a BRDF sample and the first light it crosses, or the next one; a pick of a resampling
// flush) and traces it (direct_trace): one traversal for the driver to compile. `rays` counts the
// shadow rays traced.
vec3 direct_lighting(Shading sh, GpuMaterial m, inout Rng rng, inout uint rays) {
    if (frame.light_count == 0u) return vec3(0.0);
    DirectPlan plan = direct_plan(sh, m);
    direct_plan_picks(plan, rng);
    PROF(PROF_DIRECT_PLAN);
    vec3 result = vec3(0.0);
    DirectGroup grp;
    grp.g = 0u;
    grp.opened = false;
    grp.n_l = 0.0;
    uint ids[DIRECT_MAX_CROSSED];                 // the lights the BRDF sample crosses
    ShadowCandidate cands[SHADOW_GROUP_MAX];      // the resampling group's waiting candidates
    ShadowGroup group = shadow_group();
    ShadowRay ray;
    while (grp.g < plan.groups) {
        if (!grp.opened) direct_open(plan, sh, grp, rng);
        PROF(PROF_DIRECT_OPEN);
        ray.on = false;
        if (group.flushing && !shadow_flush_next(group, cands, ray)) {
            result += group.part;
            if (shadow_flush_done(group)) cands[group.n++] = group.hold;
        }
        PROF(PROF_DIRECT_FLUSH);
        if (!group.flushing) {
            ShadowCandidate x = no_shadow_candidate();
            uint step = direct_step(grp);
            if (step == DIRECT_SAMPLE) {
                grp.j += 1u;
                PROF(PROF_DIRECT_LOOP);
                if (grp.g < plan.rounds) {
                    x = direct_light_sample(plan, sh, m, grp, ray, rng);
                    PROF(PROF_LIGHT_SAMPLE);
                } else {
                    grp.crossed = direct_brdf_sample(sh, m, grp.g - plan.first_brdf, group_u(grp, rng, grp.j - 1u, false), grp.bdir, ids);
                    grp.q = 0u;
                    if (grp.crossed > 0u) step = DIRECT_CROSS;
                    PROF(PROF_BRDF_SAMPLE);
                }
            } else if (step == DIRECT_CLOSE) {
                grp.closed = true;
                if (grp.close) shadow_group_end(group, cands, rng);
                // With no flush to wait for (no resampling, or nothing waiting) the group ends
                // in this iteration: its rays are all traced, and an iteration saved is a pass
                // of every lane through the loop's body.
                if (!group.flushing) step = DIRECT_END;
            }
            if (step == DIRECT_END) {
                if (grp.cv) result += control_variate(sh, grp.l, plan.dome, float(grp.count), grp.cv_sv, grp.cv_so, grp.cv_vis, grp.cv_tr);
                grp.g += 1u;
                grp.opened = false;
            }
            if (step == DIRECT_CROSS) {
                PROF(PROF_DIRECT_LOOP);
                x = direct_brdf_light(plan, sh, grp.bdir, ids[grp.q++]);
                PROF(PROF_BRDF_SAMPLE);
            }
            uint joins = shadow_candidate(ray, x, group.n, rng);
            if (joins == SHADOW_FULL) {
                shadow_flush_start(group, cands, rng);
                group.held = true;
                group.hold = x;
            } else if (joins == SHADOW_JOIN) {
                cands[group.n++] = x;
            }
        }
        PROF(PROF_DIRECT_CANDIDATES);
        if (ray.on) direct_trace(plan, sh, ray, grp, group, result, rays);
        PROF(PROF_SHADOW_TRACE);
    }
    PROF(PROF_DIRECT_LOOP);
    return result;
}

#endif
