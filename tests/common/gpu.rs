//! The validated Vulkan context every GPU test runs on, and the test kernels of tests/kernels/.

use ash::vk;
use glam::DVec3;
use illum::trace::TraceMode;
use illum::vk::{ComputePipeline, Context, ContextOptions, MemoryLocation};

pub fn context() -> Context {
    Context::new(&ContextOptions {
        device: std::env::var("ILLUM_TEST_DEVICE").ok(),
        validation: true,
        ..Default::default()
    })
    .expect("creating a Vulkan context with validation layers")
}

pub fn trace_mode() -> TraceMode {
    std::env::var("ILLUM_TEST_TRACE")
        .ok()
        .map(|s| s.parse().expect("ILLUM_TEST_TRACE"))
        .unwrap_or(TraceMode::Auto)
}

/// Fails the test if the validation layers said anything.
pub fn assert_no_validation_messages(ctx: &Context) {
    assert!(ctx.validation_enabled(), "validation layers are not on");
    let m = ctx.validation_messages();
    assert!(
        m.is_empty(),
        "{} validation message(s):\n{}",
        m.len(),
        m.join("\n")
    );
}

/// A vec4 of a test kernel's records: xyz from `v`, w.
pub fn f4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// The xyz of a kernel's vec3 or vec4, in double precision.
pub fn d3<const N: usize>(v: [f32; N]) -> DVec3 {
    DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
}

/// A test kernel of tests/kernels/: binding 0 parameters, 1 input, 2 output (storage buffers), push
/// constants (mode, count, seed, 0); one invocation per item, 64 per workgroup.
pub struct Kernel {
    ctx: Context,
    pipeline: ComputePipeline,
}

impl Kernel {
    pub fn new(ctx: &Context, name: &str, spirv: &[u8]) -> Kernel {
        let s = vk::DescriptorType::STORAGE_BUFFER;
        let pipeline = ComputePipeline::new(ctx, name, spirv, &[(0, s), (1, s), (2, s)], 16, &[])
            .unwrap_or_else(|e| panic!("kernel {name}: {e}"));
        Kernel {
            ctx: ctx.clone(),
            pipeline,
        }
    }

    /// Runs `count` items and returns `out_len` elements of the output buffer.
    pub fn run<P: bytemuck::Pod, I: bytemuck::Pod, O: bytemuck::Pod>(
        &self,
        params: &P,
        input: &[I],
        mode: u32,
        count: usize,
        seed: u32,
        out_len: usize,
    ) -> Vec<O> {
        let ctx = &self.ctx;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let pbuf = ctx
            .upload("test params", std::slice::from_ref(params), storage)
            .unwrap();
        let ibuf = ctx.upload("test input", input, storage).unwrap();
        let obuf = ctx
            .create_buffer(
                "test output",
                (out_len * std::mem::size_of::<O>()) as u64,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )
            .unwrap();
        self.pipeline
            .bind_buffer(0, vk::DescriptorType::STORAGE_BUFFER, &pbuf);
        self.pipeline
            .bind_buffer(1, vk::DescriptorType::STORAGE_BUFFER, &ibuf);
        self.pipeline
            .bind_buffer(2, vk::DescriptorType::STORAGE_BUFFER, &obuf);
        let push: [u32; 4] = [mode, count as u32, seed, 0];
        // Bounded dispatches (at most 2^16 groups each is not needed here: count <= 2^22).
        let groups = count.div_ceil(64) as u32;
        assert!(groups <= 65535, "too many items for one dispatch: {count}");
        ctx.one_shot(|cmd| {
            self.pipeline
                .dispatch(cmd, bytemuck::bytes_of(&push), [groups.max(1), 1, 1]);
            ctx.barrier(cmd);
        })
        .unwrap();
        ctx.download(&obuf, out_len).unwrap()
    }
}
