// illum-variants: rq bvh
// Camera rays with a box pixel filter: the AOVs (albedo, normal, depth, emission) and the beauty,
// emission seen directly plus direct lighting at the first hit (glsl/direct/direct.glsl).
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/layout.glsl"
#include "trace/trace.glsl"
#include "direct/direct.glsl"
#include "film/film.glsl"
#include "shared/profile.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(push_constant, scalar) uniform PassBlock { PassConstants pc; };

void main() {
    uvec2 pix;
    uint pixel;
    if (!film_pixel(pc, pix, pixel)) return;
    // The film holds float32 sums of at most 256 samples per pixel: the host adds them exactly in
    // fixed point (src/film/mod.rs), since long float32 running sums round systematically.
    uint slot = film_slot(pix);
    FilmPixel acc = film_load(pc, slot);
    uint rays = 0u;   // traced by this invocation (the rays-per-second figures)
    FilmSamples fs = film_samples(pc, pix, pixel);
    PROF_START();
    for (uint k = 0u; k < fs.count; ++k) {
        uint sample_index = fs.first + k;
        Rng rng;
        vec3 d = film_camera_ray(pc, pix, pixel, sample_index, fs.split, rng);
        vec3 o = frame.cam_origin.xyz;
        PROF(PROF_CAMERA_RAY);
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        rays += 1u;
        PROF(PROF_CAMERA_TRACE);
        vec3 beauty = vec3(0.0);
        vec3 le;   // emission seen directly
        GpuMaterial m;
        Shading sh;
        bool lit = film_camera_hit(h, o, d, acc, le, m, sh);
        PROF(PROF_CAMERA_SHADE);
        if (lit) {
            beauty += film_clamp(direct_lighting(sh, m, rng, rays), acc);
        }
        beauty += le;
        film_add(acc, sample_index, fs.split, beauty, le);
        PROF(PROF_FILM);
    }
    acc.beauty_sq.w += float(rays);
    film_store(pc, slot, acc);
    PROF_END(frame.profile, slot);
}
