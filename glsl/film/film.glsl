// The per-sample film bookkeeping of the film kernels (glsl/direct/primary.comp,
// glsl/indirect/{full,path}.comp): the camera ray, the camera hit's AOVs, the firefly clamp, the
// non-finite count and the sums with their half-buffer (src/film/mod.rs reads them). One copy,
// so the kernels' films agree by construction.
#ifndef ILLUM_FILM_GLSL
#define ILLUM_FILM_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/scene.glsl"
#include "scene/surface.glsl"
#include "scene/shading.glsl"
#include "trace/hit.glsl"
#include "lights/lights.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer PixelEndRef { uint v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer PixelOrderRef { uint v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 16) buffer FilmRef { FilmPixel v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 16) buffer AovRef { vec4 v[]; };

// The invocation's y in its dispatch, the workgroup rows interleaved by `row_step`
// (PassConstants.row_step; 0 or 1: in order): lavapipe gives each thread an equal contiguous
// range of workgroups (src/render/film_kernel.rs, interleaves_rows).
uint interleaved_invocation_y(uint row_step) {
    if (row_step <= 1u) return gl_GlobalInvocationID.y;
    return (gl_WorkGroupID.y * row_step) % gl_NumWorkGroups.y * WORKGROUP_Y + gl_LocalInvocationID.y;
}

// The invocation's pixel in dispatch p: of its tile, or with p.order entry p.tile.x + k of
// Frame.pixel_order (adaptive sampling packs the pixels still sampling, so that no lane idles
// beside a pixel that takes many more samples), the rows interleaved by p.row_step. False when
// the invocation has none.
bool film_pixel(PassConstants p, out uvec2 pix, out uint pixel) {
    uvec2 local = uvec2(gl_GlobalInvocationID.x, interleaved_invocation_y(p.row_step));
    if (local.x >= p.tile.z || local.y >= p.tile.w) return false;
    if (p.order != 0u) {
        uint k = local.y * p.tile.z + local.x;
        if (k >= p.tile.y) return false;
        pixel = PixelOrderRef(frame.pixel_order).v[p.tile.x + k];
        pix = uvec2(pixel % frame.width, pixel / frame.width);
        return true;
    }
    pix = local + p.tile.xy;
    pixel = pix.y * frame.width + pix.x;
    return true;
}

// Where pixel pix's sums lie in the device film (and its AOV planes): the film covers the window
// Frame.film_x0, film_y0, film_width (the job's pixels, with adaptive sampling its pilot's).
uint film_slot(uvec2 pix) {
    return (pix.y - frame.film_y0) * frame.film_width + (pix.x - frame.film_x0);
}

// Film slot `slot`'s sums in pass p's device film, and their write-back (one invocation owns a
// pixel: no atomics). By address (PassConstants.film_address says why).
FilmPixel film_load(PassConstants p, uint slot) { return FilmRef(p.film_address).v[slot]; }
void film_store(PassConstants p, uint slot, FilmPixel acc) { FilmRef(p.film_address).v[slot] = acc; }

// AOV plane k of `planes` at film slot `slot` (layout.glsl, BINDING_AOVS), and its write-back.
vec4 aov_load(PassConstants p, uint slot, uint planes, uint k) {
    return AovRef(p.aovs_address).v[slot * planes + k];
}
void aov_store(PassConstants p, uint slot, uint planes, uint k, vec4 v) {
    AovRef(p.aovs_address).v[slot * planes + k] = v;
}

// The samples of pass p that pixel `pixel` takes: all of them, or with adaptive sampling those
// below the index at which it stops (src/render/adaptive.rs decides it).
uint film_sample_count(PassConstants p, uint pixel) {
    if (frame.pixel_ends == 0ul) return p.sample_count;
    uint end = PixelEndRef(frame.pixel_ends).v[pixel];
    return end <= p.first_sample ? 0u : min(p.sample_count, end - p.first_sample);
}

// Pixel pix's samples in pass p, in its own index space: [first, first + count), two camera
// sequences alternating where `split` (Frame.witness). With a witness period M > 1 a witness
// pixel takes both sequences' sample s of the pass (indices 2s and 2s + 1), the others the first
// sequence's alone: whole workgroups, so no SIMD group mixes the two (src/film/split.rs).
struct FilmSamples { uint first; uint count; bool split; };
FilmSamples film_samples(PassConstants p, uvec2 pix, uint pixel) {
    uint n = film_sample_count(p, pixel);
    uint period = frame.witness & 0xffffu;
    if (period <= 1u) return FilmSamples(p.first_sample, n, true);
    uvec2 b = pix / uvec2(WORKGROUP_X, WORKGROUP_Y);
    if ((b.x + WITNESS_ROW_STEP * b.y + (frame.witness >> 16u)) % period != 0u) return FilmSamples(p.first_sample, n, false);
    return FilmSamples(2u * p.first_sample, 2u * n, true);
}

// Direction of the camera ray through film position film_uv in [0,1]^2.
vec3 camera_direction(vec2 film_uv) {
    vec2 ndc = 2.0 * film_uv - 1.0;
    return normalize(frame.cam_forward.xyz + ndc.x * frame.cam_right.xyz - ndc.y * frame.cam_up.xyz);
}

// Sample `sample_index` of pixel pix in pass p (of its FilmSamples): its random numbers and its
// camera ray's direction d (from frame.cam_origin).
vec3 film_camera_ray(PassConstants p, uvec2 pix, uint pixel, uint sample_index, bool split, out Rng rng) {
    rng = rng_init_camera(p.seed_lo, p.seed_hi, pixel, sample_index, split);
    vec2 film_uv = (vec2(pix) + rng_next2(rng)) / vec2(frame.width, frame.height);
    return camera_direction(film_uv);
}

// The camera hit h's AOVs, added to acc, and the emission seen directly (the dome's on a miss),
// given its surface s and, where `material`, its shading sh.
void film_camera_aovs(Hit h, Surface s, bool material, Shading sh, vec3 d, inout FilmPixel acc,
                      out vec3 le) {
    if (h.kind == HIT_NONE) {
        le = dome_radiance(d);
        return;
    }
    le = surface_emission(s, d);
    acc.normal += vec4(s.ns, h.t);
    if (material) acc.albedo += vec4(sh.albedo, 1.0);
    else acc.albedo.w += 1.0;
}

// The camera hit h of ray (o, d): adds its AOVs to acc and returns the emission seen directly
// (the dome's on a miss). True when the hit has a material: then m and sh are its shading.
bool film_camera_hit(Hit h, vec3 o, vec3 d, inout FilmPixel acc, out vec3 le, out GpuMaterial m,
                     out Shading sh) {
    Surface s;
    bool material = false;
    if (h.kind != HIT_NONE) {
        s = surface_at(h, o, d);
        if (s.material != NONE) {
            m = get_material(s.material);
            sh = shading_at(s, m, d);
            material = true;
        }
    }
    film_camera_aovs(h, s, material, sh, d, acc, le);
    return material;
}

// Optional firefly clamp of the camera hit's direct lighting (hue-preserving; docs/techniques.md,
// "Non-finite samples and the firefly clamp"): biased, off by default; acc.beauty.w counts the
// samples it reduced. A non-finite value is not hidden here: film_add counts it.
vec3 film_clamp(vec3 direct, inout FilmPixel acc) {
    float clamp_luminance = frame.clamp_luminance;
    float y = luminance(direct);
    if (clamp_luminance > 0.0 && y > clamp_luminance) {
        direct *= clamp_luminance / y;
        acc.beauty.w += 1.0;
    }
    return direct;
}

// Adds sample_index `sample_index`'s beauty and directly seen emission le to acc. The one place where
// non-finite sample_index values are counted, before anything accumulates them: such a sample_index counts as
// 0 (beauty, emission and the caller's AOVs, which it skips when this returns false).
bool film_add(inout FilmPixel acc, uint sample_index, bool split, vec3 beauty, vec3 le) {
    // Test hook (RenderSettings::inject_non_finite): every n-th sample_index of each pixel is NaN, so
    // that tests can check this accounting end to end.
    acc.beauty_odd.w += 1.0;
    uint inject = frame.nan_every;
    if (inject != 0u && sample_index % inject == 0u) beauty.g = uintBitsToFloat(0x7fc00000u);
    bool finite = !non_finite(beauty);
    if (!finite) {
        acc.emission.w += 1.0;
        beauty = le = vec3(0.0);
    }
    acc.emission.rgb += le;
    acc.beauty.rgb += beauty;
    acc.beauty_sq.rgb += beauty * beauty;
    if (split && (sample_index & 1u) == 1u) acc.beauty_odd.rgb += beauty;
    return finite;
}

#endif
