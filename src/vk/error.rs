//! The Vulkan layer's error type. Failures name the call; device loss and memory exhaustion get
//! their own variants so that callers can react to them.

use ash::vk;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(
        "cannot load the Vulkan library: {0} (install libvulkan1 and a driver, e.g. scripts/setup-debian.sh)"
    )]
    Loader(String),
    #[error(
        "Vulkan validation was requested (--validate or ILLUM_VALIDATION=1) but the layer {0} is not installed; the Vulkan library itself loaded fine (install vulkan-validationlayers, or leave validation off)"
    )]
    MissingLayer(String),
    #[error("no usable Vulkan device: {0}")]
    NoDevice(String),
    #[error("device \"{device}\" cannot run illum: {what}")]
    Unsupported { device: String, what: String },
    #[error(
        "{call}: the Vulkan device was lost (VK_ERROR_DEVICE_LOST); the driver reset it, possibly after a dispatch ran too long"
    )]
    DeviceLost { call: &'static str },
    #[error("{call}: out of {kind} memory ({result:?}); try a smaller resolution or scene")]
    OutOfMemory {
        call: &'static str,
        kind: &'static str,
        result: vk::Result,
    },
    #[error("{call} failed: {result:?}")]
    Vulkan {
        call: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation for {what} failed: {source}")]
    Allocation {
        what: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
    #[error("{0}")]
    Invalid(String),
}

/// Attaches the name of the Vulkan call to a `vk::Result` error.
pub trait VkResultExt<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkResultExt<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::from_call(call, result))
    }
}

impl Error {
    /// The error of Vulkan call `call` that returned `result`.
    pub fn from_call(call: &'static str, result: vk::Result) -> Error {
        match result {
            vk::Result::ERROR_DEVICE_LOST => Error::DeviceLost { call },
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => Error::OutOfMemory {
                call,
                kind: "device",
                result,
            },
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => Error::OutOfMemory {
                call,
                kind: "host",
                result,
            },
            _ => Error::Vulkan { call, result },
        }
    }
}
