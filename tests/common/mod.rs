//! The integration tests' support library, one file a topic: the validated Vulkan context and the
//! test kernels (gpu.rs), inline scenes (scenes.rs), renders (render.rs) and independent batches
//! of them (batches.rs), statistics (stats.rs), chi-square tests of direction samplers over
//! domains of directions (chi2.rs, domain.rs), the light test kernels (lights.rs, used as
//! `common::lights`), random numbers (rng.rs), the illum binary (cli.rs) and scratch folders removed with their
//! process (scratch.rs).
//! `ILLUM_TEST_TRACE=auto|rayquery|bvh` picks the trace path (CI runs the suite on each),
//! `ILLUM_TEST_DEVICE` the device.
#![allow(dead_code)]

mod batches;
mod chi2;
mod cli;
mod domain;
mod gpu;
pub mod lights;
mod render;
mod rng;
mod scenes;
mod scratch;
mod stats;

// Each test binary uses a part of the library; the re-exports of the parts it does not use
// would warn.
#[allow(unused_imports)]
pub use {
    batches::*, chi2::*, cli::*, domain::*, gpu::*, render::*, rng::*, scenes::*, scratch::*,
    stats::*,
};
