// Every shared struct in a buffer, so that glslang emits its member offsets and array stride into
// the SPIR-V; tests/layout.rs compares them with the Rust mirrors in src/layout.rs.
#version 460
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "shared/layout.glsl"
layout(local_size_x = 1) in;
layout(scalar, binding = 0) buffer B0 { Frame frame_v[]; };
layout(scalar, binding = 1) buffer B1 { PassConstants pass_v[]; };
layout(scalar, binding = 2) buffer B2 { GpuVertex vertex_v[]; };
layout(scalar, binding = 3) buffer B3 { GpuInstance instance_v[]; };
layout(scalar, binding = 4) buffer B4 { GpuShape shape_v[]; };
layout(scalar, binding = 5) buffer B5 { GpuLobe lobe_v[]; };
layout(scalar, binding = 6) buffer B6 { GpuMaterial material_v[]; };
layout(scalar, binding = 7) buffer B7 { GpuLight light_v[]; };
layout(scalar, binding = 8) buffer B8 { GpuTexture texture_v[]; };
layout(scalar, binding = 9) buffer B9 { FilmPixel film_v[]; };
layout(scalar, binding = 10) buffer B10 { BvhHeader bvh_header_v[]; };
layout(scalar, binding = 11) buffer B11 { BvhNode bvh_node_v[]; };
layout(scalar, binding = 12) buffer B12 { BvhTriangle bvh_triangle_v[]; };
layout(scalar, binding = 13) buffer B13 { BvhInstance bvh_instance_v[]; };
layout(scalar, binding = 14) buffer B14 { QueryRay query_ray_v[]; };
layout(scalar, binding = 15) buffer B15 { QueryHit query_hit_v[]; };
layout(scalar, binding = 16) buffer B16 { QueryConstants query_constants_v[]; };
layout(scalar, binding = 17) buffer B17 { GpuDomeSampling dome_sampling_v[]; };
layout(scalar, binding = 18) buffer B18 { GpuLightNode light_node_v[]; };
layout(scalar, binding = 19) buffer B19 { RadiosityEntry radiosity_entry_v[]; };
layout(scalar, binding = 20) buffer B20 { RadiosityRecord radiosity_record_v[]; };
layout(scalar, binding = 21) buffer B21 { RadiosityPass radiosity_pass_v[]; };
layout(scalar, binding = 22) buffer B22 { GpuLightTreeNode light_tree_node_v[]; };
layout(scalar, binding = 23) buffer B23 { FullPass full_pass_v[]; };
layout(scalar, binding = 24) buffer B24 { BvhFlat bvh_flat_v[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    frame_v[i + 1] = frame_v[i];
    pass_v[i + 1] = pass_v[i];
    vertex_v[i + 1] = vertex_v[i];
    instance_v[i + 1] = instance_v[i];
    shape_v[i + 1] = shape_v[i];
    lobe_v[i + 1] = lobe_v[i];
    material_v[i + 1] = material_v[i];
    light_v[i + 1] = light_v[i];
    texture_v[i + 1] = texture_v[i];
    film_v[i + 1] = film_v[i];
    light_node_v[i + 1] = light_node_v[i];
    light_tree_node_v[i + 1] = light_tree_node_v[i];
    dome_sampling_v[i + 1] = dome_sampling_v[i];
    bvh_header_v[i + 1] = bvh_header_v[i];
    bvh_node_v[i + 1] = bvh_node_v[i];
    bvh_triangle_v[i + 1] = bvh_triangle_v[i];
    bvh_instance_v[i + 1] = bvh_instance_v[i];
    query_ray_v[i + 1] = query_ray_v[i];
    query_hit_v[i + 1] = query_hit_v[i];
    query_constants_v[i + 1] = query_constants_v[i];
    radiosity_entry_v[i + 1] = radiosity_entry_v[i];
    radiosity_record_v[i + 1] = radiosity_record_v[i];
    radiosity_pass_v[i + 1] = radiosity_pass_v[i];
    full_pass_v[i + 1] = full_pass_v[i];
    bvh_flat_v[i + 1] = bvh_flat_v[i];
}
