//! The Vulkan layer: context (instance, device, queue), memory, command submission, compute
//! pipelines. It knows nothing of rendering.

mod commands;
mod context;
mod devices;
mod error;
mod memory;
mod pipeline;
mod pipeline_cache;
pub use pipeline_cache::cache_dir;
mod requirements;
mod timer;

pub use commands::{ImageState, image_barrier};
pub use context::{Context, ContextOptions, ExternalDevice, KernelEvent, KernelListener};
pub use devices::{DeviceInfo, list_devices};
pub use error::{Error, VkResultExt};
pub use gpu_allocator::MemoryLocation;
pub use memory::{Buffer, STAGING_BYTES};
pub use pipeline::{ComputePipeline, kernel_times, process_cpu_seconds};
pub use requirements::{FeatureSet, Requirements, requirements};
pub use timer::GpuTimer;
