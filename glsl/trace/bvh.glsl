// The trace interface on illum's compute BVH (TRACE_BVH; built by src/trace/bvh/): trace.glsl
// documents the semantics both paths share. Empty in other variants.
//
// One loop walks both levels: a top-level leaf is a mesh instance (the ray moves into its object
// space and a marker goes on the stack; popping the marker moves it back) or an analytic shape.
// Nodes hold four children's boxes quantized to bytes (BvhNode); the children a ray enters are
// visited nearest first, and for closest hits the stack keeps each entry's distance so that
// entries beyond the nearest hit so far are dropped unread. Triangles use the watertight test of
// Woop, Benthin and Wald (JCGT 2013) on vertices gathered in leaf order, two-sided, with
// tmin < t < tmax.
//
// Written for lavapipe as much as for GPUs (measurements: src/trace/bvh/mod.rs). Lavapipe runs 8
// rays in the lanes of one SIMD loop, executes every branch of the loop body for all of them
// under a mask, and turns each load from a per-lane address into 8 scalar loads: the cost is
// mostly words fetched per ray, then the body's ALU. Hence small nodes, and one iteration that
// does a bit of each kind of work for the lanes that need it (pop, test a node, enter an
// instance, test one triangle), so that a lane often pops, descends and tests a triangle in the
// same iteration.
#ifndef ILLUM_TRACE_BVH_GLSL
#define ILLUM_TRACE_BVH_GLSL
#if defined(TRACE_BVH)

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_control_flow_attributes : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/scene.glsl"
#include "trace/hit.glsl"
#include "trace/shapes.glsl"

layout(scalar, binding = BINDING_BVH) uniform BvhBlock { BvhHeader bvh; BvhFlat bvh_flat_shapes; };
// Nodes (BvhNode), triangles (BvhTriangle, 40 bytes) and instances are read as 64-bit words, two
// fields per load: lavapipe issues one gather, or 8 scalar loads, per word whatever its width, so
// this halves the loads (1.4-1.5x rays per CPU-second where loads are lane by lane, as in Mesa 22
// or without AVX-512; the same with AVX-512 gathers: docs/performance-kernels.md, "Trace throughput").
layout(buffer_reference, scalar, buffer_reference_align = 8) readonly buffer BvhWordRef { uint64_t v[]; };
uvec2 bvh_word(BvhWordRef p, uint i) { return unpackUint2x32(p.v[i]); }
vec4 bvh_row(BvhWordRef p, uint i) { return uintBitsToFloat(uvec4(bvh_word(p, i), bvh_word(p, i + 1u))); }

// A ray in the space of the level being walked, with what the box and triangle tests reuse.
struct BvhRay {
    vec3 o;
    vec3 d;
    vec3 inv_d;    // 1 / d, zero components replaced by a tiny value of the same sign
    uint kx, ky, kz;
    vec3 shear;    // Sx, Sy, Sz of the watertight test
};

// 1 / d for the slab tests, zero components replaced by a tiny value of the same sign.
vec3 bvh_inv_dir(vec3 d) {
    const float tiny = 1e-20;
    return 1.0 / mix(d, mix(vec3(tiny), vec3(-tiny), lessThan(d, vec3(0.0))), lessThan(abs(d), vec3(tiny)));
}

// Box exits are widened by a few ulp so that rounding never culls a box the ray touches (Ize
// 2013, "Robust BVH ray traversal"); the host pads the boxes for the rest.
const float BVH_WIDEN = 1.0 + 4.0 / 16777216.0;

BvhRay bvh_ray(vec3 o, vec3 d) {
    BvhRay r;
    r.o = o;
    r.d = d;
    vec3 ad = abs(d);
    r.inv_d = bvh_inv_dir(d);
    // The dimension where the ray direction is largest becomes z; x and y keep the winding.
    r.kz = ad.x > ad.y ? (ad.x > ad.z ? 0u : 2u) : (ad.y > ad.z ? 1u : 2u);
    r.kx = r.kz == 2u ? 0u : r.kz + 1u;
    r.ky = r.kx == 2u ? 0u : r.kx + 1u;
    if (d[r.kz] < 0.0) { uint t = r.kx; r.kx = r.ky; r.ky = t; }
    r.shear = vec3(d[r.kx] / d[r.kz], d[r.ky] / d[r.kz], 1.0 / d[r.kz]);
    return r;
}

// Watertight ray/triangle test; t in (tmin, tmax) and the barycentrics of v1 and v2, or false.
bool bvh_triangle(BvhRay r, vec3 v0, vec3 v1, vec3 v2, float tmin, float tmax, out float t, out vec2 bary) {
    t = INF;
    bary = vec2(0.0);
    vec3 A = v0 - r.o, B = v1 - r.o, C = v2 - r.o;
    // `precise` keeps every product rounded on its own, as the test's watertightness assumes: an
    // edge shared by two triangles gives exactly opposite edge functions in both.
    precise float Ax = A[r.kx] - r.shear.x * A[r.kz];
    precise float Ay = A[r.ky] - r.shear.y * A[r.kz];
    precise float Bx = B[r.kx] - r.shear.x * B[r.kz];
    precise float By = B[r.ky] - r.shear.y * B[r.kz];
    precise float Cx = C[r.kx] - r.shear.x * C[r.kz];
    precise float Cy = C[r.ky] - r.shear.y * C[r.kz];
    precise float U = Cx * By - Cy * Bx;
    precise float V = Ax * Cy - Ay * Cx;
    precise float W = Bx * Ay - By * Ax;
    // Two-sided: inside when the three edge functions do not disagree in sign (zero is inside,
    // so a ray through a shared edge hits at least one of its triangles).
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0)) return false;
    float det = U + V + W;
    if (det == 0.0) return false;
    float Az = r.shear.z * A[r.kz];
    float Bz = r.shear.z * B[r.kz];
    float Cz = r.shear.z * C[r.kz];
    float T = U * Az + V * Bz + W * Cz;
    float inv_det = 1.0 / det;
    t = T * inv_det;
    if (!(t > tmin && t < tmax)) return false;
    bary = vec2(V, W) * inv_det;
    return true;
}

// The four bytes of a plane word (one per child), as floats.
vec4 bvh_bytes(uint w) { return vec4(uvec4(w, w >> 8, w >> 16, w >> 24) & 0xffu); }

bool bvh_is_leaf(uint link) { return (link & BVH_LEAF_BIT) != 0u; }
uint bvh_leaf_first(uint link) { return link & BVH_LEAF_FIRST_MASK; }
uint bvh_leaf_count(uint link) { return ((link >> BVH_LEAF_COUNT_SHIFT) & 15u) + 1u; }
// Stack entry that marks the return from an instance to the top level.
const uint BVH_MARKER = 0xfffffffeu;

// The stack's top 8 entries live in vectors (l0, l1: links, top at l0.x; t0, t1: their entry
// distances; rc of them in use), the rest in the private arrays below them. Lavapipe turns every
// store to a private array at a per-lane index into 8 masked scalar stores, each reading the old
// word back for the lanes that do not store: those pushes and pops took 16% of a direct-lighting
// kernel's time and 26% of the path tracer's (perf of the JIT code, docs/performance-kernels.md).
// A push or pop of the top is a few vector selects; the arrays take what overflows (rare: the
// depth of a 4-wide tree).
//
// An iteration pushes once, at its end (one copy of the code per traversal): n (1 to 4) entries
// p (top first: an instance's marker, then a node's second, third and fourth nearest children)
// with distances pt. The entries pushed out below the 8th go to the arrays, deepest first (with
// rc + n > 8 they are among old 4..7).
#define BVH_SPILL(k, lk, tk) if (rc > k && k + n >= 8u) { stack[sp] = lk; if (!any_hit) stack_t[sp] = tk; sp++; }
#define BVH_PUSH(n_, p, pt) {                                                                 \
        uint n = n_;                                                                        \
        if (rc + n > 8u) {                                                                  \
            BVH_SPILL(7u, l1.w, t1.w) BVH_SPILL(6u, l1.z, t1.z)                               \
            BVH_SPILL(5u, l1.y, t1.y) BVH_SPILL(4u, l1.x, t1.x)                               \
            rc = 8u - n;                                                                    \
        }                                                                                   \
        if (n == 1u) {                                                                      \
            l1 = uvec4(l0.w, l1.xyz); l0 = uvec4(p.x, l0.xyz);                              \
            if (!any_hit) { t1 = vec4(t0.w, t1.xyz); t0 = vec4(pt.x, t0.xyz); }             \
        } else if (n == 2u) {                                                               \
            l1 = uvec4(l0.zw, l1.xy); l0 = uvec4(p.xy, l0.xy);                              \
            if (!any_hit) { t1 = vec4(t0.zw, t1.xy); t0 = vec4(pt.xy, t0.xy); }             \
        } else if (n == 3u) {                                                               \
            l1 = uvec4(l0.yzw, l1.x); l0 = uvec4(p.xyz, l0.x);                              \
            if (!any_hit) { t1 = vec4(t0.yzw, t1.x); t0 = vec4(pt.xyz, t0.x); }             \
        } else {                                                                            \
            l1 = l0; l0 = p;                                                                \
            if (!any_hit) { t1 = t0; t0 = pt; }                                             \
        }                                                                                   \
        rc += n;                                                                            \
    }

// Walks the BVH; with `any_hit` the first hit ends the walk. Returns whether anything was hit.
bool bvh_traverse(vec3 o, vec3 d, float tmin, float tmax, uint mask, const bool any_hit, out Hit h) {
    h.t = INF; h.kind = HIT_NONE; h.instance = NONE; h.prim = NONE; h.bary = vec2(0.0);
    if (bvh.root == NONE) return false;
    BvhWordRef node_words = BvhWordRef(bvh.nodes);
    BvhWordRef tri_words = BvhWordRef(bvh.triangles);
    BvhWordRef inst_words = BvhWordRef(bvh.instances);
    BvhRay world = bvh_ray(o, d);
    BvhRay r = world;
    uvec4 l0 = uvec4(NONE), l1 = uvec4(NONE);
    vec4 t0 = vec4(0.0), t1 = vec4(0.0);
    uint rc = 0u;
    uint stack[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    uint sp = 0u;
    uint link = bvh.root;
    uint instance = NONE;
    bool hit = false;
    for (;;) {
        if (link == NONE) {
            float entry;
            if (rc > 0u) {
                link = l0.x;
                l0 = uvec4(l0.yzw, l1.x); l1 = uvec4(l1.yzw, NONE);
                if (!any_hit) { entry = t0.x; t0 = vec4(t0.yzw, t1.x); t1 = vec4(t1.yzw, 0.0); }
                rc--;
            } else {
                if (sp == 0u) break;
                link = stack[--sp];
                if (!any_hit) entry = stack_t[sp];
            }
            if (!any_hit && link != BVH_MARKER && entry > tmax) link = NONE;
            if (link == BVH_MARKER) {
                // Back from an instance to the top level.
                r = world;
                instance = NONE;
                link = NONE;
            }
        }
        // What this iteration pushes (see BVH_PUSH).
        uint push = 0u;
        uvec4 pushed = uvec4(NONE);
        vec4 pushed_t = vec4(0.0);
        if (link != NONE && !bvh_is_leaf(link)) {
            // Child planes: origin + step * q, so t = q * (step / d) + (origin - o) / d.
            uint base = 8u * link;
            uvec2 w0 = bvh_word(node_words, base), w1 = bvh_word(node_words, base + 1u);
            vec3 origin = uintBitsToFloat(uvec3(w0, w1.x));
            uint e = w1.y;
            vec3 a = uintBitsToFloat(uvec3(e << 23, (e >> 8) << 23, (e >> 16) << 23) & 0x7f800000u) * r.inv_d;
            vec3 b = (origin - r.o) * r.inv_d;
            // Near and far planes by the ray's direction signs.
            uvec2 px = bvh_word(node_words, base + 4u), py = bvh_word(node_words, base + 5u);
            uvec2 pz = bvh_word(node_words, base + 6u);
            uint lx = px.x, hx = px.y, ly = py.x, hy = py.y, lz = pz.x, hz = pz.y;
            vec4 near = max(max(bvh_bytes(a.x >= 0.0 ? lx : hx) * a.x + b.x, bvh_bytes(a.y >= 0.0 ? ly : hy) * a.y + b.y),
                            max(bvh_bytes(a.z >= 0.0 ? lz : hz) * a.z + b.z, vec4(tmin)));
            vec4 far = min(min(bvh_bytes(a.x >= 0.0 ? hx : lx) * a.x + b.x, bvh_bytes(a.y >= 0.0 ? hy : ly) * a.y + b.y),
                           bvh_bytes(a.z >= 0.0 ? hz : lz) * a.z + b.z);
            far = min(far * BVH_WIDEN, vec4(tmax));
            uvec4 l = uvec4(bvh_word(node_words, base + 2u), bvh_word(node_words, base + 3u));
            // An unused slot has link NONE (its box, lo 255 > hi 0, can pass the widened test).
            bvec4 hits = bvec4(uvec4(lessThanEqual(near, far)) & uvec4(notEqual(l, uvec4(NONE))));
            vec4 key = mix(vec4(INF), near, hits);
            // Sorting network: nearest first.
#define BVH_CSWAP(a, b) if (key.b < key.a) { float tk = key.a; key.a = key.b; key.b = tk; uint tl = l.a; l.a = l.b; l.b = tl; }
            BVH_CSWAP(x, y) BVH_CSWAP(z, w) BVH_CSWAP(x, z) BVH_CSWAP(y, w) BVH_CSWAP(y, z)
#undef BVH_CSWAP
            uint count = uint(hits.x) + uint(hits.y) + uint(hits.z) + uint(hits.w);
            // The second nearest on top, then the third and fourth.
            if (count > 1u) {
                push = count - 1u;
                pushed = uvec4(l.yzw, NONE);
                pushed_t = vec4(key.yzw, 0.0);
            }
            link = count > 0u ? l.x : NONE;
        }
        if (link != NONE && bvh_is_leaf(link) && instance == NONE) {
            // A top-level leaf: one instance or shape.
            uint base = 8u * bvh_leaf_first(link);
            uvec2 root_index = bvh_word(inst_words, base + 6u);
            uint inst_mask = bvh_word(inst_words, base + 7u).x;
            link = NONE;
            if ((inst_mask & mask) != 0u) {
                if (has_feature(FEATURE_MESHES) && root_index.x != BVH_SHAPE) {
                    // Rows of world_to_object.
                    vec4 row0 = bvh_row(inst_words, base), row1 = bvh_row(inst_words, base + 2u);
                    vec4 row2 = bvh_row(inst_words, base + 4u);
                    vec4 oh = vec4(o, 1.0);
                    r = bvh_ray(vec3(dot(row0, oh), dot(row1, oh), dot(row2, oh)),
                                vec3(dot(row0.xyz, d), dot(row1.xyz, d), dot(row2.xyz, d)));
                    instance = root_index.y;
                    // The marker goes on top of what the node pushed in this iteration.
                    pushed = uvec4(BVH_MARKER, pushed.xyz);
                    pushed_t = vec4(0.0, pushed_t.xyz);
                    push += 1u;
                    link = root_index.x;
                } else if (has_feature(FEATURE_SHAPES)) {
                    float t = intersect_shape(get_shape(root_index.y), o, d, tmin, tmax);
                    if (t < INF) {
                        hit = true;
                        tmax = t;
                        h.t = t; h.kind = HIT_SHAPE; h.instance = NONE; h.prim = root_index.y; h.bary = vec2(0.0);
                        if (any_hit) return true;
                    }
                }
            }
        }
        if (has_feature(FEATURE_MESHES) && link != NONE && bvh_is_leaf(link) && instance != NONE) {
            // One triangle of a bottom-level leaf; the link moves on to the next one.
            uint k = bvh_leaf_first(link);
            float t;
            vec2 bary;
            uvec2 t0 = bvh_word(tri_words, 5u * k), t1 = bvh_word(tri_words, 5u * k + 1u);
            uvec2 t2 = bvh_word(tri_words, 5u * k + 2u), t3 = bvh_word(tri_words, 5u * k + 3u);
            uvec2 t4 = bvh_word(tri_words, 5u * k + 4u);
            vec3 v0 = uintBitsToFloat(uvec3(t0, t1.x));
            vec3 v1 = uintBitsToFloat(uvec3(t1.y, t2));
            vec3 v2 = uintBitsToFloat(uvec3(t3, t4.x));
            if (bvh_triangle(r, v0, v1, v2, tmin, tmax, t, bary)) {
                hit = true;
                tmax = t;
                h.t = t; h.kind = HIT_TRIANGLE; h.instance = instance; h.prim = t4.y; h.bary = bary;
                if (any_hit) return true;
            }
            link = (link & ~BVH_LEAF_FIRST_MASK) == BVH_LEAF_BIT ? NONE : link + 1u - (1u << BVH_LEAF_COUNT_SHIFT);
        }
        if (push > 0u) BVH_PUSH(push, pushed, pushed_t)
    }
    return hit;
}
#undef BVH_PUSH
#undef BVH_SPILL

// FEATURE_FLAT_SHAPES: every shape tested, in shape order, where the ray crosses its box (of
// two shapes at exactly the same distance the first in shape order wins, where the walk keeps the
// first it visits). Lavapipe loads from a per-lane address lane by lane (or by gathers), and
// inside any loop it does so even where every lane reads the same word; a uniform buffer read at
// a compile-time constant offset is one scalar load, which the unrolled loop gives each shape's
// box and words. With few shapes that costs less than the walk's gathered node and shape words
// (docs/performance-kernels.md, "Flat shapes"). The boxes are the BVH's, so the flat test culls
// no hit the walk would find.
layout(constant_id = SPEC_FLAT_KINDS) const uint FLAT_KINDS = 0u;

bool bvh_flat(vec3 o, vec3 d, float tmin, float tmax, uint mask, const bool any_hit, out Hit h) {
    h.t = INF; h.kind = HIT_NONE; h.instance = NONE; h.prim = NONE; h.bary = vec2(0.0);
    bool hit = false;
    vec3 inv_d = bvh_inv_dir(d);
    // Unrolled, with each shape's kind a constant: the driver compiles each shape's own test
    // once and nothing past the last shape (a loop of 16 tests of every kind added 1.3-1.5 s to a
    // cold compile on lavapipe).
    [[unroll]] for (uint i = 0u; i < BVH_FLAT_MAX; ++i) {
        uint kind = (FLAT_KINDS >> (2u * i)) & 3u;
        if (kind == 0u) break;
        vec3 t0 = (bvh_flat_shapes.lo[i].xyz - o) * inv_d, t1 = (bvh_flat_shapes.hi[i].xyz - o) * inv_d;
        vec3 tn = min(t0, t1), tf = max(t0, t1);
        float near = max(max(tn.x, tn.y), max(tn.z, tmin));
        float far = min(min(tf.x, tf.y), min(tf.z, tmax)) * BVH_WIDEN;
        // An any-hit lane that has its hit tests no more shapes; no `break` for it, which would
        // keep the driver from unrolling the loop (and its offsets from being constants).
        if ((bvh_flat_shapes.masks[i] & mask) != 0u && near <= far && !(any_hit && hit)) {
            GpuShape s = bvh_flat_shapes.shapes[i];
            s.kind = kind - 1u;   // the constant, so that only this kind's test is compiled
            float t = intersect_shape(s, o, d, tmin, tmax);
            if (t < INF) {
                hit = true;
                tmax = t;
                h.t = t; h.kind = HIT_SHAPE; h.prim = i;
            }
        }
    }
    return hit;
}

Hit trace_closest(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    Hit h;
    if (has_feature(FEATURE_FLAT_SHAPES)) bvh_flat(o, d, tmin, tmax, mask, false, h);
    else bvh_traverse(o, d, tmin, tmax, mask, false, h);
    return h;
}

bool trace_occluded(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    Hit h;
    if (has_feature(FEATURE_FLAT_SHAPES)) return bvh_flat(o, d, tmin, tmax, mask, true, h);
    return bvh_traverse(o, d, tmin, tmax, mask, true, h);
}

#endif
#endif
