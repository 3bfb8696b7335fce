//! illum: a physically based renderer on Vulkan, after "Physically Based Lighting at Pixar"
//! (Villemin & Hery, SIGGRAPH 2013).
//!
//! Data flows one way: scene file → [`scene::Scene`] (validated host types) → GPU scene
//! (buffers, acceleration structures) → integrator kernels → film → outputs.

pub mod film;
pub mod jobs;
pub mod layout;
pub mod output;
pub mod scene;

/// SPIR-V of every kernel variant, compiled by build.rs (`<KERNEL>_<VARIANT>: &[u8]`); the test
/// kernels are the `illum-test-kernels` crate's (tests/kernels/).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
pub mod capi;
pub mod cli;
pub mod compare;
pub mod denoise;
pub mod error;
pub mod vk;

pub use error::{Error, Result};
pub mod gpu_scene;
pub mod integrators;
pub mod metrics;
pub mod note;
pub mod render;
pub mod report;
pub mod stress;
pub mod trace;
pub mod view;
