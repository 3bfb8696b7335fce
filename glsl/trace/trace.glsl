// The one trace interface every kernel uses. Two implementations behind it, chosen per build
// variant: hardware ray queries (TRACE_RAYQUERY) and illum's compute BVH (TRACE_BVH).
// Semantics (both paths): the closest hit with tmin < t < tmax among instances whose mask shares a
// bit with `mask`; triangles are two-sided for tracing; analytic shapes are reported as HIT_SHAPE
// with `prim` = index into the shape buffer.
#ifndef ILLUM_TRACE_GLSL
#define ILLUM_TRACE_GLSL

#include "trace/hit.glsl"

#if defined(TRACE_RAYQUERY)
#include "trace/rayquery.glsl"
#elif defined(TRACE_BVH)
#include "trace/bvh.glsl"
#else
#error "no trace backend: define TRACE_RAYQUERY or TRACE_BVH"
#endif

#endif
