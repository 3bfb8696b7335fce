// The one trace interface every kernel uses. Two implementations behind it, chosen per build
// variant: hardware ray queries (TRACE_RAYQUERY) and illum's compute BVH (TRACE_BVH).
// Semantics (both paths): the closest hit with tmin < t < tmax among instances whose mask shares a
// bit with `mask`; triangles are two-sided for tracing; analytic shapes are reported as HIT_SHAPE
// with `prim` = index into the shape buffer.
#ifndef ILLUM_TRACE_GLSL
#define ILLUM_TRACE_GLSL

#include "scene/scene.glsl"
#include "trace/shapes.glsl"

struct Hit {
    float t;
    uint kind;       // HIT_*
    uint instance;   // GpuInstance index (triangles)
    uint prim;       // triangle index within its mesh, or shape index
    vec2 bary;       // barycentrics of vertices 1 and 2 (triangles)
};

#if defined(TRACE_RAYQUERY)
#extension GL_EXT_ray_query : require
layout(binding = BINDING_TLAS) uniform accelerationStructureEXT tlas;

// Procedural candidates (the analytic shapes' AABBs) are intersected here; shape index =
// instance custom index (first shape of that BLAS) + primitive index. A macro, because GLSL cannot
// pass a rayQueryEXT to a function.
#define RQ_PROCEED(rq, o, d, tmin, tmax_ray)                                                         \
    while (rayQueryProceedEXT(rq)) {                                                                 \
        if (rayQueryGetIntersectionTypeEXT(rq, false) == gl_RayQueryCandidateIntersectionAABBEXT) {  \
            uint s_ = rayQueryGetIntersectionInstanceCustomIndexEXT(rq, false)                       \
                    + rayQueryGetIntersectionPrimitiveIndexEXT(rq, false);                           \
            float tmax_ = rayQueryGetIntersectionTypeEXT(rq, true) != gl_RayQueryCommittedIntersectionNoneEXT \
                ? rayQueryGetIntersectionTEXT(rq, true) : tmax_ray;                                  \
            float t_ = intersect_shape(get_shape(s_), o, d, tmin, tmax_);                           \
            if (t_ < INF) rayQueryGenerateIntersectionEXT(rq, t_);                                   \
        }                                                                                            \
    }

Hit trace_closest(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsNoneEXT, mask, o, tmin, d, tmax);
    RQ_PROCEED(rq, o, d, tmin, tmax)
    Hit h;
    h.t = INF; h.kind = HIT_NONE; h.instance = NONE; h.prim = NONE; h.bary = vec2(0.0);
    uint type = rayQueryGetIntersectionTypeEXT(rq, true);
    if (type == gl_RayQueryCommittedIntersectionTriangleEXT) {
        h.t = rayQueryGetIntersectionTEXT(rq, true);
        h.kind = HIT_TRIANGLE;
        h.instance = rayQueryGetIntersectionInstanceCustomIndexEXT(rq, true);
        h.prim = rayQueryGetIntersectionPrimitiveIndexEXT(rq, true);
        h.bary = rayQueryGetIntersectionBarycentricsEXT(rq, true);
    } else if (type == gl_RayQueryCommittedIntersectionGeneratedEXT) {
        h.t = rayQueryGetIntersectionTEXT(rq, true);
        h.kind = HIT_SHAPE;
        h.prim = rayQueryGetIntersectionInstanceCustomIndexEXT(rq, true)
               + rayQueryGetIntersectionPrimitiveIndexEXT(rq, true);
    }
    return h;
}

bool trace_occluded(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsTerminateOnFirstHitEXT, mask, o, tmin, d, tmax);
    RQ_PROCEED(rq, o, d, tmin, tmax)
    return rayQueryGetIntersectionTypeEXT(rq, true) != gl_RayQueryCommittedIntersectionNoneEXT;
}
#elif defined(TRACE_BVH)
#include "trace/bvh.glsl"
#else
#error "no trace backend: define TRACE_RAYQUERY or TRACE_BVH"
#endif

#endif
