//! `illum stress`: the stress suite's scenes rendered on every trace path, and its Markdown report.

use crate::render::Renderer;
use crate::vk::{Context, ContextOptions};
use anyhow::{Context as _, Result, bail};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct StressArgs {
    /// Folder of the stress scenes. [default: scenes/stress in the current folder, else in the
    /// source tree illum was built from]
    #[arg(long)]
    pub scenes: Option<PathBuf>,
    /// The Markdown report to write (the repository keeps one as docs/stress.md: run
    /// `illum stress -o docs/stress.md` from its root to refresh it).
    #[arg(short, long, default_value = "stress.md")]
    pub output: PathBuf,
    /// Render time per case and trace path, in seconds.
    #[arg(long, default_value_t = 2.0)]
    pub time: f64,
    /// Image width and height of every case.
    #[arg(long, default_value_t = 64)]
    pub size: u32,
    /// Samples per pixel of the references rendered by a different technique.
    #[arg(long, default_value_t = 2048)]
    pub reference_spp: u32,
    /// Device index or a substring of its name (see `illum devices`). [default: the best device]
    #[arg(long)]
    pub device: Option<String>,
}

/// The scenes folder: the one named, else `scenes/stress` here or in the source tree.
fn scenes_folder(named: Option<&Path>) -> Result<PathBuf> {
    let first = crate::stress::CASES[0].name;
    let has_cases = |d: &Path| d.join(format!("{first}.json")).is_file();
    if let Some(d) = named {
        if !d.is_dir() {
            bail!(
                "--scenes {}: no such folder (name the scenes/stress folder of an illum checkout)",
                d.display()
            );
        }
        if !has_cases(d) {
            bail!(
                "--scenes {}: it holds no {first}.json; name the scenes/stress folder of an illum \
                 checkout (scripts/make-stress-scenes.py writes them)",
                d.display()
            );
        }
        return Ok(d.to_path_buf());
    }
    let here = PathBuf::from("scenes/stress");
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/stress");
    for d in [&here, &source] {
        if has_cases(d) {
            return Ok(d.clone());
        }
    }
    bail!(
        "the stress scenes are not in scenes/stress under the current folder nor in {}: run illum \
         stress from the root of an illum checkout, or name the folder with --scenes DIR",
        source.display()
    )
}

pub fn run(a: &StressArgs) -> Result<()> {
    crate::output::check_writable(&a.output)?;
    let scenes = scenes_folder(a.scenes.as_deref())?;
    for case in crate::stress::CASES {
        let f = scenes.join(format!("{}.json", case.name));
        if !f.is_file() {
            bail!("the stress suite needs {}, which is missing", f.display());
        }
    }
    if a.scenes.is_none() && scenes != Path::new("scenes/stress") {
        crate::note!("illum stress: scenes from {}", scenes.display());
    }
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
        ..Default::default()
    })?;
    let renderer = Renderer::new(ctx.clone());
    let o = crate::stress::StressOptions {
        seconds: a.time,
        width: a.size,
        height: a.size,
        reference_spp: a.reference_spp,
    };
    let rows = crate::stress::run(&renderer, &scenes, &o, &mut |r| {
        crate::note!(
            "illum stress: {:<24} {:<9} {:>7} spp  relMSE {:.2e}  non-finite {}  mean ratio {:.5} (z {:+.1})",
            r.case,
            r.trace,
            r.spp,
            r.relmse,
            r.non_finite_samples,
            r.mean_ratio,
            r.z
        )
    })?;
    let command = format!(
        "illum stress --time {} --size {} --reference-spp {}",
        a.time, a.size, a.reference_spp
    );
    let md = crate::stress::markdown(&rows, &o, &ctx.info().name, &command);
    crate::output::write_atomically(&a.output, |tmp| {
        std::fs::write(tmp, &md).map_err(|cause| crate::output::OutputError::Io {
            path: a.output.clone(),
            cause,
        })
    })
    .with_context(|| format!("writing the report {}", a.output.display()))?;
    crate::note!("illum stress: wrote {}", a.output.display());
    Ok(())
}
