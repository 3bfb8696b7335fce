//! `illum merge`: the jobs of a split render (partial EXRs of `illum render --samples/--crop`)
//! into the image a render in one piece writes, bit for bit (src/jobs/mod.rs).

use super::check_outputs;
use crate::jobs::{Merged, merge_files};
use crate::output::{ImageMetadata, write_exr, write_png};
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The jobs' partial EXRs: together they must cover every pixel and sample exactly once.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,
    /// The merged image: .exr (all layers), or .png (then the .exr is written beside it too).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write an sRGB PNG of the beauty beside the EXR.
    #[arg(long)]
    pub png: bool,
    /// No summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The EXR header of a merged image: what `illum merge` writes (and Python's `illum.merge`).
pub fn merged_metadata(m: &Merged, parts: usize) -> ImageMetadata {
    let mut extra = vec![
        ("illum.trace".to_string(), m.trace.clone()),
        ("illum.settings".into(), m.settings.clone()),
        (
            "illum.nonFiniteSamples".into(),
            m.non_finite_samples.to_string(),
        ),
        ("illum.mergedParts".into(), parts.to_string()),
    ];
    if m.clamped_samples > 0 {
        extra.push(("illum.clampedSamples".into(), m.clamped_samples.to_string()));
    }
    ImageMetadata {
        spp: m.spp,
        render_seconds: m.render_seconds,
        setup_seconds: m.setup_seconds,
        device: m.devices.join(", "),
        seed: m.seed,
        extra,
    }
}

pub fn run(a: &MergeArgs) -> Result<()> {
    let (exr_path, png_path) = super::image_paths(&a.output, a.png)?;
    let outputs = super::named([
        ("image", Some(exr_path.as_path())),
        ("PNG", png_path.as_deref()),
    ]);
    let inputs: Vec<(&str, &std::path::Path)> =
        a.parts.iter().map(|p| ("part", p.as_path())).collect();
    check_outputs(&outputs, &inputs)?;
    let start = Instant::now();
    // Headers first (a mismatch fails before any data is read), then one part at a time.
    let m = merge_files(&a.parts)?;
    let meta = merged_metadata(&m, a.parts.len());
    write_exr(&exr_path, &m.film, &meta)?;
    if let Some(p) = &png_path {
        write_png(p, &m.film)?;
    }
    if !a.quiet {
        crate::note!(
            "illum: merged {} parts into {}x{} at {} spp in {:.2} s; the parts rendered for {:.2} s after {:.2} s of set-up; wrote {}",
            a.parts.len(),
            m.film.width,
            m.film.height,
            m.spp,
            start.elapsed().as_secs_f64(),
            m.render_seconds,
            m.setup_seconds,
            exr_path.display()
        );
    }
    Ok(())
}
