//! The integrators and their table. Each integrator is a module of its own that parses its own
//! parameters (refusing names it does not take) and implements [`crate::render::Integrator`];
//! [`INTEGRATORS`] is the one list that the command line, scene files, the C API, `compare` and
//! `merge` read. Adding an integrator is its module plus one line there.

pub mod direct;
pub mod indirect;

pub use direct::{ControlVariates, Direct, DirectLighting, LightSelection, Technique};
pub use indirect::{Full, Path};

use crate::render::{Integrator, Params, RenderSettings};
use std::sync::Arc;

/// One integrator of the table.
pub struct Registration {
    pub name: &'static str,
    /// One line for help texts.
    pub summary: &'static str,
    /// The AOV planes its film adds (the same as its [`Integrator::aov_planes`]).
    pub aov_planes: &'static [&'static str],
    /// Reads its parameters, refusing any it does not take.
    pub create: fn(&Params) -> Result<Arc<dyn Integrator>, String>,
}

/// Every integrator, the default first.
pub const INTEGRATORS: &[Registration] = &[
    Registration {
        name: "direct",
        summary: "direct lighting only (emission seen directly, direct lighting at the camera hit)",
        aov_planes: &[],
        create: |p| Ok(Arc::new(Direct::parse(p)?)),
    },
    Registration {
        name: "full",
        summary: "direct lighting, indirect diffuse through the radiosity cache, and reflections",
        aov_planes: indirect::PLANES,
        create: |p| Ok(Arc::new(Full::parse(p)?)),
    },
    Registration {
        name: "path",
        summary: "a brute-force unidirectional path tracer (all light paths)",
        aov_planes: indirect::PLANES,
        create: |p| Ok(Arc::new(Path::parse(p)?)),
    },
];

/// The names of the table, for messages.
pub fn names() -> String {
    let n: Vec<&str> = INTEGRATORS.iter().map(|r| r.name).collect();
    n.join(", ")
}

/// The integrator `name` with parameters `params`.
pub fn create(name: &str, params: &Params) -> Result<Arc<dyn Integrator>, String> {
    let r = INTEGRATORS
        .iter()
        .find(|r| r.name == name)
        .ok_or_else(|| format!("unknown integrator {name:?} (expected one of {})", names()))?;
    (r.create)(params)
}

/// The integrator a render uses: the one the caller names, else the scene's, else the default.
pub fn chosen(given: Option<&str>, scene: &crate::scene::Scene) -> String {
    given
        .map(str::to_string)
        .or_else(|| scene.integrator.name.clone())
        .unwrap_or_else(|| default_integrator().name().to_string())
}

/// The parameters a scene's `integrator` section gives integrator `name` (none when the section
/// names another one), each named by its origin: what every front end (the CLI, Python) starts
/// from before its own options.
pub fn scene_params(name: &str, scene: &crate::scene::Scene) -> Params {
    let mut p = Params::new();
    let c = &scene.integrator;
    if c.name.as_deref().is_none_or(|n| n == name) {
        let file = scene
            .source
            .as_ref()
            .map_or_else(|| "the scene".to_string(), |s| s.display().to_string());
        for (k, v) in &c.params {
            p.set(k, v, format!("{file}: integrator.{k}"));
        }
    }
    p
}

/// The default integrator with its default parameters.
pub fn default_integrator() -> Arc<dyn Integrator> {
    Arc::new(Direct::measured())
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings::with_integrator(default_integrator())
    }
}

impl From<Direct> for Arc<dyn Integrator> {
    fn from(i: Direct) -> Self {
        Arc::new(i)
    }
}

impl From<Full> for Arc<dyn Integrator> {
    fn from(i: Full) -> Self {
        Arc::new(i)
    }
}

impl From<Path> for Arc<dyn Integrator> {
    fn from(i: Path) -> Self {
        Arc::new(i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_integrator_declares_the_planes_it_renders() {
        for r in INTEGRATORS {
            let i = (r.create)(&Params::new()).unwrap();
            assert_eq!(i.name(), r.name);
            assert_eq!(i.aov_planes(), r.aov_planes, "{}", r.name);
            assert!(i.check().is_ok());
        }
        assert_eq!(default_integrator().name(), INTEGRATORS[0].name);
    }

    #[test]
    fn unknown_names_and_parameters_are_refused() {
        let e = create("fool", &Params::new()).unwrap_err();
        assert!(
            e.contains("fool") && e.contains("direct, full, path"),
            "{e}"
        );
        let mut p = Params::new();
        p.set("max_depth", "3", "--max-depth");
        let e = create("direct", &p).unwrap_err();
        assert!(e.contains("max_depth (--max-depth)"), "{e}");
        assert!(create("path", &p).is_ok());
        p.set("light_samples", "65", "--light-samples");
        let e = create("path", &p).unwrap_err();
        assert!(e.contains("1..=64"), "{e}");
    }
}
