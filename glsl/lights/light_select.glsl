// How light samples pick lights in scenes of more than DIRECT_LOOP_LIGHTS lights
// (Frame.light_select): the light tree (light_tree.glsl), or the former linear scan of a CDF over
// every light, kept for comparison.
#ifndef ILLUM_LIGHT_SELECT_GLSL
#define ILLUM_LIGHT_SELECT_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "lights/lights.glsl"

// Selection weight of a light at p (many-light mode): luminance x share, with a floor on the
// cosine factor so that every light that may contribute keeps a positive probability.
float light_importance(GpuLight l, vec3 p, vec3 n) {
    float lum = luminance(l.radiance);
    if (l.kind == LIGHT_DOME || l.kind == LIGHT_SUN) return lum * (l.kind == LIGHT_SUN ? 1.0 : 2.0 * PI);
    vec3 c = l.kind == LIGHT_TRIANGLE ? l.p0.xyz + (l.p1.xyz + l.p2.xyz) / 3.0 : l.p0.xyz;
    vec3 d = c - p;
    float len = length(d);
    float cosc = len > 0.0 ? dot(n, d / len) : 1.0;
    return lum * light_share(l, p) * (0.1 + max(cosc, 0.0)) + 1e-20;
}

#endif
