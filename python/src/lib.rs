//! `illum._illum`, the native half of the Python package `illum` (python/illum/ re-exports it):
//! scenes loaded and validated by the library, rendered by its one driver (`Renderer::render`,
//! as `illum render` does) into NumPy arrays that take the film's own planes without a copy.
//! Errors are `illum.IllumError` with the message the CLI prints; rendering releases the GIL,
//! and Ctrl-C stops a render, which then returns the samples it has (as the CLI writes them).

use illum::film::{AovPlane, Film, FilmSums, Window};
use illum::jobs::partial::PartInfo;
use illum::output::ImageMetadata;
use illum::render::{RenderOutput, RenderSettings, Renderer};
use illum::trace::TraceMode;
use illum::vk::{Context, ContextOptions};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::cell::RefCell;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

mod compare;

create_exception!(
    _illum,
    IllumError,
    PyException,
    "A failure of illum: bad input (the message names the file, field and value, as `illum` \
     prints it), a device illum cannot use, or a failed write."
);

/// The error as the CLI prints it (`illum: error: {e:#}`, without the prefix).
fn err(e: impl Into<anyhow::Error>) -> PyErr {
    IllumError::new_err(format!("{:#}", e.into()))
}

thread_local! {
    /// One device context per thread and device choice, made by the first render that asks for
    /// it (its kernels and pipeline cache then serve every later render).
    static CONTEXTS: RefCell<Vec<(Option<String>, Context)>> = const { RefCell::new(Vec::new()) };
}

fn context(device: &Option<String>) -> illum::Result<Context> {
    CONTEXTS.with(|c| {
        let mut c = c.borrow_mut();
        if let Some((_, ctx)) = c.iter().find(|(d, _)| d == device) {
            return Ok(ctx.clone());
        }
        let ctx = Context::new(&ContextOptions {
            device: device.clone(),
            validation: false,
            ..Default::default()
        })?;
        c.push((device.clone(), ctx.clone()));
        Ok(ctx)
    })
}

/// Marks data that stays on the calling thread while the GIL is released (`Python::detach` runs
/// its closure on this same thread): the device context and the render's callbacks.
struct SameThread<T>(T);
// SAFETY: `detach` runs the closure on the thread that called it and returns before that thread
// runs any Python code again, so the wrapped value never crosses threads.
unsafe impl<T> Send for SameThread<T> {}

impl<T> SameThread<T> {
    /// The value (a method, so that a closure captures the whole wrapper, not its fields).
    fn get(self) -> T {
        self.0
    }
}

/// A validated scene (`illum.load`, `Scene.from_dict`).
#[pyclass(module = "illum", frozen)]
struct Scene {
    inner: illum::scene::Scene,
    /// Its JSON, the folder its relative paths start from and its name in messages, when it came
    /// from JSON: what a prepared scene's edits rewrite.
    json: Option<Json>,
}

#[derive(Clone)]
struct Json {
    text: String,
    base: PathBuf,
    origin: String,
}

/// The arguments every render takes, as `illum render` reads them.
struct RenderArgs {
    spp: Option<u32>,
    time: Option<f64>,
    seed: u64,
    integrator: Option<String>,
    trace: String,
    report: bool,
    /// The integrator's parameters: (name, value as text, origin).
    params: Vec<(String, String, String)>,
}

impl RenderArgs {
    /// Keyword parameters as (name, text, origin); `call` names the function in the origin.
    fn params(
        kw: Option<&Bound<'_, PyDict>>,
        call: &str,
    ) -> PyResult<Vec<(String, String, String)>> {
        let mut out = Vec::new();
        if let Some(kw) = kw {
            for (k, v) in kw.iter() {
                let k: String = k.extract()?;
                let text = param_text(&v)?;
                let origin = format!("{call}({k}={})", v.repr()?);
                out.push((k, text, origin));
            }
        }
        Ok(out)
    }

    /// The render settings for `scene`, and the flag that stops the render.
    fn settings(&self, scene: &illum::scene::Scene) -> PyResult<(RenderSettings, Arc<AtomicBool>)> {
        let name = illum::integrators::chosen(self.integrator.as_deref(), scene);
        let p = params_for(&name, scene, &self.params);
        let integrator =
            illum::integrators::create(&name, &p).map_err(|e| err(anyhow::anyhow!(e)))?;
        let trace = trace_mode(&self.trace)?;
        let cancel = Arc::new(AtomicBool::new(false));
        let settings = RenderSettings {
            integrator,
            // As `illum render`: 16 spp, or without a cap under a time budget.
            spp: self
                .spp
                .unwrap_or(if self.time.is_some() { 1 << 20 } else { 16 }),
            time: self.time,
            seed: self.seed,
            trace,
            evaluate_passes: self.report,
            cancel: Some(cancel.clone()),
            ..Default::default()
        };
        Ok((settings, cancel))
    }
}

/// What a render with the GIL released gives back: its output, the device's name, its settings
/// and whether KeyboardInterrupt stopped it.
type Detached = (illum::Result<RenderOutput>, String, RenderSettings, bool);

/// Integrator `kind`'s parameters: the scene's, then the keyword parameters over them.
fn params_for(
    kind: &str,
    scene: &illum::scene::Scene,
    kw: &[(String, String, String)],
) -> illum::render::Params {
    let mut p = illum::integrators::scene_params(kind, scene);
    for (k, v, origin) in kw {
        p.set(k, v, origin);
    }
    p
}

/// `scene` at the resolution `width`/`height` ask for (as `--width`/`--height`).
fn at_resolution(
    scene: &illum::scene::Scene,
    width: Option<u32>,
    height: Option<u32>,
) -> PyResult<illum::scene::Scene> {
    let mut scene = scene.clone();
    scene
        .camera
        .set_resolution(width, height)
        .map_err(|e| err(anyhow::anyhow!(e)))?;
    Ok(scene)
}

/// Runs `render` with the GIL released and Ctrl-C setting `cancel`.
fn detached(
    py: Python<'_>,
    ctx: Context,
    settings: RenderSettings,
    cancel: Arc<AtomicBool>,
    render: impl FnOnce(
        &Renderer,
        &RenderSettings,
        &mut dyn FnMut(u32, u32),
    ) -> illum::Result<RenderOutput>,
) -> Detached {
    let job = SameThread((ctx, settings, render));
    py.detach(move || {
        let (ctx, settings, render) = job.get();
        let mut stopped = false;
        let r = render(&Renderer::new(ctx.clone()), &settings, &mut |_, _| {
            // Python's SIGINT handler runs here; KeyboardInterrupt stops the render.
            if !stopped && Python::attach(|py| py.check_signals()).is_err() {
                stopped = true;
                cancel.store(true, Ordering::SeqCst);
            }
        });
        SameThread((r, ctx.info().name.clone(), settings, stopped))
    })
    .0
}

/// Runs `render` as [`detached`] does and makes its result.
fn run(
    py: Python<'_>,
    ctx: Context,
    settings: RenderSettings,
    cancel: Arc<AtomicBool>,
    render: impl FnOnce(
        &Renderer,
        &RenderSettings,
        &mut dyn FnMut(u32, u32),
    ) -> illum::Result<RenderOutput>,
) -> PyResult<Render> {
    let (out, device_name, settings, stopped) = detached(py, ctx, settings, cancel, render);
    let out = out.map_err(err)?;
    let meta = illum::output::image_metadata(&out, &settings, &device_name);
    Render::new(py, out, meta, stopped)
}

/// Joins the jobs of a split render (their `Render` results, or the partial EXRs they wrote)
/// into the image a render in one piece gives, bit for bit, as `illum merge` does.
#[pyfunction]
fn merge(py: Python<'_>, parts: &Bound<'_, PyList>) -> PyResult<Render> {
    let mut paths = Vec::new();
    let mut jobs = Vec::new();
    for (k, p) in parts.iter().enumerate() {
        if let Ok(r) = p.cast::<Render>() {
            let (info, sums) = r.get().part.clone().ok_or_else(|| {
                IllumError::new_err(format!(
                    "merge: part {k} is not a job of a split render (render it with samples= or crop=)"
                ))
            })?;
            jobs.push(illum::jobs::Part {
                path: PathBuf::from(format!("part {k}")),
                info,
                sums,
            });
        } else {
            paths.push(p.extract::<PathBuf>()?);
        }
    }
    if !jobs.is_empty() && !paths.is_empty() {
        return Err(IllumError::new_err(
            "merge: give the jobs' results or their files, not both",
        ));
    }
    let n = jobs.len().max(paths.len());
    let m = py
        .detach(move || {
            if paths.is_empty() {
                illum::jobs::merge(&jobs)
            } else {
                illum::jobs::merge_files(&paths)
            }
        })
        .map_err(err)?;
    let meta = illum::cli::merge::merged_metadata(&m, n);
    Render::from_film(
        py,
        m.film,
        meta,
        m.spp,
        (m.split, m.spp, (0, 0)),
        false,
        &[],
    )
}

/// A `trace=` argument: auto, rayquery or bvh, as `--trace` takes it.
fn trace_mode(s: &str) -> PyResult<TraceMode> {
    s.parse()
        .map_err(|e: String| err(anyhow::anyhow!("trace={s:?}: {e}")))
}

/// The value of a keyword parameter as the integrator reads it: booleans as on/off.
fn param_text(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = v.extract::<bool>() {
        return Ok(if b { "on" } else { "off" }.to_string());
    }
    Ok(v.str()?.to_string())
}

#[pymethods]
impl Scene {
    /// A scene from a dict of the JSON scene format (docs/scene-format.md), validated as a scene
    /// file is; relative paths are resolved against `base_dir` (default: the working folder).
    #[staticmethod]
    #[pyo3(signature = (d, base_dir=None))]
    fn from_dict(
        py: Python<'_>,
        d: &Bound<'_, PyAny>,
        base_dir: Option<PathBuf>,
    ) -> PyResult<Scene> {
        let text: String = py.import("json")?.call_method1("dumps", (d,))?.extract()?;
        let base = match base_dir {
            Some(b) => b,
            None => std::env::current_dir().map_err(err)?,
        };
        let inner = illum::scene::from_json_str(&text, DICT, &base).map_err(err)?;
        Ok(Scene {
            inner,
            json: Some(Json {
                text,
                base,
                origin: DICT.into(),
            }),
        })
    }

    /// What the scene file holds that illum does not render, each naming where it is (a USD
    /// stage's prim and attribute); `illum render --strict` refuses such a scene.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }

    /// The camera's resolution, (width, height).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.inner.camera.width, self.inner.camera.height)
    }

    /// Renders the scene, as `illum render` does with the same settings (the same pixels bit
    /// for bit). `integrator` and `**params` as `--integrator` and `--param NAME=VALUE` (booleans
    /// for on/off); `width`/`height` as `--width`/`--height`; `report=True` evaluates every pass
    /// (the error-against-time arrays). `samples=(a, b)` and `crop=(x0, y0, x1, y1)` render one
    /// job of a split render, as `--samples A..B` and `--crop X0,Y0,X1,Y1` do: its `write` writes
    /// the partial EXR and `illum.merge` joins the jobs. Ctrl-C stops the render: the result then
    /// holds the samples done (`interrupted` is True).
    #[pyo3(signature = (spp=None, time=None, seed=0, integrator=None, width=None, height=None,
                        trace="auto", device=None, report=false, samples=None, crop=None, **params))]
    #[allow(clippy::too_many_arguments)]
    fn render(
        &self,
        py: Python<'_>,
        spp: Option<u32>,
        time: Option<f64>,
        seed: u64,
        integrator: Option<String>,
        width: Option<u32>,
        height: Option<u32>,
        trace: &str,
        device: Option<String>,
        report: bool,
        samples: Option<(u32, u32)>,
        crop: Option<(u32, u32, u32, u32)>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Render> {
        let scene = at_resolution(&self.inner, width, height)?;
        let args = RenderArgs {
            spp,
            time,
            seed,
            integrator,
            trace: trace.to_string(),
            report,
            params: RenderArgs::params(params, "render")?,
        };
        let (mut settings, cancel) = args.settings(&scene)?;
        settings.samples = samples;
        settings.crop = crop.map(|(x0, y0, x1, y1)| Window { x0, y0, x1, y1 });
        let job = settings.samples.is_some() || settings.crop.is_some();
        let ctx = context(&device).map_err(err)?;
        let mut r = run(py, ctx, settings.clone(), cancel, |r, s, progress| {
            r.render(&scene, s, progress)
        })?;
        r.is_job = job;
        if let Some(out) = r.job.take()
            && job
            && !r.interrupted
        {
            // part_info refuses an output without sums (a frame rendered in bands).
            let info =
                illum::jobs::part_info(&scene, &settings, &out, &r.meta.device).map_err(err)?;
            r.part = out.job.map(|j| (info, j.sums));
        }
        Ok(r)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner.camera;
        format!("<illum.Scene {}x{}>", c.width, c.height)
    }
}

/// The origin a scene from a dict has in messages.
const DICT: &str = "the scene dict";

/// Loads and validates a scene file (JSON or a USD stage), as `illum render FILE` does.
#[pyfunction]
fn load(path: PathBuf) -> PyResult<Scene> {
    let inner = illum::scene::load(&path).map_err(err)?;
    let json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        .then(|| std::fs::read_to_string(&path).ok())
        .flatten()
        .map(|text| Json {
            text,
            base: path.parent().map(PathBuf::from).unwrap_or_default(),
            origin: path.display().to_string(),
        });
    Ok(Scene { inner, json })
}

/// The built-in default scene (what `illum render` renders without a scene file).
#[pyfunction]
fn default_scene() -> Scene {
    Scene {
        inner: illum::scene::default_scene(),
        json: None,
    }
}

/// A scene uploaded once, with its trace structure and kernels (`illum.prepare`): renders again
/// without uploading, and edits (lights, materials, the camera, instance transforms) rewrite only
/// what they change (`PreparedScene::update`), giving the pixels a fresh load of the edited scene
/// gives.
#[pyclass(module = "illum", unsendable)]
struct Prepared {
    ctx: Context,
    prepared: illum::render::PreparedScene,
    scene: illum::scene::Scene,
    json: Option<(serde_json::Value, Json)>,
}

/// Prepares `scene` for repeated renders and edits.
#[pyfunction]
#[pyo3(signature = (scene, trace="auto", device=None))]
fn prepare(
    py: Python<'_>,
    scene: &Scene,
    trace: &str,
    device: Option<String>,
) -> PyResult<Prepared> {
    let trace = trace_mode(trace)?;
    let json = match &scene.json {
        Some(j) => Some((
            serde_json::from_str(&j.text).map_err(|e| err(anyhow::anyhow!("{}: {e}", j.origin)))?,
            j.clone(),
        )),
        None => None,
    };
    let ctx = context(&device).map_err(err)?;
    let job = SameThread((ctx.clone(), &scene.inner));
    let prepared = py
        .detach(move || {
            let (ctx, s) = job.get();
            SameThread(Renderer::new(ctx).prepare(s, trace))
        })
        .0
        .map_err(err)?;
    Ok(Prepared {
        ctx,
        prepared,
        scene: scene.inner.clone(),
        json,
    })
}

impl Prepared {
    /// Sets `fields` of the JSON object `section` (or its member `name`), validates the edited
    /// scene as a load would and brings the prepared scene to it; on any error nothing changes.
    fn edit(
        &mut self,
        py: Python<'_>,
        what: &str,
        section: &str,
        name: Option<&str>,
        fields: &[(String, Bound<'_, PyAny>)],
    ) -> PyResult<()> {
        let Some((value, j)) = &self.json else {
            return Err(IllumError::new_err(format!(
                "{what}: edits need a scene loaded from JSON or made by Scene.from_dict"
            )));
        };
        let mut value = value.clone();
        let obj = match name {
            Some(n) => {
                let names: Vec<String> = value[section]
                    .as_object()
                    .map(|o| o.keys().cloned().collect())
                    .unwrap_or_default();
                value[section]
                    .get_mut(n)
                    .and_then(|v| v.as_object_mut())
                    .ok_or_else(|| {
                        IllumError::new_err(format!(
                            "{what}: {}: no {section}.{n} (it has: {})",
                            j.origin,
                            names.join(", ")
                        ))
                    })?
            }
            None => value
                .get_mut(section)
                .and_then(|v| v.as_object_mut())
                .ok_or_else(|| {
                    IllumError::new_err(format!("{what}: {}: no {section}", j.origin))
                })?,
        };
        let dumps = py.import("json")?.getattr("dumps")?;
        for (k, v) in fields {
            let text: String = dumps.call1((v,))?.extract()?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| err(anyhow::anyhow!("{what}({k}=...): {e}")))?;
            obj.insert(k.clone(), v);
        }
        let text = value.to_string();
        let scene = illum::scene::from_json_str(&text, &j.origin, &j.base).map_err(err)?;
        self.prepared.update(&self.ctx, &scene).map_err(err)?;
        let j = Json { text, ..j.clone() };
        self.scene = scene;
        self.json = Some((value, j));
        Ok(())
    }
}

fn fields<'py>(kw: Option<&Bound<'py, PyDict>>) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    let mut out = Vec::new();
    if let Some(kw) = kw {
        for (k, v) in kw.iter() {
            out.push((k.extract()?, v));
        }
    }
    Ok(out)
}

#[pymethods]
impl Prepared {
    /// Sets fields of light `name` as the scene format names them (e.g. intensity=4,
    /// color=[1, 0.9, 0.8]): its table is rewritten, nothing else.
    #[pyo3(signature = (name, **fields))]
    fn set_light(
        &mut self,
        py: Python<'_>,
        name: &str,
        fields: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let f = self::fields(fields)?;
        self.edit(py, "set_light", "lights", Some(name), &f)
    }

    /// Sets fields of material `name` (e.g. diffuse=[0.5, 0.5, 0.5]).
    #[pyo3(signature = (name, **fields))]
    fn set_material(
        &mut self,
        py: Python<'_>,
        name: &str,
        fields: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let f = self::fields(fields)?;
        self.edit(py, "set_material", "materials", Some(name), &f)
    }

    /// Sets fields of the camera (position, look_at, up, fov_y, resolution): nothing is uploaded.
    #[pyo3(signature = (**fields))]
    fn set_camera(&mut self, py: Python<'_>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let f = self::fields(fields)?;
        self.edit(py, "set_camera", "camera", None, &f)
    }

    /// Sets the transform of shape `name` (as the scene format's `transform`): the trace
    /// structure's top level is rebuilt, no mesh is uploaded again.
    fn set_transform(
        &mut self,
        py: Python<'_>,
        name: &str,
        transform: Bound<'_, PyAny>,
    ) -> PyResult<()> {
        self.edit(
            py,
            "set_transform",
            "shapes",
            Some(name),
            &[("transform".to_string(), transform)],
        )
    }

    /// The scene as edited so far.
    #[getter]
    fn scene(&self) -> Scene {
        Scene {
            inner: self.scene.clone(),
            json: self.json.as_ref().map(|(_, j)| j.clone()),
        }
    }

    /// Renders as `Scene.render` does (the trace path and device are the prepared scene's),
    /// without uploading the scene again.
    #[pyo3(signature = (spp=None, time=None, seed=0, integrator=None, report=false, **params))]
    #[allow(clippy::too_many_arguments)]
    fn render(
        &self,
        py: Python<'_>,
        spp: Option<u32>,
        time: Option<f64>,
        seed: u64,
        integrator: Option<String>,
        report: bool,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Render> {
        let args = RenderArgs {
            spp,
            time,
            seed,
            integrator,
            trace: "auto".into(),
            report,
            params: RenderArgs::params(params, "render")?,
        };
        // Trace "auto": the path the scene was prepared for.
        let (settings, cancel) = args.settings(&self.scene)?;
        let job = SameThread((&self.prepared, &self.scene.camera));
        let mut r = run(
            py,
            self.ctx.clone(),
            settings,
            cancel,
            move |r, s, progress| {
                let (prepared, camera) = job.get();
                let mut outs = r.render_prepared(prepared, camera, s, &[s.seed], progress)?;
                Ok(outs.pop().expect("one render per seed"))
            },
        )?;
        r.job = None;
        Ok(r)
    }

    fn __repr__(&self) -> String {
        let c = &self.scene.camera;
        format!(
            "<illum.Prepared {}x{}, {}>",
            c.width,
            c.height,
            self.prepared.trace_name()
        )
    }
}

/// Every Vulkan device illum sees, as dicts (what `illum devices` prints).
#[pyfunction]
fn devices(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = py.detach(illum::vk::list_devices).map_err(err)?;
    let out = PyList::empty(py);
    for d in list {
        let e = PyDict::new(py);
        e.set_item("index", d.index)?;
        e.set_item("name", d.name)?;
        e.set_item("kind", d.kind)?;
        e.set_item("driver", d.driver)?;
        e.set_item("api_version", d.api_version)?;
        e.set_item("device_local_memory", d.device_local_memory)?;
        e.set_item("ray_query", d.ray_query)?;
        e.set_item("missing", d.missing)?;
        out.append(e)?;
    }
    Ok(out)
}

/// The Vulkan validation layers' messages so far, of every device context of this thread (with
/// ILLUM_VALIDATION=1; the tests fail on any).
#[pyfunction]
fn validation_messages() -> Vec<String> {
    CONTEXTS.with(|c| {
        c.borrow()
            .iter()
            .flat_map(|(_, ctx)| ctx.validation_messages())
            .collect()
    })
}

/// Reinterprets RGB triples as their floats without copying.
fn flat(v: Vec<[f32; 3]>) -> Vec<f32> {
    let mut v = std::mem::ManuallyDrop::new(v);
    let (ptr, len, cap) = (v.as_mut_ptr(), v.len(), v.capacity());
    // SAFETY: [f32; 3] is three f32s with f32's alignment, so the allocation of `cap` triples
    // is exactly the allocation of 3 * cap floats (same size and alignment), `len` triples of
    // which are initialised.
    unsafe { Vec::from_raw_parts(ptr.cast::<f32>(), len * 3, cap * 3) }
}

/// A job's samples (a, b), window (x0, y0, x1, y1) and frame (width, height).
type JobShape = ((u32, u32), (u32, u32, u32, u32), (u32, u32));

/// A render's result: NumPy float32 arrays (height, width[, 3]) holding the film's planes, the
/// metadata of its EXR header and its error-against-time report.
#[pyclass(module = "illum", frozen)]
struct Render {
    #[pyo3(get)]
    beauty: Py<PyAny>,
    #[pyo3(get)]
    albedo: Py<PyAny>,
    #[pyo3(get)]
    normal: Py<PyAny>,
    /// Distance along the camera ray (+inf where nothing was hit).
    #[pyo3(get)]
    depth: Py<PyAny>,
    #[pyo3(get)]
    emission: Py<PyAny>,
    /// The per-pixel variance of the beauty mean, or None.
    #[pyo3(get)]
    variance: Py<PyAny>,
    /// Samples each pixel took: a job's of its own range, and at witness pixels twice the
    /// render's spp (src/film/split.rs).
    #[pyo3(get)]
    samples: Py<PyAny>,
    /// The integrator's AOV planes by name (e.g. Direct, IndirectDiffuse, Reflection).
    #[pyo3(get)]
    aovs: Py<PyDict>,
    /// What the EXR header holds, as strings by attribute name.
    #[pyo3(get)]
    metadata: Py<PyDict>,
    /// One entry per pass (with report=True; else the last): arrays spp, wall_seconds,
    /// device_seconds, estimated_relmse and relmse (against a reference: `illum.compare`'s; NaN
    /// where unknown).
    #[pyo3(get)]
    report: Py<PyDict>,
    /// Samples per pixel rendered.
    #[pyo3(get)]
    spp: u32,
    /// Whether Ctrl-C stopped the render early.
    #[pyo3(get)]
    interrupted: bool,
    width: u32,
    height: u32,
    /// The EXR header, for `write`.
    meta: ImageMetadata,
    /// Whether the film had per-pixel counts.
    has_counts: bool,
    /// A job of a split render: what its partial EXR holds (None when it was interrupted).
    part: Option<(PartInfo, FilmSums)>,
    is_job: bool,
    /// The render's output (its film moved into the arrays), until a job's part is made.
    job: Option<RenderOutput>,
}

impl Render {
    fn new(
        py: Python<'_>,
        mut out: RenderOutput,
        meta: ImageMetadata,
        stopped: bool,
    ) -> PyResult<Render> {
        let film = std::mem::replace(&mut out.film, Film::new(0, 0));
        let interrupted = stopped || out.stats.interrupted;
        // What each pixel took: a job's own samples over its window, else the render's.
        let (taken, origin) = out.job.as_ref().map_or((out.stats.spp, (0, 0)), |j| {
            (j.range.1 - j.range.0, (j.sums.window.x0, j.sums.window.y0))
        });
        let counts = (out.stats.split, taken, origin);
        let mut r = Render::from_film(
            py,
            film,
            meta,
            out.stats.spp,
            counts,
            interrupted,
            &out.passes,
        )?;
        r.job = Some(out);
        Ok(r)
    }

    fn from_film(
        py: Python<'_>,
        film: Film,
        meta: ImageMetadata,
        spp: u32,
        (split, taken, (x0, y0)): (illum::film::Split, u32, (u32, u32)),
        interrupted: bool,
        passes: &[illum::render::PassReport],
    ) -> PyResult<Render> {
        let (w, h) = (film.width as usize, film.height as usize);
        let rgb = |v: Vec<[f32; 3]>| -> PyResult<Py<PyAny>> {
            Ok(PyArray1::from_vec(py, flat(v))
                .reshape([h, w, 3])?
                .into_any()
                .unbind())
        };
        let mono = |v: Vec<f32>| -> PyResult<Py<PyAny>> {
            Ok(PyArray1::from_vec(py, v)
                .reshape([h, w])?
                .into_any()
                .unbind())
        };
        let has_counts = film.samples.is_some();
        // Without a SampleCount plane every pixel took spp samples, but for witness pixels twice.
        let counts = film.samples.unwrap_or_else(|| {
            split
                .counts(x0, y0, w as u32, h as u32, taken)
                .into_iter()
                .map(|c| c as f32)
                .collect()
        });
        let aovs = PyDict::new(py);
        for AovPlane { name, rgb: plane } in film.aovs {
            aovs.set_item(name, rgb(plane)?)?;
        }
        let md = PyDict::new(py);
        md.set_item("illum.spp", meta.spp.to_string())?;
        md.set_item("illum.seed", meta.seed.to_string())?;
        md.set_item("illum.device", meta.device.clone())?;
        md.set_item("illum.renderSeconds", format!("{:.6}", meta.render_seconds))?;
        md.set_item("illum.setupSeconds", format!("{:.6}", meta.setup_seconds))?;
        for (k, v) in &meta.extra {
            md.set_item(k, v)?;
        }
        let rep = PyDict::new(py);
        let col = |f: &dyn Fn(&illum::render::PassReport) -> f64| -> Py<PyAny> {
            PyArray1::from_vec(py, passes.iter().map(f).collect::<Vec<f64>>())
                .into_any()
                .unbind()
        };
        rep.set_item("spp", col(&|p| f64::from(p.spp)))?;
        rep.set_item("wall_seconds", col(&|p| p.wall_seconds))?;
        rep.set_item("device_seconds", col(&|p| p.device_seconds))?;
        rep.set_item(
            "estimated_relmse",
            col(&|p| p.estimated_relmse.unwrap_or(f64::NAN)),
        )?;
        rep.set_item("relmse", col(&|p| p.error.map_or(f64::NAN, |e| e.relmse)))?;
        Ok(Render {
            beauty: rgb(film.beauty)?,
            albedo: rgb(film.albedo)?,
            normal: rgb(film.normal)?,
            depth: mono(film.depth)?,
            emission: rgb(film.emission)?,
            variance: match film.variance {
                Some(v) => rgb(v)?,
                None => py.None(),
            },
            samples: mono(counts)?,
            aovs: aovs.unbind(),
            metadata: md.unbind(),
            report: rep.unbind(),
            spp,
            interrupted,
            width: film.width,
            height: film.height,
            meta,
            has_counts,
            part: None,
            is_job: false,
            job: None,
        })
    }

    /// The film the arrays hold now (copied out of them).
    fn film(&self, py: Python<'_>) -> PyResult<Film> {
        let rgb = |a: &Py<PyAny>| -> PyResult<Vec<[f32; 3]>> {
            let a = a.bind(py).cast::<numpy::PyArray3<f32>>()?.try_readonly()?;
            let s = a.as_slice()?;
            Ok(s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        };
        let mono = |a: &Py<PyAny>| -> PyResult<Vec<f32>> {
            let a = a.bind(py).cast::<numpy::PyArray2<f32>>()?.try_readonly()?;
            Ok(a.as_slice()?.to_vec())
        };
        let mut aovs = Vec::new();
        for (k, v) in self.aovs.bind(py).iter() {
            aovs.push(AovPlane {
                name: k.extract()?,
                rgb: rgb(&v.unbind())?,
            });
        }
        Ok(Film {
            width: self.width,
            height: self.height,
            beauty: rgb(&self.beauty)?,
            albedo: rgb(&self.albedo)?,
            normal: rgb(&self.normal)?,
            depth: mono(&self.depth)?,
            emission: rgb(&self.emission)?,
            variance: if self.variance.is_none(py) {
                None
            } else {
                Some(rgb(&self.variance)?)
            },
            samples: if self.has_counts {
                Some(mono(&self.samples)?)
            } else {
                None
            },
            aovs,
        })
    }
}

#[pymethods]
impl Render {
    /// Writes the image as `illum render -o PATH` does: an EXR (every plane, the same header),
    /// or a PNG (tone-mapped beauty) for a .png path; written to a temporary file and renamed. A
    /// job of a split render writes its partial EXR (the exact sums `illum merge` takes).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        if self.is_job && self.part.is_none() {
            // As `illum render --samples/--crop`: a job is all or nothing.
            return Err(IllumError::new_err(format!(
                "{}: the job was interrupted after {} samples: an incomplete job has no part to \
                 write; render it again",
                path.display(),
                self.spp
            )));
        }
        if let Some((info, sums)) = &self.part {
            if !path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
            {
                return Err(IllumError::new_err(format!(
                    "{}: a job of a split render writes a partial EXR: name a .exr file",
                    path.display()
                )));
            }
            return illum::jobs::partial::write_partial(&path, info, sums)
                .map_err(|e| err(illum::Error::from(e)));
        }
        let film = self.film(py)?;
        let png = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        let r = if png {
            illum::output::write_png(&path, &film)
        } else {
            illum::output::write_exr(&path, &film, &self.meta)
        };
        r.map_err(|e| err(illum::Error::from(e)))
    }

    /// (width, height).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// For a job of a split render: its samples (a, b), window (x0, y0, x1, y1) and the frame's
    /// (width, height); else None.
    #[getter]
    fn job(&self) -> Option<JobShape> {
        self.part.as_ref().map(|(i, _)| {
            let w = i.window;
            (i.samples, (w.x0, w.y0, w.x1, w.y1), i.frame)
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "<illum.Render {}x{}, {} spp{}>",
            self.width,
            self.height,
            self.spp,
            if self.interrupted {
                ", interrupted"
            } else {
                ""
            }
        )
    }
}

#[pymodule]
fn _illum(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("IllumError", m.py().get_type::<IllumError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Render>()?;
    m.add_class::<Prepared>()?;
    m.add_function(wrap_pyfunction!(prepare, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_class::<compare::Comparison>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(default_scene, m)?)?;
    m.add_function(wrap_pyfunction!(devices, m)?)?;
    m.add_function(wrap_pyfunction!(validation_messages, m)?)?;
    Ok(())
}
