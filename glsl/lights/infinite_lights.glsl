// The samplers of the infinite lights (light_sampling.glsl states the conventions and what each
// sampler does): the sun's cone and the dome's map, each with its *_hit() of a direction.
#ifndef ILLUM_INFINITE_LIGHTS_GLSL
#define ILLUM_INFINITE_LIGHTS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "lights/dome_map.glsl"
#include "lights/light_sample.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeCdfRef { float v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeGuideRef { uvec2 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer DomeTexelRef { vec4 v[]; };

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
// Dome

// Index i with cdf[i] <= u < cdf[i + 1] among the CDF's intervals (cdf[0] = 0, cdf[n] = 1,
// non-decreasing); only intervals of positive width can be returned for u in [0, 1). The guide
// (one uvec2 per bucket of width 1/m in u, m a multiple of n: src/gpu_scene/dome.rs) bounds the
// binary search to the few intervals that bucket can reach: it returns the same index as a
// search over all n, in O(1) expected steps.
uint cdf_find(DomeCdfRef cdf, uint base, DomeGuideRef guide, uint gbase, uint m, float u) {
    uvec2 r = guide.v[gbase + min(floor_uint(u * float(m)), m - 1u)];
    uint lo = r.x, hi = r.y;   // invariant: cdf[lo] <= u < cdf[hi] (cdf[n] = 1 > u)
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1u;
        if (cdf.v[base + mid] <= u) lo = mid; else hi = mid;
    }
    return lo;
}

// The density inside a cell (GpuDomeSampling.shape): piecewise bilinear over its 2 x 2 quarters,
// given by its 3 x 3 nodes (rows r0, r1, r2 from the top, each (left, middle, right)) at x, y in
// {0, 1/2, 1}. Both shapes other than uniform are exactly this: Mitsuba's one bilinear patch
// (nodes interpolated from its corners) and the four bilinear quarters of illum's texel. Sampling
// draws y from the marginal, then x given y, each piecewise linear and inverted in closed form, so
// (fx, fy) -> (x, y) is monotone in each and the sample sequence's stratification is kept.
// Mitsuba's cell (DOME_SHAPE_CORNERS, `bilinear`) is one bilinear patch, kept as its corners: top
// (left, right) t and bottom b, whose rows are linear (dome_patch_warp).
struct DomeCell { bool bilinear; vec2 t, b; vec3 r0, r1, r2; };

// Nodes are luminances; the sign bit of a cell's first node (texel (i, j)) says whether the cell
// is shaped at all (src/gpu_scene/dome.rs: where its luminance varies enough to pay for it).
float dome_node(DomeCdfRef nodes, uint stride, int i, int j) {
    return abs(nodes.v[uint(j + 1) * stride + uint(i + 1)]);
}

// The four texels at the corners of a Mitsuba-convention cell (i, j) (GpuDomeSampling.texels):
// its lookup's bilinear patch, top row (t00, t10) and bottom row (t01, t11), periodic in u.
struct DomeCorners { vec3 t00, t10, t01, t11; };

// Whether a light sample reads its cell's corners itself (dome_corners) instead of the nodes and
// the texture lookup: a Mitsuba-convention map whose texels the host gave.
bool dome_reads_corners(GpuLight l, GpuDomeSampling ds) { return dome_is_mitsuba(l) && ds.texels != 0ul; }

DomeCorners dome_corners(GpuDomeSampling ds, uint i, uint j) {
    DomeTexelRef t = DomeTexelRef(ds.texels);
    uint w = ds.width;   // Mitsuba's cells: one column a texel column
    uint r0 = j * w, r1 = r0 + w, i1 = i + 1u == w ? 0u : i + 1u;
    return DomeCorners(t.v[r0 + i].rgb, t.v[r0 + i1].rgb, t.v[r1 + i].rgb, t.v[r1 + i1].rgb);
}

// The radiance of light l's map at f in a cell of corners k: the lookup's bilinear patch.
vec3 dome_corner_radiance(GpuLight l, DomeCorners k, vec2 f) {
    return l.radiance * mix(mix(k.t00, k.t10, f.x), mix(k.t01, k.t11, f.x), f.y);
}

// No corners read (dome_reads_corners false): dome_cell takes the nodes.
DomeCorners no_corners() { return DomeCorners(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0)); }

// Whether cell (i, j)'s density is shaped (the sign bit of its first node); uniform otherwise.
bool dome_cell_shaped(GpuDomeSampling ds, uint i, uint j) {
    if (!has_feature(FEATURE_DOME_SHAPED) || ds.shape == DOME_SHAPE_UNIFORM) return false;
    uint k = (j + 1u) * ds.nodes_width + i + 1u;
    return (floatBitsToUint(DomeCdfRef(ds.nodes).v[k]) & 0x80000000u) != 0u;
}

// The nodes of shaped cell (i, j). With corners (`read`, Mitsuba's cells), their luminance
// under the light's colour, as the host's nodes hold it.
DomeCell dome_cell(GpuLight l, GpuDomeSampling ds, uint i, uint j, bool read, DomeCorners k) {
    DomeCell c = DomeCell(ds.shape == DOME_SHAPE_CORNERS, vec2(1.0), vec2(1.0), vec3(1.0), vec3(1.0), vec3(1.0));
    DomeCdfRef nodes = DomeCdfRef(ds.nodes);
    uint s = ds.nodes_width;
    int x = int(i), y = int(j);
    if (c.bilinear && read) {
        vec3 tint = l.radiance;
        c.t = max(vec2(luminance(tint * k.t00), luminance(tint * k.t10)), 0.0);
        c.b = max(vec2(luminance(tint * k.t01), luminance(tint * k.t11)), 0.0);
    } else if (c.bilinear) {
        // Mitsuba: corners are texels (i, j) .. (i + 1, j + 1), the nodes wrapped in u already.
        c.t = vec2(dome_node(nodes, s, x, y), dome_node(nodes, s, x + 1, y));
        c.b = vec2(dome_node(nodes, s, x, y + 1), dome_node(nodes, s, x + 1, y + 1));
    } else {
        // illum's bilinear lookup over texel (i, j): at its centre the texel, at its edges the
        // means of two texels, at its corners of four.
        vec3 rows[3];
        for (int d = 0; d < 3; d++) {
            vec3 t = vec3(dome_node(nodes, s, x - 1, y + d - 1), dome_node(nodes, s, x, y + d - 1),
                          dome_node(nodes, s, x + 1, y + d - 1));
            rows[d] = vec3(0.5 * (t.x + t.y), t.y, 0.5 * (t.y + t.z));
        }
        c.r0 = 0.5 * (rows[0] + rows[1]);
        c.r1 = rows[1];
        c.r2 = 0.5 * (rows[1] + rows[2]);
    }
    return c;
}

// Integral over [0, 1] of the piecewise linear function with nodes n at 0, 1/2, 1 (times 4).
float dome_pl_mass(vec3 n) { return n.x + 2.0 * n.y + n.z; }

// The piecewise linear function of nodes n at x.
float dome_pl_eval(vec3 n, float x) {
    return x < 0.5 ? mix(n.x, n.y, 2.0 * x) : mix(n.y, n.z, 2.0 * x - 1.0);
}

// x in [0, 1) with density proportional to the line from a (at 0) to b (at 1), by inversion.
float dome_sample_linear(float u, float a, float b) {
    if (!(a + b > 0.0)) return u;
    if (u == 0.0 && a == 0.0) return 0.0;
    float x = u * (a + b) / (a + sqrt(mix(a * a, b * b, u)));
    return min(x, 0.99999994);
}

// x in [0, 1) with density proportional to the piecewise linear function of nodes n.
float dome_sample_pl(float u, vec3 n) {
    float sa = n.x + n.y, sb = n.y + n.z;
    if (!(sa + sb > 0.0)) return u;
    float t = u * (sa + sb);
    if (t < sa || !(sb > 0.0)) return 0.5 * dome_sample_linear(min(t / sa, 1.0), n.x, n.y);
    return 0.5 + 0.5 * dome_sample_linear(min((t - sa) / sb, 1.0), n.y, n.z);
}

// The cell's nodes along x at height y.
vec3 dome_cell_row(DomeCell c, float y) {
    return y < 0.5 ? mix(c.r0, c.r1, 2.0 * y) : mix(c.r1, c.r2, 2.0 * y - 1.0);
}

// The cell's marginal nodes along y (each row's mass, times 4).
vec3 dome_cell_marginal(DomeCell c) {
    return vec3(dome_pl_mass(c.r0), dome_pl_mass(c.r1), dome_pl_mass(c.r2));
}

// The cell's density at f relative to uniform (it integrates to 1 over the cell), given its
// marginal m: f over its mean, 16 f / mass(m).
float dome_cell_density(DomeCell c, vec3 m, vec2 f) {
    float total = 0.25 * dome_pl_mass(m);
    if (!(total > 0.0)) return 1.0;
    return 4.0 * dome_pl_eval(dome_cell_row(c, f.y), f.x) / total;
}

// (fx, fy) uniform in the cell to a point with the cell's density (y from the marginal, then x
// given y); returns that density there.
float dome_cell_warp(DomeCell c, inout vec2 f) {
    vec3 m = dome_cell_marginal(c);
    if (!(dome_pl_mass(m) > 0.0)) return 1.0;
    float y = dome_sample_pl(f.y, m);
    f = vec2(dome_sample_pl(f.x, dome_cell_row(c, y)), y);
    return dome_cell_density(c, m, f);
}

// One bilinear patch of corners t, b: its point drawn by inverting the linear marginal in y, then
// the line at y, each once (its rows as piecewise linear nodes would be linear, the same inverse
// CDF by halves); returns the density relative to uniform.
float dome_patch_warp(vec2 t, vec2 b, inout vec2 f) {
    float top = t.x + t.y, total = top + b.x + b.y;
    if (!(total > 0.0)) return 1.0;
    float y = dome_sample_linear(f.y, top, b.x + b.y);
    vec2 row = mix(t, b, y);
    f = vec2(dome_sample_linear(f.x, row.x, row.y), y);
    return 4.0 * mix(row.x, row.y, f.x) / total;
}

// The patch's density at f relative to uniform (dome_patch_warp's).
float dome_patch_density(vec2 t, vec2 b, vec2 f) {
    float total = t.x + t.y + b.x + b.y;
    if (!(total > 0.0)) return 1.0;
    vec2 row = mix(t, b, f.y);
    return 4.0 * mix(row.x, row.y, f.x) / total;
}

// A shaped cell's point and density (dome_cell), and its density at f.
float dome_shape_warp(DomeCell c, inout vec2 f) {
    return c.bilinear ? dome_patch_warp(c.t, c.b, f) : dome_cell_warp(c, f);
}
float dome_shape_density(DomeCell c, vec2 f) {
    return c.bilinear ? dome_patch_density(c.t, c.b, f) : dome_cell_density(c, dome_cell_marginal(c), f);
}

// The table's density at direction w of map coordinates uv (0 where it gives none).
float dome_table_pdf(GpuLight l, GpuDomeSampling ds, vec3 w, vec2 uv) {
    uint W = ds.width, H = ds.height;
    float cu = uv.x - dome_cell_offset(l, W);
    if (cu < 0.0) cu += 1.0;
    float x = max(cu, 0.0) * float(W), y = max(uv.y, 0.0) * float(H);
    uint i = min(floor_uint(x), W - 1u);
    uint j = min(floor_uint(y), H - 1u);
    DomeCdfRef marg = DomeCdfRef(ds.marginal);
    DomeCdfRef cond = DomeCdfRef(ds.conditional);
    uint base = j * (W + 1u);
    float pm = marg.v[j + 1u] - marg.v[j];
    float pc = cond.v[base + i + 1u] - cond.v[base + i];
    float jacobian = dome_jacobian(l, w);
    if (!(jacobian > 0.0)) return 0.0;
    float shape = 1.0;
    if (dome_cell_shaped(ds, i, j)) {
        // The corners only where the shape needs them (a BRDF sample's hit needs no radiance here).
        bool read = dome_reads_corners(l, ds);
        DomeCell c = dome_cell(l, ds, i, j, read, read ? dome_corners(ds, i, j) : no_corners());
        shape = dome_shape_density(c, clamp(vec2(x - float(i), y - float(j)), 0.0, 1.0));
    }
    return pm * pc * shape * float(W * H) / jacobian;
}

// The defensive mixture's density from the table's (see the header).
float dome_mix_pdf(GpuDomeSampling ds, float table_pdf) {
    return ds.defensive > 0.0 ? ds.defensive / (4.0 * PI) + (1.0 - ds.defensive) * table_pdf : table_pdf;
}

// A constant dome (no table) at a shading point with normal n: cosine-weighted about n, pdf
// cos / pi, the product of its radiance and a diffuse lobe's cosine, so that an unshadowed
// diffuse point gets its exact irradiance from every sample and no sample falls below the
// horizon (uniform over the sphere wasted half). It covers every direction direct lighting
// integrates (eval_lobes() is 0 where n.w <= 0). n = 0 (no shading point): uniform over the sphere.
LightSample sample_dome(GpuLight l, GpuDomeSampling ds, vec3 n, vec2 u) {
    LightSample s = no_light_sample();
    s.dist = INF;
    if (ds.width == 0u) {
        if (n != vec3(0.0)) {
            vec3 t, b;
            make_basis(n, t, b);
            vec3 c = cosine_hemisphere(u);
            s.wi = normalize(c.x * t + c.y * b + c.z * n);
            // dome_hit()'s density, from the same direction (on the horizon: none).
            s.pdf = max(dot(n, s.wi), 0.0) * INV_PI;
            if (!(c.z > 0.0) || !(s.pdf > 0.0)) return no_light_sample();
        } else {
            s.wi = uniform_sphere(u);
            s.pdf = 1.0 / (4.0 * PI);
        }
        s.n = -s.wi;
        s.uv = dome_uv(l, s.wi);
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
    // The guides follow the conditional CDFs: the marginal's buckets, then each row's.
    DomeGuideRef guide = DomeGuideRef(ds.conditional + 4ul * uint64_t(H * (W + 1u)));
    uint j = cdf_find(marg, 0u, guide, 0u, ds.marginal_buckets, ux);
    float m0 = marg.v[j], m1 = marg.v[j + 1u];
    uint base = j * (W + 1u);
    uint i = cdf_find(cond, base, guide, ds.marginal_buckets + j * W, W, uy);
    float c0 = cond.v[base + i], c1 = cond.v[base + i + 1u];
    float pm = m1 - m0, pc = c1 - c0;
    if (!(pm > 0.0) || !(pc > 0.0)) return s;
    vec2 f = clamp(vec2((uy - c0) / pc, (ux - m0) / pm), 0.0, 1.0);
    // A Mitsuba-convention cell's corners, read once for its shape and the sample's radiance.
    bool read = dome_reads_corners(l, ds);
    DomeCorners k = read ? dome_corners(ds, i, j) : no_corners();
    float shape = dome_cell_shaped(ds, i, j) ? dome_shape_warp(dome_cell(l, ds, i, j, read, k), f) : 1.0;
    if (read) s.le = dome_corner_radiance(l, k, f);
    vec2 uv = vec2((float(i) + f.x) / float(W) + dome_cell_offset(l, W), (float(j) + f.y) / float(H));
    if (uv.x >= 1.0) uv.x -= 1.0;
    float jacobian;
    s.wi = dome_direction(l, uv, jacobian);
    if (!(jacobian > 0.0)) return s;
    s.n = -s.wi;
    s.uv = uv;
    s.pdf = dome_mix_pdf(ds, pm * pc * shape * float(W * H) / jacobian);
    return s;
}

LightHit dome_hit(GpuLight l, GpuDomeSampling ds, vec3 n, vec3 w) {
    LightHit h = light_miss();
    h.n = -w;
    h.uv = dome_uv(l, w);
    if (ds.width == 0u) {
        // sample_dome()'s density at w.
        h.pdf = n != vec3(0.0) ? max(dot(n, w), 0.0) * INV_PI : 1.0 / (4.0 * PI);
        return h;
    }
    h.pdf = dome_mix_pdf(ds, dome_table_pdf(l, ds, w, h.uv));
    return h;
}

#endif
