// illum-variants: rq bvh
// Camera rays with a box pixel filter: the AOVs (albedo, normal, depth, emission) and the beauty,
// emission seen directly plus direct lighting at the first hit (glsl/shared/direct.glsl).
#version 460
#include "direct.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_FILM) buffer FilmBlock { FilmPixel film[]; };
layout(push_constant, scalar) uniform PassBlock { PassConstants pc; };

void main() {
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= pc.tile.z || local.y >= pc.tile.w) return;
    uvec2 pix = local + pc.tile.xy;
    uint width = frame.width, height = frame.height;
    uint pixel = pix.y * width + pix.x;
    // The film holds float32 sums of at most 256 samples per pixel: the host moves them into
    // float64 sums (src/render/film.rs), since long float32 running sums round systematically.
    FilmPixel acc = film[pixel];
    float clamp_luminance = frame.clamp_luminance;
    uint inject = frame.nan_every;   // test hook, see below
    for (uint k = 0u; k < pc.sample_count; ++k) {
        Rng rng = rng_init(pc.seed_lo, pc.seed_hi, pixel, pc.first_sample + k);
        vec2 film_uv = (vec2(pix) + rng_next2(rng)) / vec2(width, height);
        vec2 ndc = 2.0 * film_uv - 1.0;
        vec3 d = normalize(frame.cam_forward.xyz + ndc.x * frame.cam_right.xyz - ndc.y * frame.cam_up.xyz);
        vec3 o = frame.cam_origin.xyz;
        Hit h = trace_closest(o, d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        g_rays += 1u;
        vec3 beauty = vec3(0.0);
        vec3 le = vec3(0.0);   // emission seen directly
        if (h.kind == HIT_NONE) {
            le = dome_radiance(d);
        } else {
            Surface s = surface_at(h, o, d);
            le = surface_emission(s, d);
            acc.normal += vec4(s.ns, h.t);
            if (s.material != NONE) {
                GpuMaterial m = get_material(s.material);
                Shading sh = shading_at(s, m, d);
                acc.albedo += vec4(sh.albedo, 1.0);
                vec3 direct = direct_lighting(sh, m, rng);
                // Optional firefly clamp (hue-preserving, TECHNIQUES 7.6): biased, off by default.
                // A non-finite value fails the test and is counted below, not hidden.
                float y = luminance(direct);
                if (clamp_luminance > 0.0 && y > clamp_luminance) {
                    direct *= clamp_luminance / y;
                    acc.beauty.w += 1.0;
                }
                beauty += direct;
            } else {
                acc.albedo.w += 1.0;
            }
        }
        beauty += le;
        // Test hook (RenderSettings::inject_non_finite): every n-th sample of each pixel is NaN,
        // so that tests can check the accounting below end to end.
        if (inject != 0u && (pc.first_sample + k) % inject == 0u) beauty.g = uintBitsToFloat(0x7fc00000u);
        // The one place where non-finite sample values are counted, before anything accumulates
        // them; the sample then counts as 0 in the beauty and the emission AOV.
        if (non_finite(beauty)) {
            acc.emission.w += 1.0;
            beauty = vec3(0.0);
            le = vec3(0.0);
        }
        acc.emission.rgb += le;
        acc.beauty.rgb += beauty;
        acc.beauty_sq.rgb += beauty * beauty;
        if (((pc.first_sample + k) & 1u) == 1u) acc.beauty_odd.rgb += beauty;
    }
    acc.beauty_sq.w += float(g_rays);
    film[pixel] = acc;
}
