// illum-variants: rq bvh
// Primary rays with a box pixel filter, writing the AOVs (albedo, normal, depth, emission) and a
// preview beauty: emission plus Lambert direct lighting, one light sample per light with a shadow
// ray (dome: cosine-sampled). The direct-lighting integrator replaces the preview beauty.
#version 460
#include "surface.glsl"

layout(local_size_x = WORKGROUP_X, local_size_y = WORKGROUP_Y) in;
layout(scalar, binding = BINDING_FILM) buffer FilmBlock { FilmPixel film[]; };
layout(push_constant, scalar) uniform PassBlock { PassConstants pc; };

// One-sample Lambert direct lighting from light `li` (radiance over pdf, times cos, times V).
vec3 preview_light(uint li, Surface s, inout Rng rng) {
    GpuLight l = get_light(li);
    vec2 u = rng_next2(rng);
    vec3 n = s.ns;
    vec3 wi;
    float dist;
    vec3 L_over_pdf;
    if (has_feature(FEATURE_AREA_LIGHTS) && (l.kind == LIGHT_RECT || l.kind == LIGHT_DISK)) {
        vec3 x, nl;
        vec2 tuv;
        if (l.kind == LIGHT_RECT) {
            x = l.p0.xyz + (u.x - 0.5) * l.p1.xyz + (u.y - 0.5) * l.p2.xyz;
            nl = normalize(cross(l.p1.xyz, l.p2.xyz));
            tuv = u;
        } else {
            vec2 dk = concentric_disk(u);
            x = l.p0.xyz + l.p0.w * (dk.x * l.p2.xyz + dk.y * cross(l.p1.xyz, l.p2.xyz));
            nl = l.p1.xyz;
            tuv = 0.5 * dk + 0.5;
        }
        vec3 dv = x - s.p;
        float d2 = dot(dv, dv);
        dist = sqrt(d2);
        wi = dv / dist;
        float cl = -dot(nl, wi);
        if ((l.flags & LIGHT_FLAG_TWO_SIDED) != 0u) cl = abs(cl);
        if (cl <= 0.0 || d2 == 0.0) return vec3(0.0);
        L_over_pdf = l.radiance * texture_lookup(l.texture, tuv).rgb * (l.area * cl / d2);
    } else if (has_feature(FEATURE_AREA_LIGHTS) && l.kind == LIGHT_SPHERE) {
        // Cone sampling of the visible cap with the stable 1 - cos(theta_max) (TECHNIQUES.md 2.2).
        vec3 dc = l.p0.xyz - s.p;
        float dd2 = dot(dc, dc);
        float r2 = l.p0.w * l.p0.w;
        if (dd2 <= r2) return vec3(0.0);
        float s2max = r2 / dd2;
        float cmax = sqrt(max(0.0, 1.0 - s2max));
        float om = s2max / (1.0 + cmax);
        float omc = u.x * om;
        float ct = 1.0 - omc;
        float st = sqrt(max(0.0, omc * (2.0 - omc)));
        float phi = 2.0 * PI * u.y;
        float dlen = sqrt(dd2);
        vec3 z = dc / dlen, t, b;
        make_basis(z, t, b);
        wi = st * cos(phi) * t + st * sin(phi) * b + ct * z;
        dist = (dd2 - r2) / (dlen * ct + sqrt(max(0.0, dd2 * (s2max - st * st))));
        L_over_pdf = l.radiance * (2.0 * PI * om);
    } else if (has_feature(FEATURE_SUN) && l.kind == LIGHT_SUN) {
        // Uniform cone about the sun direction; delta light when the cone is empty.
        float om = l.p1.x;
        if (om <= 0.0) {
            wi = l.p0.xyz;
            L_over_pdf = l.radiance;
        } else {
            float omc = u.x * om;
            float st = sqrt(max(0.0, omc * (2.0 - omc)));
            float phi = 2.0 * PI * u.y;
            vec3 t, b;
            make_basis(l.p0.xyz, t, b);
            wi = st * cos(phi) * t + st * sin(phi) * b + (1.0 - omc) * l.p0.xyz;
            // L = E / (pi sin^2 theta_s), pdf = 1 / (2 pi om): L / pdf = E 2 om / sin^2 theta_s.
            float s2 = om * (2.0 - om);
            L_over_pdf = l.radiance * (2.0 * om / s2);
        }
        dist = INF;
    } else if (has_feature(FEATURE_DOME) && l.kind == LIGHT_DOME) {
        vec3 t, b;
        make_basis(n, t, b);
        vec3 c = cosine_hemisphere(u);
        wi = c.x * t + c.y * b + c.z * n;
        dist = INF;
        // Cosine sampling: f cos / pdf = albedo, so return L * pi / cos to cancel below.
        float cw = max(dot(wi, n), 1e-8);
        L_over_pdf = dome_radiance(wi) * (PI / cw);
    } else {
        return vec3(0.0);
    }
    float cs = dot(wi, n);
    if (cs <= 0.0 || dot(wi, s.ng) <= 0.0) return vec3(0.0);
    vec3 o = offset_ray_origin(s.p, s.ng);
    float tmax = dist == INF ? INF : dist * (1.0 - 1e-4);
    if (trace_occluded(o, wi, 0.0, tmax, MASK_GEOMETRY)) return vec3(0.0);
    return L_over_pdf * cs * INV_PI;
}

void main() {
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= pc.tile.z || local.y >= pc.tile.w) return;
    uvec2 pix = local + pc.tile.xy;
    uint width = frame.size.x, height = frame.size.y;
    uint pixel = pix.y * width + pix.x;
    FilmPixel acc = film[pixel];
    for (uint k = 0u; k < pc.sample_count; ++k) {
        Rng rng = rng_init(pc.seed_lo, pc.seed_hi, pixel, pc.first_sample + k);
        vec2 film_uv = (vec2(pix) + rng_next2(rng)) / vec2(width, height);
        vec2 ndc = 2.0 * film_uv - 1.0;
        vec3 d = normalize(frame.cam_forward.xyz + ndc.x * frame.cam_right.xyz - ndc.y * frame.cam_up.xyz);
        Hit h = trace_closest(vec3(0.0), d, 0.0, INF, MASK_GEOMETRY | MASK_LIGHTS);
        vec3 beauty = vec3(0.0);
        if (h.kind == HIT_NONE) {
            beauty = dome_radiance(d);
            acc.emission.rgb += beauty;
        } else {
            Surface s = surface_at(h, vec3(0.0), d);
            vec3 le = surface_emission(s, d);
            beauty = le;
            acc.emission.rgb += le;
            acc.normal += vec4(s.ns, h.t);
            if (s.material != NONE) {
                GpuMaterial m = get_material(s.material);
                vec3 albedo = m.diffuse * texture_lookup(m.diffuse_texture, s.uv).rgb;
                acc.albedo += vec4(albedo, 1.0);
                // Shade the side the camera sees.
                if (dot(s.ng, d) > 0.0) { s.ng = -s.ng; s.ns = -s.ns; }
                vec3 direct = vec3(0.0);
                for (uint li = 0u; li < frame.size.z; ++li) direct += preview_light(li, s, rng);
                beauty += albedo * direct;
            } else {
                acc.albedo.w += 1.0;
            }
        }
        if (non_finite(beauty)) {
            acc.emission.w += 1.0;
            beauty = vec3(0.0);
        }
        acc.beauty.rgb += beauty;
        acc.beauty_sq.rgb += beauty * beauty;
        if (((pc.first_sample + k) & 1u) == 1u) acc.beauty_odd.rgb += beauty;
    }
    film[pixel] = acc;
}
