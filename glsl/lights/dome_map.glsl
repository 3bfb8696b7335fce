// How a dome light's map covers the sphere of directions: its map coordinates uv in [0, 1]^2 (the
// image's top-left corner at (0, 0)), per convention (GpuLight.flags; docs/scene-format.md).
// Every convention first undoes the dome's rotation about +Y (GpuLight.p0.xy = cos, sin).
// * illum (neither flag): lat-long, u = atan2(x, -z) / 2pi + 1/2 (u = 1/2 at -Z, growing toward
//   +X), v = theta / pi from +Y; texel centres at ((i + 1/2) / W, (j + 1/2) / H); the texture's
//   own filter and wrap modes.
// * Mitsuba 3 `envmap` (LIGHT_FLAG_DOME_MITSUBA): lat-long with u = atan2(x, -z) / 2pi (u = 0 at
//   -Z: half a turn from illum's), v = theta / pi; column i centred at u = (i + 1/2) / W, row j at
//   v = j / (H - 1) (the first and last rows on the poles); bilinear, periodic in u, clamped in v.
// * pbrt-v4 `imageinfinite` (LIGHT_FLAG_DOME_PBRT): the equal-area octahedral square of a square
//   map (Clarberg 2008, pbrt's EqualAreaSphereToSquare), in pbrt's light frame, whose +Z is
//   illum's +Y (the usual Z-up to Y-up conversion: pbrt (x, y, z) = illum (x, -z, y)); nearest
//   texel, as pbrt looks it up.
#ifndef ILLUM_DOME_MAP_GLSL
#define ILLUM_DOME_MAP_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"

bool dome_is_mitsuba(GpuLight l) { return (l.flags & LIGHT_FLAG_DOME_MITSUBA) != 0u; }
bool dome_is_pbrt(GpuLight l) { return (l.flags & LIGHT_FLAG_DOME_PBRT) != 0u; }

// The dome's rotation about +Y: world to map frame, and back.
vec3 dome_to_map_frame(GpuLight l, vec3 d) {
    vec2 r = l.p0.xy;
    return vec3(r.x * d.x - r.y * d.z, d.y, r.y * d.x + r.x * d.z);
}
vec3 dome_from_map_frame(GpuLight l, vec3 d) {
    vec2 r = l.p0.xy;
    return vec3(r.x * d.x + r.y * d.z, d.y, -r.y * d.x + r.x * d.z);
}

// pbrt-v4's EqualAreaSphereToSquare with an exact atan and 1 - |z| = (x^2 + y^2) / (1 + |z|)
// (no cancellation at the centre).
vec2 equal_area_sphere_to_square(vec3 d) {
    vec3 a = abs(d);
    float r = sqrt((a.x * a.x + a.y * a.y) / (1.0 + a.z));
    float big = max(a.x, a.y), small = min(a.x, a.y);
    float phi = big == 0.0 ? 0.0 : atan2_accurate(small, big) * (2.0 * INV_PI);
    if (a.x < a.y) phi = 1.0 - phi;
    float v = phi * r;
    float u = r - v;
    if (d.z < 0.0) {
        float t = u;
        u = 1.0 - v;
        v = 1.0 - t;
    }
    u = d.x < 0.0 ? -u : u;
    v = d.y < 0.0 ? -v : v;
    return 0.5 * vec2(u, v) + 0.5;
}

// pbrt-v4's EqualAreaSquareToSphere.
vec3 equal_area_square_to_sphere(vec2 p) {
    float u = 2.0 * p.x - 1.0, v = 2.0 * p.y - 1.0;
    float up = abs(u), vp = abs(v);
    float sd = 1.0 - (up + vp);
    float r = 1.0 - abs(sd);
    float phi = (r == 0.0 ? 1.0 : (vp - up) / r + 1.0) * (0.25 * PI);
    float z = sd < 0.0 ? -(1.0 - r * r) : 1.0 - r * r;
    float s = r * sqrt(max(0.0, 2.0 - r * r));
    return vec3((u < 0.0 ? -1.0 : 1.0) * cos(phi) * s, (v < 0.0 ? -1.0 : 1.0) * sin(phi) * s, z);
}

// Map coordinates of world direction d.
vec2 dome_uv(GpuLight l, vec3 d) {
    vec3 m = dome_to_map_frame(l, d);
    if (dome_is_pbrt(l)) return equal_area_sphere_to_square(vec3(m.x, -m.z, m.y));
    vec2 uv = direction_to_latlong(m, vec2(1.0, 0.0));
    if (dome_is_mitsuba(l)) uv.x = uv.x >= 0.5 ? uv.x - 0.5 : uv.x + 0.5;
    return uv;
}

// World direction of map coordinates uv, and the solid angle per unit map area there (dω / du dv:
// 2 pi^2 sin(theta) for lat-long maps, 4 pi for the equal-area square); 0 at a lat-long pole.
vec3 dome_direction(GpuLight l, vec2 uv, out float jacobian) {
    if (dome_is_pbrt(l)) {
        jacobian = 4.0 * PI;
        vec3 p = equal_area_square_to_sphere(uv);
        return dome_from_map_frame(l, normalize(vec3(p.x, p.z, -p.y)));
    }
    if (dome_is_mitsuba(l)) uv.x += 0.5;
    float theta = PI * uv.y;
    float st = sin(theta);
    jacobian = 2.0 * PI * PI * st;
    return dome_from_map_frame(l, normalize(latlong_to_direction(uv, st, cos(theta), vec2(1.0, 0.0))));
}

// Solid angle per unit map area in direction d (see dome_direction).
float dome_jacobian(GpuLight l, vec3 d) {
    // sin(theta) of a lat-long map = the distance from the Y axis, which the rotation keeps.
    return dome_is_pbrt(l) ? 4.0 * PI : 2.0 * PI * PI * length(d.xz);
}

// Offset along u of the sampling cells (GpuDomeSampling): Mitsuba's cells lie between texel
// centres, the others' are the texels.
float dome_cell_offset(GpuLight l, uint width) { return dome_is_mitsuba(l) ? 0.5 / float(width) : 0.0; }

#endif
