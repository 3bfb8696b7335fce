//! The SPIR-V of the test kernels in this folder (`<STEM>_PLAIN`, as `illum::shaders` names the
//! library's), compiled by build.rs against the library's GLSL pieces in glsl/. A crate of its
//! own, a dev-dependency of illum, so that neither the library nor the `illum` command carries
//! them, and switching between `cargo build` and `cargo test` rebuilds nothing.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
