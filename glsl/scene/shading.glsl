// The shading point of a surface hit (Shading): its frame, with the normals on the viewer's side
// and the tangent anisotropic lobes follow, its offset ray origin and its diffuse albedo. What
// direct lighting, the film and the indirect integrators read of a hit.
#ifndef ILLUM_SHADING_GLSL
#define ILLUM_SHADING_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/scene.glsl"
#include "scene/surface.glsl"

struct Shading {
    vec3 p;        // shading point
    vec3 origin;   // offset ray origin (Waechter & Binder) on the viewer's side
    vec3 ng;       // geometric normal, on the viewer's side
    vec3 n, t, b;  // shading frame, n on the viewer's side
    vec3 v;        // toward the viewer
    vec3 albedo;   // Lambert rho
    uint self_light;   // the light whose surface p lies on (emissive shapes), else NONE
};

// All zero: a loop's per-iteration frame before its hit sets it (path.comp).
Shading no_shading() { return Shading(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), 0u); }

// The shading frame at a surface hit by a ray of direction d. Patches `m` where its parameters
// vary per texel (glTF metallic-roughness).
Shading shading_at(Surface s, inout GpuMaterial m, vec3 d) {
    Shading sh;
    sh.p = s.p;
    sh.v = -d;
    sh.ng = dot(s.ng, d) > 0.0 ? -s.ng : s.ng;
    sh.n = dot(s.ns, sh.ng) < 0.0 ? -s.ns : s.ns;
    sh.origin = offset_ray_origin(s.p, sh.ng);
    sh.self_light = s.light;
    // Tangent: the surface's (mesh tangents, a sphere's pole), else the material's direction,
    // each projected on the tangent plane; else around +Y (so that anisotropic spheres are brushed
    // along latitudes, as with a pole of +Y); else any. The
    // bitangent's handedness is not needed: the distributions are even in the bitangent.
    bool directed = (m.flags & MATERIAL_FLAG_TANGENT_DIR) != 0u;
    vec3 dir = directed ? m.tangent_dir : vec3(0.0, 1.0, 0.0);
    vec3 t = directed ? dir - sh.n * dot(sh.n, dir) : cross(dir, sh.n);
    if (dot(s.tangent, s.tangent) > 0.0) {
        vec3 tn = normalize(s.tangent);
        vec3 tm = tn - sh.n * dot(sh.n, tn);
        if (dot(tm, tm) > 1e-8) t = tm;
    }
    if (dot(t, t) < 1e-8) {
        vec3 b;
        make_basis(sh.n, t, b);
    }
    sh.t = normalize(t);
    sh.b = cross(sh.n, sh.t);
    vec3 tex = texture_lookup(m.diffuse_texture, s.uv).rgb;
    sh.albedo = m.diffuse * tex;
    if ((m.flags & MATERIAL_FLAG_METALLIC_ROUGHNESS) != 0u && m.lobe_count > 0u) {
        // Metallic in B, roughness in G of the metallic-roughness texture (glTF's packing).
        vec4 mr = texture_lookup(m.metallic_roughness_texture, s.uv);
        vec3 base = m.base_metallic.rgb * tex;
        float metallic = clamp(m.base_metallic.w * mr.b, 0.0, 1.0);
        float roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
        sh.albedo = base * (1.0 - metallic);
        m.lobes[0].fresnel0.rgb = mix(vec3(m.dielectric_f0), base, metallic);
        m.lobes[0].alpha = vec2(max(roughness * roughness, 1e-4));
    }
    return sh;
}

#endif
