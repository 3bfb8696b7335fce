// What the trace interface (trace.glsl) reports of a closest hit; surface.glsl turns it into a
// shading point.
#ifndef ILLUM_HIT_GLSL
#define ILLUM_HIT_GLSL

#include "shared/layout.glsl"

struct Hit {
    float t;
    uint kind;       // HIT_*
    uint instance;   // GpuInstance index (triangles)
    uint prim;       // triangle index within its mesh, or shape index
    vec2 bary;       // barycentrics of vertices 1 and 2 (triangles)
};

#endif
