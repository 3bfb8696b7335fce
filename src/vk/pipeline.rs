//! Compute pipelines: one descriptor set, push constants, and specialization constants (the
//! per-scene feature switches that fold away code a scene does not need).

use super::context::Context;
use super::error::{Error, Result, VkResultExt};
use super::memory::Buffer;
use ash::vk;

pub struct ComputePipeline {
    ctx: Context,
    pub name: String,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

impl ComputePipeline {
    /// `spec[i]` is the value of the u32 specialization constant with constant_id i.
    pub fn new(
        ctx: &Context,
        name: &str,
        spirv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_size: u32,
        spec: &[u32],
    ) -> Result<ComputePipeline> {
        let code = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
            .map_err(|e| Error::Invalid(format!("kernel {name}: bad SPIR-V: {e}")))?;
        ctx.notify_kernel(crate::vk::KernelEvent::Creating(name));
        let dev = &ctx.device;
        // SAFETY: valid device; the objects are owned by the returned pipeline (or destroyed on
        // error by its Drop, since null handles are ignored by vkDestroy*).
        unsafe {
            let mut p = ComputePipeline {
                ctx: ctx.clone(),
                name: name.to_string(),
                set_layout: vk::DescriptorSetLayout::null(),
                layout: vk::PipelineLayout::null(),
                pipeline: vk::Pipeline::null(),
                pool: vk::DescriptorPool::null(),
                set: vk::DescriptorSet::null(),
            };
            let lb: Vec<_> = bindings
                .iter()
                .map(|&(b, ty)| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b)
                        .descriptor_type(ty)
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            p.set_layout = dev
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&lb),
                    None,
                )
                .vk("vkCreateDescriptorSetLayout")?;
            let layouts = [p.set_layout];
            let ranges = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .size(push_size)];
            let mut li = vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts);
            if push_size > 0 {
                li = li.push_constant_ranges(&ranges);
            }
            p.layout = dev
                .create_pipeline_layout(&li, None)
                .vk("vkCreatePipelineLayout")?;
            let module = dev
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
                .vk("vkCreateShaderModule")?;
            let entries: Vec<_> = (0..spec.len())
                .map(|i| vk::SpecializationMapEntry {
                    constant_id: i as u32,
                    offset: (i * 4) as u32,
                    size: 4,
                })
                .collect();
            let spec_info = vk::SpecializationInfo::default()
                .map_entries(&entries)
                .data(bytemuck::cast_slice(spec));
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main")
                .specialization_info(&spec_info);
            let (t0, cpu0) = (std::time::Instant::now(), process_cpu_seconds());
            let flags = if ctx.executable_stats.is_some() {
                vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
            } else {
                vk::PipelineCreateFlags::empty()
            };
            let created = dev.create_compute_pipelines(
                ctx.pipeline_cache,
                &[vk::ComputePipelineCreateInfo::default()
                    .flags(flags)
                    .stage(stage)
                    .layout(p.layout)],
                None,
            );
            dev.destroy_shader_module(module, None);
            if kernel_times() {
                crate::note!(
                    "illum: kernel {name}: {} bytes of SPIR-V, features {:#x}, created in {:.3} s \
                     ({:.3} s of process CPU)",
                    spirv.len(),
                    spec.first().copied().unwrap_or(0),
                    t0.elapsed().as_secs_f64(),
                    process_cpu_seconds() - cpu0
                );
            }
            p.pipeline = created.map_err(|(_, e)| e).vk("vkCreateComputePipelines")?[0];
            if let Some(x) = &ctx.executable_stats {
                print_stats(x, p.pipeline, name);
            }
            if let Some(file) = &ctx.pipeline_cache_file {
                super::pipeline_cache::save(dev, ctx.pipeline_cache, file);
            }
            let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
            for &(_, ty) in bindings {
                match sizes.iter_mut().find(|s| s.ty == ty) {
                    Some(s) => s.descriptor_count += 1,
                    None => sizes.push(vk::DescriptorPoolSize {
                        ty,
                        descriptor_count: 1,
                    }),
                }
            }
            p.pool = dev
                .create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&sizes),
                    None,
                )
                .vk("vkCreateDescriptorPool")?;
            p.set = dev
                .allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default()
                        .descriptor_pool(p.pool)
                        .set_layouts(&layouts),
                )
                .vk("vkAllocateDescriptorSets")?[0];
            Ok(p)
        }
    }

    pub fn bind_buffer(&self, binding: u32, ty: vk::DescriptorType, buffer: &Buffer) {
        let info = [vk::DescriptorBufferInfo::default()
            .buffer(buffer.buffer)
            .range(vk::WHOLE_SIZE)];
        let w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .descriptor_type(ty)
            .buffer_info(&info);
        // SAFETY: the set is not in use by pending work (callers bind before recording).
        unsafe { self.ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    pub fn bind_acceleration_structure(&self, binding: u32, tlas: vk::AccelerationStructureKHR) {
        let handles = [tlas];
        let mut asw = vk::WriteDescriptorSetAccelerationStructureKHR::default()
            .acceleration_structures(&handles);
        // push_next leaves descriptor_count 0: set it (PLATFORM.md, ash 0.38 pitfalls).
        let mut w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut asw);
        w.descriptor_count = 1;
        // SAFETY: as in bind_buffer.
        unsafe { self.ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    /// Binds a storage image view (in layout GENERAL when the dispatch runs).
    pub fn bind_storage_image(&self, binding: u32, view: vk::ImageView) {
        let info = [vk::DescriptorImageInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::GENERAL)];
        let w = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
            .image_info(&info);
        // SAFETY: as in bind_buffer.
        unsafe { self.ctx.device.update_descriptor_sets(&[w], &[]) };
    }

    /// Records push constants, the bound set and a dispatch of `groups` workgroups.
    pub fn dispatch(&self, cmd: vk::CommandBuffer, push: &[u8], groups: [u32; 3]) {
        let dev = &self.ctx.device;
        // SAFETY: cmd is recording; the pipeline, layout and set are alive.
        unsafe {
            dev.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            dev.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[self.set],
                &[],
            );
            if !push.is_empty() {
                dev.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            dev.cmd_dispatch(cmd, groups[0], groups[1], groups[2]);
        }
    }
}

/// ILLUM_KERNEL_TIMES=1: each pipeline creation says on stderr how long it took (measuring the
/// driver's compile time, docs/performance-kernels.md).
pub fn kernel_times() -> bool {
    std::env::var("ILLUM_KERNEL_TIMES").is_ok_and(|v| v != "0" && !v.is_empty())
}

/// ILLUM_KERNEL_STATS=1: on a device with VK_KHR_pipeline_executable_properties, each kernel's
/// statistics as the driver reports them (register count, spills, instruction count, ...) are
/// printed on stderr at its creation (docs/performance-kernels.md, "Kernel statistics").
pub fn kernel_stats() -> bool {
    std::env::var("ILLUM_KERNEL_STATS").is_ok_and(|v| v != "0" && !v.is_empty())
}

/// Prints the driver's statistics of every executable of `pipeline`, one line each.
///
/// # Safety
/// `pipeline` was created with CAPTURE_STATISTICS_KHR on the device of `x`.
unsafe fn print_stats(
    x: &ash::khr::pipeline_executable_properties::Device,
    pipeline: vk::Pipeline,
    name: &str,
) {
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: as the caller promises.
    let executables = unsafe { x.get_pipeline_executable_properties(&info) }.unwrap_or_default();
    for (k, e) in executables.iter().enumerate() {
        let what = e
            .name_as_c_str()
            .map_or(String::new(), |c| c.to_string_lossy().into());
        let ei = vk::PipelineExecutableInfoKHR::default()
            .pipeline(pipeline)
            .executable_index(k as u32);
        // SAFETY: as above; the index is one of the pipeline's executables.
        let stats = unsafe { x.get_pipeline_executable_statistics(&ei) }.unwrap_or_default();
        let values: Vec<String> = stats
            .iter()
            .map(|s| {
                let n = s
                    .name_as_c_str()
                    .map_or(String::new(), |c| c.to_string_lossy().into());
                // SAFETY: the union member read is the one `format` names.
                let v = unsafe {
                    match s.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => s.value.b32.to_string(),
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => s.value.i64.to_string(),
                        vk::PipelineExecutableStatisticFormatKHR::UINT64 => s.value.u64.to_string(),
                        _ => format!("{:.4}", s.value.f64),
                    }
                };
                format!("{n} {v}")
            })
            .collect();
        crate::note!(
            "illum: kernel {name} statistics ({what}, subgroup {}): {}",
            e.subgroup_size,
            values.join(", ")
        );
    }
}

/// User plus system CPU seconds of the whole process (all threads): on a loaded machine a
/// better measure of compile work than wall time.
pub fn process_cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return 0.0;
    }
    let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    s(u.ru_utime) + s(u.ru_stime)
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        let dev = &self.ctx.device;
        // SAFETY: no pending work uses these (submissions are waited for).
        unsafe {
            dev.destroy_pipeline(self.pipeline, None);
            dev.destroy_descriptor_pool(self.pool, None);
            dev.destroy_pipeline_layout(self.layout, None);
            dev.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
