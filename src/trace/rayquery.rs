//! Hardware ray-query acceleration structures: one BLAS per mesh, one of AABBs per group of
//! analytic shapes, a TLAS over the instances. Scratch addresses honour the device's
//! minAccelerationStructureScratchOffsetAlignment; BLASes are compacted.

use crate::error::{Error, Result};
use crate::vk::VkResultExt;
use crate::vk::{Buffer, Context, MemoryLocation};
use ash::vk;
use std::time::Instant;

/// Triangles read straight from the scene's vertex and index buffers.
pub struct TriangleGeometry {
    pub vertex_address: u64,
    pub vertex_stride: u64,
    pub vertex_count: u32,
    pub index_address: u64,
    pub triangle_count: u32,
}

/// Axis-aligned boxes (vk::AabbPositionsKHR, 24 bytes each) of procedural primitives.
pub struct AabbGeometry {
    pub aabb_address: u64,
    pub count: u32,
}

pub enum BlasInput {
    Triangles(TriangleGeometry),
    Aabbs(AabbGeometry),
}

pub struct TlasInstance {
    pub blas: usize,
    /// Rows of the 3x4 object-to-world matrix.
    pub transform: [[f32; 4]; 3],
    /// 24 bits, read by the kernels as the instance custom index.
    pub custom_index: u32,
    pub mask: u8,
}

pub use super::BuildStats;

pub struct AccelerationStructure {
    ctx: Context,
    pub handle: vk::AccelerationStructureKHR,
    pub address: u64,
    _buffer: Buffer,
}

impl Drop for AccelerationStructure {
    fn drop(&mut self) {
        if let Some(a) = &self.ctx.accel {
            // SAFETY: no pending work uses it (every submission is waited for).
            unsafe { a.destroy_acceleration_structure(self.handle, None) };
        }
    }
}

pub struct RayQueryScene {
    _blases: Vec<AccelerationStructure>,
    pub tlas: AccelerationStructure,
    _instances: Buffer,
    instance_count: usize,
    pub stats: BuildStats,
}

fn accel(ctx: &Context) -> Result<&ash::khr::acceleration_structure::Device> {
    ctx.accel.as_ref().ok_or_else(|| {
        Error::Gpu(crate::vk::Error::Unsupported {
            device: ctx.info().name.clone(),
            what: "it has no VK_KHR_acceleration_structure".into(),
        })
    })
}

fn create_as(
    ctx: &Context,
    ty: vk::AccelerationStructureTypeKHR,
    size: u64,
    name: &str,
) -> Result<AccelerationStructure> {
    let buffer = ctx.create_buffer(
        name,
        size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR,
        MemoryLocation::GpuOnly,
    )?;
    let a = accel(ctx)?;
    // SAFETY: the buffer outlives the structure (both are owned by the returned value).
    unsafe {
        let handle = a
            .create_acceleration_structure(
                &vk::AccelerationStructureCreateInfoKHR::default()
                    .buffer(buffer.buffer)
                    .size(size)
                    .ty(ty),
                None,
            )
            .vk("vkCreateAccelerationStructureKHR")?;
        let address = a.get_acceleration_structure_device_address(
            &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                .acceleration_structure(handle),
        );
        Ok(AccelerationStructure {
            ctx: ctx.clone(),
            handle,
            address,
            _buffer: buffer,
        })
    }
}

/// A scratch buffer whose device address is rounded up to the device's alignment.
fn scratch(ctx: &Context, size: u64) -> Result<(Buffer, u64)> {
    let align = ctx.scratch_alignment;
    let b = ctx.create_buffer(
        "acceleration structure scratch",
        size + align,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryLocation::GpuOnly,
    )?;
    let addr = b.address.div_ceil(align) * align;
    Ok((b, addr))
}

fn geometry(input: &BlasInput) -> (vk::AccelerationStructureGeometryKHR<'static>, u32) {
    match input {
        BlasInput::Triangles(t) => (
            vk::AccelerationStructureGeometryKHR::default()
                .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
                .flags(vk::GeometryFlagsKHR::OPAQUE)
                .geometry(vk::AccelerationStructureGeometryDataKHR {
                    triangles: vk::AccelerationStructureGeometryTrianglesDataKHR::default()
                        .vertex_format(vk::Format::R32G32B32_SFLOAT)
                        .vertex_data(vk::DeviceOrHostAddressConstKHR {
                            device_address: t.vertex_address,
                        })
                        .vertex_stride(t.vertex_stride)
                        .max_vertex(t.vertex_count.saturating_sub(1))
                        .index_type(vk::IndexType::UINT32)
                        .index_data(vk::DeviceOrHostAddressConstKHR {
                            device_address: t.index_address,
                        }),
                }),
            t.triangle_count,
        ),
        BlasInput::Aabbs(a) => (
            vk::AccelerationStructureGeometryKHR::default()
                .geometry_type(vk::GeometryTypeKHR::AABBS)
                .flags(vk::GeometryFlagsKHR::OPAQUE)
                .geometry(vk::AccelerationStructureGeometryDataKHR {
                    aabbs: vk::AccelerationStructureGeometryAabbsDataKHR::default()
                        .data(vk::DeviceOrHostAddressConstKHR {
                            device_address: a.aabb_address,
                        })
                        .stride(24),
                }),
            a.count,
        ),
    }
}

/// The bottom levels of `inputs` (built, then compacted) and the top level over `instances`.
pub fn build(
    ctx: &Context,
    inputs: &[BlasInput],
    instances: &[TlasInstance],
) -> Result<RayQueryScene> {
    accel(ctx)?;
    let mut stats = BuildStats {
        blas_count: inputs.len(),
        triangles: inputs
            .iter()
            .map(|i| match i {
                BlasInput::Triangles(t) => u64::from(t.triangle_count),
                BlasInput::Aabbs(_) => 0,
            })
            .sum(),
        ..Default::default()
    };
    let t0 = Instant::now();
    let geoms: Vec<_> = inputs.iter().map(geometry).collect();
    let levels = create_bottom_levels(ctx, &geoms, &mut stats)?;
    let (blases, compact_sizes) = build_bottom_levels(ctx, levels, &geoms)?;
    stats.blas_seconds = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let compacted = compact(ctx, blases, &compact_sizes, &mut stats)?;
    stats.compaction_seconds = t1.elapsed().as_secs_f64();

    let t2 = Instant::now();
    let (tlas, instance_buffer, tlas_bytes) = build_top(ctx, &compacted, instances, None)?
        .ok_or_else(|| Error::Invalid("no top level was built".into()))?;
    stats.tlas_bytes = tlas_bytes;
    stats.tlas_seconds = t2.elapsed().as_secs_f64();
    ctx.count_builds(compacted.len(), 1);
    Ok(RayQueryScene {
        _blases: compacted,
        tlas,
        _instances: instance_buffer,
        instance_count: instances.len(),
        stats,
    })
}

/// Bottom levels created at their build size, each with its scratch and build info.
struct BottomLevels<'g> {
    blases: Vec<AccelerationStructure>,
    scratches: Vec<Buffer>,
    infos: Vec<vk::AccelerationStructureBuildGeometryInfoKHR<'g>>,
}

/// Sizes and creates a bottom level per geometry (primitive count beside it).
fn create_bottom_levels<'g>(
    ctx: &Context,
    geoms: &'g [(vk::AccelerationStructureGeometryKHR<'static>, u32)],
    stats: &mut BuildStats,
) -> Result<BottomLevels<'g>> {
    let a = accel(ctx)?;
    let mut levels = BottomLevels {
        blases: Vec::new(),
        scratches: Vec::new(),
        infos: Vec::new(),
    };
    for (g, count) in geoms {
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
            .flags(
                vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
                    | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION,
            )
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(std::slice::from_ref(g));
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        // SAFETY: valid build info.
        unsafe {
            a.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[*count],
                &mut sizes,
            )
        };
        let blas = create_as(
            ctx,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            sizes.acceleration_structure_size,
            "BLAS",
        )?;
        stats.blas_bytes_uncompacted += sizes.acceleration_structure_size;
        stats.scratch_bytes += sizes.build_scratch_size;
        let (sb, saddr) = scratch(ctx, sizes.build_scratch_size)?;
        levels.scratches.push(sb);
        levels
            .infos
            .push(info.dst_acceleration_structure(blas.handle).scratch_data(
                vk::DeviceOrHostAddressKHR {
                    device_address: saddr,
                },
            ));
        levels.blases.push(blas);
    }
    Ok(levels)
}

/// Builds every bottom level in one submission, which also queries their compacted sizes.
fn build_bottom_levels(
    ctx: &Context,
    levels: BottomLevels,
    geoms: &[(vk::AccelerationStructureGeometryKHR<'static>, u32)],
) -> Result<(Vec<AccelerationStructure>, Vec<u64>)> {
    let a = accel(ctx)?;
    let BottomLevels {
        blases,
        scratches,
        infos,
    } = levels;
    let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> = geoms
        .iter()
        .map(|(_, c)| [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(*c)])
        .collect();
    let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> =
        ranges.iter().map(|r| &r[..]).collect();
    let n = blases.len() as u32;
    let pool = size_queries(ctx, n)?;
    let handles: Vec<_> = blases.iter().map(|b| b.handle).collect();
    let built = ctx.one_shot(|cmd| {
        // SAFETY: every referenced buffer and structure is alive until the wait in one_shot.
        unsafe {
            ctx.device.cmd_reset_query_pool(cmd, pool, 0, n.max(1));
            if n > 0 {
                a.cmd_build_acceleration_structures(cmd, &infos, &range_refs);
                ctx.barrier(cmd);
                a.cmd_write_acceleration_structures_properties(
                    cmd,
                    &handles,
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    pool,
                    0,
                );
            }
        }
    });
    drop(scratches);
    let sizes = built
        .map_err(Error::from)
        .and_then(|_| compacted_sizes(ctx, pool, n));
    // SAFETY: the pool is no longer used.
    unsafe { ctx.device.destroy_query_pool(pool, None) };
    Ok((blases, sizes?))
}

/// A pool of `n` compacted-size queries (one at least: a pool may not be empty), to be destroyed
/// by the caller.
fn size_queries(ctx: &Context, n: u32) -> Result<vk::QueryPool> {
    // SAFETY: valid device.
    unsafe {
        ctx.device.create_query_pool(
            &vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                .query_count(n.max(1)),
            None,
        )
    }
    .vk("vkCreateQueryPool")
    .map_err(Error::from)
}

/// The `n` compacted sizes that a completed submission wrote into `pool`.
fn compacted_sizes(ctx: &Context, pool: vk::QueryPool, n: u32) -> Result<Vec<u64>> {
    let mut sizes = vec![0u64; n as usize];
    if n > 0 {
        // SAFETY: the queries were written by the completed submission.
        unsafe {
            ctx.device.get_query_pool_results(
                pool,
                0,
                &mut sizes,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
    }
    Ok(sizes)
}

/// Copies each bottom level into a structure of its compacted size (its own size where the
/// query gave none); the uncompacted ones are freed.
fn compact(
    ctx: &Context,
    blases: Vec<AccelerationStructure>,
    compact_sizes: &[u64],
    stats: &mut BuildStats,
) -> Result<Vec<AccelerationStructure>> {
    let a = accel(ctx)?;
    let mut compacted = Vec::with_capacity(blases.len());
    for (b, &size) in blases.iter().zip(compact_sizes) {
        let size = if size == 0 { b._buffer.size } else { size };
        compacted.push(create_as(
            ctx,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            size,
            "BLAS (compacted)",
        )?);
        stats.blas_bytes += size;
    }
    if !blases.is_empty() {
        ctx.one_shot(|cmd| {
            for (src, dst) in blases.iter().zip(&compacted) {
                // SAFETY: both structures are alive until the wait in one_shot.
                unsafe {
                    a.cmd_copy_acceleration_structure(
                        cmd,
                        &vk::CopyAccelerationStructureInfoKHR::default()
                            .src(src.handle)
                            .dst(dst.handle)
                            .mode(vk::CopyAccelerationStructureModeKHR::COMPACT),
                    )
                };
            }
        })?;
    }
    drop(blases);
    Ok(compacted)
}

fn raw_instances(
    blases: &[AccelerationStructure],
    instances: &[TlasInstance],
) -> Vec<vk::AccelerationStructureInstanceKHR> {
    instances
        .iter()
        .map(|i| {
            let m = &i.transform;
            vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: [
                        m[0][0], m[0][1], m[0][2], m[0][3], m[1][0], m[1][1], m[1][2], m[1][3],
                        m[2][0], m[2][1], m[2][2], m[2][3],
                    ],
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(i.custom_index, i.mask),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: blases[i.blas].address,
                },
            }
        })
        .collect()
}

/// Builds the top level over `blases`: into a new structure and instance buffer, or, given the
/// ones of an earlier build with as many instances, into those (the structure's handle stays,
/// so the kernels bound to it need no new descriptor).
fn build_top(
    ctx: &Context,
    blases: &[AccelerationStructure],
    instances: &[TlasInstance],
    into: Option<(&AccelerationStructure, &Buffer)>,
) -> Result<Option<(AccelerationStructure, Buffer, u64)>> {
    let a = accel(ctx)?;
    let raw = raw_instances(blases, instances);
    // SAFETY: AccelerationStructureInstanceKHR is plain data of 64 bytes.
    let bytes: &[u8] = unsafe {
        std::slice::from_raw_parts(raw.as_ptr() as *const u8, std::mem::size_of_val(&raw[..]))
    };
    let fresh = match into {
        Some((_, buffer)) => {
            ctx.write(buffer, 0, bytes)?;
            None
        }
        None => Some(ctx.upload(
            "TLAS instances",
            bytes,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
        )?),
    };
    let instance_address = fresh
        .as_ref()
        .or(into.map(|i| i.1))
        .map_or(0, |b| b.address);
    let tgeom = [vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::INSTANCES)
        .geometry(vk::AccelerationStructureGeometryDataKHR {
            instances: vk::AccelerationStructureGeometryInstancesDataKHR::default().data(
                vk::DeviceOrHostAddressConstKHR {
                    device_address: instance_address,
                },
            ),
        })];
    let count = raw.len() as u32;
    let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(&tgeom);
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: valid build info.
    unsafe {
        a.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[count],
            &mut sizes,
        )
    };
    let tlas = match into {
        Some(_) => None,
        None => Some(create_as(
            ctx,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            sizes.acceleration_structure_size,
            "TLAS",
        )?),
    };
    let dst = tlas
        .as_ref()
        .or(into.map(|i| i.0))
        .map_or(vk::AccelerationStructureKHR::null(), |t| t.handle);
    let (sb, saddr) = scratch(ctx, sizes.build_scratch_size)?;
    let info = info
        .dst_acceleration_structure(dst)
        .scratch_data(vk::DeviceOrHostAddressKHR {
            device_address: saddr,
        });
    let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
    ctx.one_shot(|cmd| {
        // SAFETY: instance buffer, scratch and TLAS are alive until the wait in one_shot; every
        // earlier submission tracing the structure has completed (one_shot waits).
        unsafe { a.cmd_build_acceleration_structures(cmd, &[info], &[&range]) };
    })?;
    drop(sb);
    Ok(tlas
        .zip(fresh)
        .map(|(t, b)| (t, b, sizes.acceleration_structure_size)))
}

impl RayQueryScene {
    /// Rebuilds the top level over the same bottom levels with moved instances (as many as
    /// before, in the same order), into the same structure.
    pub fn update_top(&mut self, ctx: &Context, instances: &[TlasInstance]) -> Result<f64> {
        let t = Instant::now();
        if instances.len() != self.instance_count {
            return Err(Error::Invalid(format!(
                "the top level holds {} instances, the update gives {}",
                self.instance_count,
                instances.len()
            )));
        }
        build_top(
            ctx,
            &self._blases,
            instances,
            Some((&self.tlas, &self._instances)),
        )?;
        ctx.count_builds(0, 1);
        Ok(t.elapsed().as_secs_f64())
    }
}
