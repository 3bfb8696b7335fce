// illum-variants: rq bvh
// The trace interface as a kernel: per ray, trace_closest's Hit and trace_occluded's answer. Host
// side: src/trace/query.rs (tests compare the two trace paths with it; `illum bench trace` times it).
#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "trace/trace.glsl"

layout(local_size_x = 64) in;
layout(push_constant, scalar) uniform QueryBlock { QueryConstants qc; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer QueryRayRef { QueryRay v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) writeonly buffer QueryHitRef { QueryHit v[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= qc.count) return;
    QueryRay r = QueryRayRef(qc.rays).v[i];
    QueryHit q;
    q.t = INF; q.kind = HIT_NONE; q.instance = NONE; q.prim = NONE; q.bary = vec2(0.0);
    q.occluded = 0u; q.pad = 0u;
    if ((qc.mode & QUERY_CLOSEST) != 0u) {
        Hit h = trace_closest(r.origin, r.dir, r.tmin, r.tmax, r.mask);
        q.t = h.t; q.kind = h.kind; q.instance = h.instance; q.prim = h.prim; q.bary = h.bary;
    }
    if ((qc.mode & QUERY_OCCLUDED) != 0u)
        q.occluded = trace_occluded(r.origin, r.dir, r.tmin, r.tmax, r.mask) ? 1u : 0u;
    QueryHitRef(qc.hits).v[i] = q;
}
