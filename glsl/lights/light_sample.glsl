// What every light sampler shares (light_sampling.glsl states the conventions): the LightSample
// and LightHit types, the silhouette margins, and the helpers that complete area and direction
// samples and decide the planar mixture.
#ifndef ILLUM_LIGHT_SAMPLE_GLSL
#define ILLUM_LIGHT_SAMPLE_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"

struct LightSample {
    vec3 wi;      // unit direction from p toward the light
    float dist;   // distance from p to x along wi; INF for the dome and the sun
    vec3 x;       // the sampled point on the emitter (area lights)
    float pdf;    // solid-angle pdf of wi; 0: no sample
    vec3 n;       // geometric normal of the emitter at x (area lights)
    bool delta;   // delta light (sun of zero angular size): pdf is 1, no MIS
    vec2 uv;      // texture coordinates on the light (see above)
    vec3 le;      // the radiance toward p where the sampler read it (a Mitsuba-convention dome with its
                  // texels: its cell's corners); negative: not read, light_radiance() gives it
};

// What a direction w from p sees of one light: the pdf the light's sampler has for w (0 if it never
// produces w), and where w meets the emitter.
struct LightHit {
    float pdf;
    float t;      // hit distance (INF for the dome and the sun, and on a miss)
    vec3 n;       // geometric normal at the hit
    vec2 uv;
};

const float LIGHT_EDGE_MARGIN = 1e-5;      // relative silhouette margin (see the header)
const float LIGHT_POSITION_ULPS = 2.5e-7;  // float32 error of a point at distance t: ~2 ulp of t

// Whether unit w lies in the cone of 1 - cos(theta_max) = om about unit z: |w - z|^2 = 2 (1 - cos)
// (no cancellation), with the relative margin and ~2 ulp of direction error.
bool in_cone(vec3 w, vec3 z, float om) {
    vec3 wz = w - z;
    return dot(wz, wz) <= 2.0 * om * (1.0 + LIGHT_EDGE_MARGIN) + 4.0 * LIGHT_POSITION_ULPS * sqrt(2.0 * om);
}
const float RECT_OMEGA_MIN = 1e-3;         // solid-angle sampling range of rects ("Rect lights")
const float RECT_OMEGA_MAX = 6.22;
const float HEMISPHERE_PDF = 0.5 / PI;     // uniform hemisphere, 1 / (2 pi)

LightSample no_light_sample() {
    LightSample s;
    s.wi = vec3(0.0, 0.0, 1.0);
    s.dist = 0.0;
    s.x = vec3(0.0);
    s.pdf = 0.0;
    s.n = vec3(0.0, 0.0, 1.0);
    s.delta = false;
    s.uv = vec2(0.0);
    s.le = vec3(-1.0);
    return s;
}

LightHit light_miss() {
    LightHit h;
    h.pdf = 0.0;
    h.t = INF;
    h.n = vec3(0.0, 0.0, 1.0);
    h.uv = vec2(0.0);
    return h;
}

bool light_two_sided(GpuLight l) { return (l.flags & LIGHT_FLAG_TWO_SIDED) != 0u; }
bool light_self(GpuLight l) { return (l.flags & LIGHT_FLAG_SELF) != 0u; }

// Completes an area sample at point x with normal nl and area density 1 / area: converts the pdf to
// solid angle (docs/techniques.md, "Light sampling: conventions").
LightSample area_light_sample(vec3 p, vec3 x, vec3 nl, float area, vec2 uv) {
    LightSample s = no_light_sample();
    vec3 q = x - p;
    float d2 = dot(q, q);
    if (!(d2 > 0.0)) return s;
    float d = sqrt(d2);
    s.wi = q / d;
    float cl = abs(dot(nl, s.wi));
    if (!(cl > 0.0)) return s;
    s.dist = d;
    s.x = x;
    s.n = nl;
    s.uv = uv;
    s.pdf = d2 / (area * cl);
    return s;
}

// Uniform direction on the hemisphere about unit z; pdf = 1 / (2 pi).
vec3 uniform_hemisphere(vec3 z, vec2 u) {
    float ct = u.x;
    float st = sqrt(max(0.0, 1.0 - ct * ct));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    make_basis(z, t, b);
    return normalize(st * cos(phi) * t + st * sin(phi) * b + ct * z);
}

// Completes a direction sample w whose hit h (the light's *_hit(), pdf included) is known: a miss
// is no sample.
LightSample light_sample_from_hit(vec3 p, vec3 w, LightHit h) {
    LightSample s = no_light_sample();
    if (!(h.pdf > 0.0) || h.t == INF) return s;
    s.wi = w;
    s.dist = h.t;
    s.x = p + h.t * w;
    s.n = h.n;
    s.uv = h.uv;
    s.pdf = h.pdf;
    return s;
}

// Whether p (pc = emitter centre - p, h = p's signed distance to the emitter's plane) is close to a
// planar emitter of bounding radius rb about that centre: the planar mixture of the header.
bool planar_mixture(vec3 pc, float h, float rb) {
    return rb >= max(abs(h), length(pc) - rb);
}

// The mixture's pdf from the area pdf of the same direction.
float planar_mixture_pdf(float area_pdf) {
    return 0.5 * (area_pdf + HEMISPHERE_PDF);
}

#endif
