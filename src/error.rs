//! The library's error type: what the layers below report (the Vulkan layer's [`GpuError`], the
//! scene's [`SceneError`], an output's error through `From` in `crate::output`) and invalid
//! requests.

pub use crate::scene::SceneError;
pub use crate::vk::Error as GpuError;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Writing or reading an output (crate::output::OutputError; the output layer sits above
    /// this one, so it is held by its trait).
    #[error(transparent)]
    Output(Box<dyn std::error::Error + Send + Sync + 'static>),
    #[error("{0}")]
    Invalid(String),
}
