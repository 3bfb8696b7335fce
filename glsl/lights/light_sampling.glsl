// Light sampling: for every light kind a sampler and the pdf() of an arbitrary direction, with
// pdf() equal to the density the sampler produces (what MIS needs: docs/techniques.md,
// "Light sampling: conventions"; one section per kind below, from "Rect lights" to
// "Dome importance sampling").
//
// Conventions:
// * p is the shading point (camera-relative world space, like GpuLight). Directions are unit.
// * Every pdf is per steradian at p and independent of the radiance. pdf == 0 in a LightSample means
//   "no sample" (p behind a one-sided emitter, inside a one-sided sphere, in the plane of a rect...):
//   it contributes 0 and still counts in the light's sample count N_L.
// * One-sided emitters (rect, disk, triangle, sphere seen from inside) emit toward their normal only,
//   unless LIGHT_FLAG_TWO_SIDED: from behind, sample_*() returns no sample and light_pdf() is 0.
// * Directions on an emitter's silhouette (edges, rims, cone boundaries) are accepted with a margin
//   of 1e-5 of the emitter's size plus ~2 ulp of the hit distance, so that float rounding never
//   makes pdf() 0 for a direction the sampler produced. The extra support has relative measure
//   ~1e-5 (the emitter's own radiance lookup decides whether such a ray hits).
// * LightSample.n is the emitter's geometric normal at x (not flipped toward p); the emitted side
//   is the one with dot(n, -wi) > 0. LightSample.uv follows glsl/scene/surface.glsl's uv of the
//   light's shape (rect: (0,0) at centre - u/2 - v/2; disk: 0.5 + local xy / (2R); sphere: lat-long
//   of the outward normal), the dome's lat-long uv, and barycentrics (b1, b2) for triangles.
//
// Samplers:
// * rect (p0 centre, p1/p2 full edges): solid-angle sampling (Urena et al. 2013, spherical
//   rectangle) when its solid angle Omega is in [1e-3, 6.22] sr, with Omega from two Van Oosterom-
//   Strackee triangles whose triple product comes from the light's own edges (float32-robust,
//   "Rect lights"); area sampling below 1e-3 sr; above 6.22 sr (a rect that nearly encloses p's
//   hemisphere) uniform sampling of the hemisphere facing the rect, a direction that misses it being
//   no sample (>= 99% hit). pdf() takes the same decision from the same Omega.
// * sphere (p0 centre, radius): uniform cone of the visible cap with the stable 1 - cos(theta_max)
//   ("Sphere lights"); from inside (two-sided only) uniform area sampling.
// * disk (p0 centre, radius; p1 normal; p2 tangent): area sampling, concentric map; near a
//   disk large for its distance, the planar mixture below.
// * sun (p0 direction, cos(theta_max); p1.x = 1 - cos(theta_max)): uniform cone; delta light
//   (delta = true, pdf = 1, no MIS) when p1.x == 0 ("Sun lights").
// * triangle (LIGHT_TRIANGLE: p0 vertex 0, p1/p2 edges to vertices 1 and 2): uniform area sampling
//   (b1, b2) = sqrt(u1) (1 - u2, u2). Chosen over spherical-triangle sampling for robustness (no
//   angle differences; the same float32 pitfalls as the rect's angle sum); MIS with BRDF samples
//   covers the grazing configurations where area sampling is noisy; near a triangle large for its
//   distance, the planar mixture below.
// * Planar mixture (disk, triangle): where the emitter's bounding radius rb about its centre is at
//   least p's distance to the emitter's plane and to its bounding sphere (p close to a large
//   emitter: a radius-20 disk 1 unit above), area sampling puts few samples where most light comes
//   from and gives fireflies (weights up to area / d^2). There the sampler draws half its samples by
//   area and half uniformly over the hemisphere facing the emitter (a miss is no sample); pdf =
//   (p_area + 1 / (2 pi)) / 2 bounds every weight by 4 pi times the integrand. The decision
//   depends on p and the light only, and pdf() repeats it.
// * dome: piecewise-constant sampling of the map's cells ("Dome importance sampling";
//   glsl/lights/dome_map.glsl) with the marginal/conditional CDFs of GpuDomeSampling (searched
//   from guide tables), then a uniform position inside the cell:
//   pdf = P(row) P(cell | row) W H / (dω / du dv), 2 pi^2 sin(theta) for lat-long maps, 4 pi for
//   the equal-area square. Probabilities are differences of the stored float CDFs, which is
//   exactly the mass the binary search gives each cell. With the Mitsuba convention and the map's
//   texels given (GpuDomeSampling.texels) the sampler reads its cell's corners once, for the
//   cell's shape and the sample's radiance (LightSample.le). Without a table (width == 0) the dome is
//   sampled uniformly (pdf = 1 / (4 pi)). LightSample.uv / LightHit.uv are map coordinates.
//   Defensive mixture (GpuDomeSampling.defensive = a > 0, under control variates): a share a of
//   the samples is uniform over the sphere, pdf = a / (4 pi) + (1 - a) p_table, positive in every
//   direction (the SH9 control is nonzero where the table's pdf is 0); a = 0 is the table alone,
//   bit for bit.
#ifndef ILLUM_LIGHT_SAMPLING_GLSL
#define ILLUM_LIGHT_SAMPLING_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "lights/light_sample.glsl"
#include "lights/area_lights.glsl"
#include "lights/infinite_lights.glsl"

// ---------------------------------------------------------------------------------------------
// Any light. `dome` is only read for LIGHT_DOME. Each kind behind its feature bit: a scene's
// kernel holds the samplers of the kinds it has (10% less LLVM time for a rect and a dome).

// n: the shading normal at p (a constant dome samples the cosine about it), or 0 (no shading
// point: uniform over the sphere).
LightSample sample_light(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 n, vec2 u) {
    if (light_is(l, LIGHT_RECT)) return sample_rect(l, p, u);
    if (light_is(l, LIGHT_SPHERE)) return sample_sphere(l, p, u);
    if (light_is(l, LIGHT_DISK)) return sample_disk(l, p, u);
    if (light_is(l, LIGHT_SUN)) return sample_sun(l, u);
    if (light_is(l, LIGHT_TRIANGLE)) return sample_triangle(l, p, u);
    if (light_is(l, LIGHT_DOME)) return sample_dome(l, dome, n, u);
    return no_light_sample();
}

LightHit light_hit(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 n, vec3 w) {
    if (light_is(l, LIGHT_RECT)) return rect_hit(l, p, w);
    if (light_is(l, LIGHT_SPHERE)) return sphere_hit(l, p, w);
    if (light_is(l, LIGHT_DISK)) return disk_hit(l, p, w);
    if (light_is(l, LIGHT_SUN)) return sun_hit(l, w);
    if (light_is(l, LIGHT_TRIANGLE)) return triangle_hit(l, p, w);
    if (light_is(l, LIGHT_DOME)) return dome_hit(l, dome, n, w);
    return light_miss();
}

// The solid-angle density with which sample_light() produces w (0 where it never does).
float light_pdf(GpuLight l, GpuDomeSampling dome, vec3 p, vec3 n, vec3 w) {
    return light_hit(l, dome, p, n, w).pdf;
}

#endif
