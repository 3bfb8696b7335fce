// The trace interface on hardware ray queries (TRACE_RAYQUERY; src/trace/rayquery.rs builds the
// TLAS and BLASes): trace.glsl documents the semantics both paths share. Empty in other variants.
#ifndef ILLUM_RAYQUERY_GLSL
#define ILLUM_RAYQUERY_GLSL
#if defined(TRACE_RAYQUERY)

#extension GL_EXT_ray_query : require

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/scene.glsl"
#include "trace/hit.glsl"
#include "trace/shapes.glsl"

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

#endif
#endif
