// Turns a Hit into a shading point: position (rebuilt from the vertices, not o + t d, whose error
// grows with t), geometric and shading normals, uv, material, and the light it belongs to.
#ifndef ILLUM_SURFACE_GLSL
#define ILLUM_SURFACE_GLSL

#include "shared/layout.glsl"
#include "shared/common.glsl"
#include "scene/features.glsl"
#include "scene/scene.glsl"
#include "trace/hit.glsl"
#include "trace/shapes.glsl"

struct Surface {
    vec3 p;
    vec3 ng;         // geometric normal (winding / shape outward side), unit
    vec3 ns;         // shading normal, unit, same hemisphere as ng
    vec2 uv;
    vec3 tangent;    // world-space mesh tangent (interpolated, not unit), or 0 where there is none
    uint material;   // NONE for light shapes
    uint light;      // NONE unless the surface is a light's
};

vec3 xform_point(vec4 m[3], vec3 p) { return vec3(dot(m[0].xyz, p) + m[0].w, dot(m[1].xyz, p) + m[1].w, dot(m[2].xyz, p) + m[2].w); }
vec3 xform_vector(vec4 m[3], vec3 v) { return vec3(dot(m[0].xyz, v), dot(m[1].xyz, v), dot(m[2].xyz, v)); }

// The three vertices of triangle `prim` of an instance's mesh.
void instance_triangle(GpuInstance inst, uint prim, out GpuVertex v0, out GpuVertex v1, out GpuVertex v2) {
    IndexRef indices = IndexRef(frame.indices);
    VertexRef vertices = VertexRef(frame.vertices);
    uint base = inst.first_index + 3u * prim;
    v0 = vertices.v[inst.first_vertex + indices.v[base]];
    v1 = vertices.v[inst.first_vertex + indices.v[base + 1u]];
    v2 = vertices.v[inst.first_vertex + indices.v[base + 2u]];
}

Surface surface_at(Hit h, vec3 o, vec3 d) {
    Surface s;
    s.light = NONE;
    s.uv = vec2(0.0);
    s.tangent = vec3(0.0);
    if (has_feature(FEATURE_MESHES) && h.kind == HIT_TRIANGLE) {
        GpuInstance inst = get_instance(h.instance);
        GpuVertex v0, v1, v2;
        instance_triangle(inst, h.prim, v0, v1, v2);
        vec3 b = vec3(1.0 - h.bary.x - h.bary.y, h.bary);
        vec3 p0 = xform_point(inst.object_to_world, v0.position);
        vec3 p1 = xform_point(inst.object_to_world, v1.position);
        vec3 p2 = xform_point(inst.object_to_world, v2.position);
        s.p = b.x * p0 + b.y * p1 + b.z * p2;
        vec3 ng = cross(p1 - p0, p2 - p0);
        float len = length(ng);
        s.ng = len > 0.0 ? ng / len : -d;
        s.ns = s.ng;
        if ((inst.flags & INSTANCE_FLAG_NORMALS) != 0u) {
            vec3 n = xform_vector(inst.normal_to_world, b.x * v0.normal + b.y * v1.normal + b.z * v2.normal);
            float nl = length(n);
            if (nl > 0.0) s.ns = n / nl;
            if (dot(s.ns, s.ng) < 0.0) s.ng = -s.ng;  // the authored normals define the front side
        }
        if ((inst.flags & INSTANCE_FLAG_UVS) != 0u)
            s.uv = b.x * vec2(v0.u, v0.v) + b.y * vec2(v1.u, v1.v) + b.z * vec2(v2.u, v2.v);
        // Tangents transform as vectors (they lie in the surface), not as normals.
        if ((inst.flags & INSTANCE_FLAG_TANGENTS) != 0u)
            s.tangent = xform_vector(inst.object_to_world, b.x * v0.tangent.xyz + b.y * v1.tangent.xyz + b.z * v2.tangent.xyz);
        s.material = inst.material;
    } else {
        GpuShape sh = get_shape(h.prim);
        s.p = o + h.t * d;
        if (sh.kind == SHAPE_SPHERE) {
            vec3 f = s.p - sh.p0.xyz;
            float fl = safe_length(f);
            s.ng = f / fl;
            // Move onto the sphere along the normal, so that offsets start from the true surface:
            // by the precise signed distance, not to c + r n, which rounds to ulp(|c|) (a unit
            // at r = 1e7, below the ground sphere's surface).
            s.p -= sphere_distance(sh.p0.xyz, sh.p2.xy, s.p, fl) * s.ng;
            s.uv = direction_to_latlong(s.ng, vec2(1.0, 0.0));
            // Tangent along the latitudes about the pole: Mitsuba's and pbrt's dp/du.
            if ((sh.flags & SHAPE_FLAG_POLE) != 0u) s.tangent = cross(sh.p1.xyz, s.ng);
        } else if (sh.kind == SHAPE_RECT) {
            s.ng = normalize(cross(sh.p1.xyz, sh.p2.xyz));
            vec3 q = s.p - sh.p0.xyz;
            s.uv = vec2(dot(q, sh.p1.xyz) / dot(sh.p1.xyz, sh.p1.xyz), dot(q, sh.p2.xyz) / dot(sh.p2.xyz, sh.p2.xyz)) + 0.5;
        } else {
            s.ng = sh.p1.xyz;
            vec3 q = s.p - sh.p0.xyz;
            vec3 bt = cross(sh.p1.xyz, sh.p2.xyz);
            s.uv = vec2(dot(q, sh.p2.xyz), dot(q, bt)) / (2.0 * sh.p0.w) + 0.5;
        }
        s.ns = s.ng;
        s.material = sh.material;
        s.light = sh.light;
    }
    return s;
}

// Radiance leaving surface s toward -d (d = ray direction), from an emissive material or a light.
vec3 surface_emission(Surface s, vec3 d) {
    bool front = dot(s.ng, d) < 0.0;
    if (s.light != NONE) {
        GpuLight l = get_light(s.light);
        if (!front && (l.flags & LIGHT_FLAG_TWO_SIDED) == 0u) return vec3(0.0);
        return l.radiance * texture_lookup(l.texture, s.uv).rgb;
    }
    GpuMaterial m = get_material(s.material);
    if (!front && (m.flags & MATERIAL_FLAG_TWO_SIDED) == 0u) return vec3(0.0);
    return m.emission * texture_lookup(m.emission_texture, s.uv).rgb;
}

#endif
