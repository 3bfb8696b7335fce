//! `illum.compare`: `illum compare` from Python. The library's `illum::compare` names the runs
//! and builds the table, curves and strip; here each run renders with the GIL released and
//! comes back as a `Render`.

use super::{
    IllumError, Render, RenderArgs, Scene, at_resolution, context, detached, err, params_for,
    trace_mode,
};
use illum::compare::{Budget, Comparison as Rendered, Spec};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// A comparison's result: each run's render by name, in order, and the table `illum compare`
/// prints.
#[pyclass(module = "illum", frozen)]
pub struct Comparison {
    /// The runs' names, in the order they rendered (as the CLI's table lists them).
    #[pyo3(get)]
    names: Vec<String>,
    /// Each run's `Render` (report arrays for every pass), by name.
    #[pyo3(get)]
    renders: Py<PyDict>,
    /// One dict per run: name, spp, seconds, relmse, efficiency (1 / (relmse × seconds)).
    #[pyo3(get)]
    table: Py<PyList>,
    /// Whether relmse is measured against the reference (else estimated from half-buffers).
    #[pyo3(get)]
    measured: bool,
    /// What the runs vary: technique, integrator or run (the table's first column).
    #[pyo3(get)]
    kind: &'static str,
}

#[pymethods]
impl Comparison {
    fn __repr__(&self) -> String {
        format!(
            "<illum.Comparison of {} {}s: {}>",
            self.names.len(),
            self.kind,
            self.names.join(", ")
        )
    }
}

/// A list argument: a list of strings, or one string of comma-separated names (as the CLI takes).
fn names(arg: &str, v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(v) = v else {
        return Ok(Vec::new());
    };
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(s.to_str()?.split(',').map(str::to_string).collect());
    }
    v.extract().map_err(|_| {
        IllumError::new_err(format!(
            "{arg}={}: expected a list of names or one comma-separated string",
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    })
}

/// The reference: an EXR's path, or an array of shape (height, width, 3).
fn reference(
    py: Python<'_>,
    v: &Bound<'_, PyAny>,
    (w, h): (u32, u32),
) -> PyResult<(Vec<[f32; 3]>, Option<PathBuf>)> {
    if let Ok(p) = v.extract::<PathBuf>() {
        let r = illum::output::read_reference(&p, w, h).map_err(|e| err(illum::Error::from(e)))?;
        return Ok((r, Some(p)));
    }
    let expected = || {
        IllumError::new_err(format!(
            "reference: expected an EXR's path or an array of shape ({h}, {w}, 3), got {}",
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    };
    let a = py
        .import("numpy")?
        .call_method1("ascontiguousarray", (v, "float32"))
        .map_err(|_| expected())?;
    let a = a.cast::<numpy::PyArray3<f32>>().map_err(|_| expected())?;
    if a.shape() != [h as usize, w as usize, 3] {
        let shape: Vec<String> = a.shape().iter().map(usize::to_string).collect();
        return Err(IllumError::new_err(format!(
            "reference: an array of shape ({}); the render is ({h}, {w}, 3)",
            shape.join(", ")
        )));
    }
    let a = a.try_readonly()?;
    let s = a.as_slice()?;
    Ok((
        s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        None,
    ))
}

/// The files a comparison with `output=PREFIX` writes: each run's EXR, the plot and the strip.
fn outputs(prefix: &Path, names: &[String]) -> (Vec<PathBuf>, PathBuf, PathBuf) {
    let with = |s: &str| PathBuf::from(format!("{}-{s}", prefix.display()));
    (
        names.iter().map(|n| with(&format!("{n}.exr"))).collect(),
        with("error.png"),
        with("strip.png"),
    )
}

/// Renders each run for `time` seconds, as `illum compare` does with the same options (the same
/// pixels bit for bit): `techniques`, `integrators` and `samples` as `--techniques`,
/// `--integrators` and `--samples` (lists or comma-separated strings), `**params` as `--param
/// NAME=VALUE`, `width`/`height` as `--width`/`--height`. `reference` is an EXR's path or an array (height, width, 3): the table's relMSE
/// is then measured, else estimated from the half-buffers. `output=PREFIX` writes what the CLI
/// writes: PREFIX-<name>.exr (each as its run ends), PREFIX-error.png and PREFIX-strip.png.
/// Ctrl-C raises KeyboardInterrupt (a run cut short had less time than the others: no fair
/// comparison), after writing the EXR of the run it stopped.
#[pyfunction]
#[pyo3(signature = (scene, time=5.0, techniques=None, integrators=None, samples=None,
                    reference=None, seed=0, integrator=None, width=None, height=None,
                    trace="auto", device=None, output=None, **params))]
#[allow(clippy::too_many_arguments)]
pub fn compare(
    py: Python<'_>,
    scene: &Scene,
    time: f64,
    techniques: Option<&Bound<'_, PyAny>>,
    integrators: Option<&Bound<'_, PyAny>>,
    samples: Option<&Bound<'_, PyAny>>,
    reference: Option<&Bound<'_, PyAny>>,
    seed: u64,
    integrator: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    trace: &str,
    device: Option<String>,
    output: Option<PathBuf>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Comparison> {
    let scene = &at_resolution(&scene.inner, width, height)?;
    let invalid = |arg: &str, e: String| IllumError::new_err(format!("{arg}=: {e}"));
    let techniques = match techniques {
        None => None,
        Some(t) => Some(
            names("techniques", Some(t))?
                .iter()
                .map(|t| t.parse().map_err(|e| invalid("techniques", e)))
                .collect::<PyResult<Vec<_>>>()?,
        ),
    };
    let samples = names("samples", samples)?
        .iter()
        .map(|s| illum::compare::parse_samples(s).map_err(|e| invalid("samples", e)))
        .collect::<PyResult<Vec<_>>>()?;
    let kw = RenderArgs::params(params, "compare")?;
    let with_kw = |kind: &str| Ok(params_for(kind, scene, &kw));
    let spec = Spec {
        techniques,
        integrators: names("integrators", integrators)?,
        samples,
        default_integrator: illum::integrators::chosen(integrator.as_deref(), scene),
        params: &with_kw,
        arg: |n| format!("{n}="),
    };
    let runs = spec.runs().map_err(err)?;
    let size = (scene.camera.width, scene.camera.height);
    let (reference, reference_path) = match reference {
        Some(v) => {
            let (r, p) = self::reference(py, v, size)?;
            (Some(r), p)
        }
        None => (None, None),
    };
    let names: Vec<String> = runs.iter().map(|r| r.name.clone()).collect();
    let files = output.as_deref().map(|o| outputs(o, &names));
    if let Some((exrs, plot, strip)) = &files {
        let outs: Vec<(&str, &Path)> = exrs
            .iter()
            .map(|p| ("image", p.as_path()))
            .chain([("plot", plot.as_path()), ("strip", strip.as_path())])
            .collect();
        let ins = illum::cli::named([
            ("scene", scene.source.as_deref()),
            ("reference", reference_path.as_deref()),
        ]);
        illum::cli::check_outputs(&outs, &ins).map_err(err)?;
    }
    let cancel = Arc::new(AtomicBool::new(false));
    let budget = Budget {
        time,
        seed,
        trace: trace_mode(trace)?,
        reference: reference.clone(),
        cancel: Some(cancel.clone()),
    };
    let ctx = context(&device).map_err(err)?;
    let mut rendered = Rendered {
        runs: Vec::new(),
        measured: reference.is_some(),
        time,
    };
    let mut metas = Vec::new();
    for (k, run) in runs.iter().enumerate() {
        let (out, device_name, settings, stopped) = detached(
            py,
            ctx.clone(),
            budget.settings(run),
            cancel.clone(),
            |r, s, p| r.render(scene, s, p),
        );
        let out = out.map_err(err)?;
        let meta = illum::output::image_metadata(&out, &settings, &device_name);
        // Each run's EXR as soon as it is rendered, as `illum compare` writes them: an
        // interrupted comparison keeps the images done.
        let exr = files.as_ref().map(|(exrs, ..)| &exrs[k]);
        if let Some(exr) = exr {
            illum::output::write_exr(exr, &out.film, &meta)
                .map_err(|e| err(illum::Error::from(e)))?;
        }
        if stopped || out.stats.interrupted {
            return Err(PyKeyboardInterrupt::new_err(format!(
                "illum.compare: stopped during {} after {} spp; no comparison{}",
                run.name,
                out.stats.spp,
                exr.map_or(String::new(), |e| format!(
                    " (wrote {} and the runs before it)",
                    e.display()
                ))
            )));
        }
        metas.push(meta);
        rendered.runs.push((run.name.clone(), out));
    }
    if let Some((_, plot, strip)) = &files {
        rendered.write_plot(plot).map_err(err)?;
        rendered
            .write_strip(strip, reference.as_deref())
            .map_err(err)?;
    }
    let table = PyList::empty(py);
    for row in rendered.rows() {
        let d = PyDict::new(py);
        d.set_item("name", row.name)?;
        d.set_item("spp", row.spp)?;
        d.set_item("seconds", row.seconds)?;
        d.set_item("relmse", row.relmse)?;
        d.set_item("efficiency", row.efficiency)?;
        table.append(d)?;
    }
    let renders = PyDict::new(py);
    for ((name, out), meta) in rendered.runs.into_iter().zip(metas) {
        renders.set_item(name, Render::new(py, out, meta, false)?)?;
    }
    Ok(Comparison {
        names,
        renders: renders.unbind(),
        table: table.unbind(),
        measured: reference.is_some(),
        kind: spec.kind(),
    })
}
