//! A resolved film: the image planes of one render, as outputs write them.

/// The EXR layers of the film's own RGB planes besides the beauty (`R`, `G`, `B`) and `Z`: albedo,
/// normal, emission and variance (`<layer>.R/G/B`, the normal's `.X/Y/Z`). AOV planes take other
/// names (`super::check_aov_names`).
pub const FILM_LAYERS: [&str; 4] = ["Albedo", "N", "Emission", "Variance"];

/// Linear, scene-referred image planes of one render, row-major, top row first, width*height each.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub beauty: Vec<[f32; 3]>,
    /// AOV "Albedo".
    pub albedo: Vec<[f32; 3]>,
    /// AOV "N" (world-space shading normal, components in [-1,1]).
    pub normal: Vec<[f32; 3]>,
    /// AOV "Z" (distance along the camera ray; +inf where nothing was hit).
    pub depth: Vec<f32>,
    /// AOV "Emission" (radiance of directly seen emitters).
    pub emission: Vec<[f32; 3]>,
    /// AOV "Variance" (per-pixel variance of the beauty mean), when present.
    pub variance: Option<Vec<[f32; 3]>>,
    /// AOV "SampleCount" (samples each pixel took), when they differ (adaptive sampling).
    pub samples: Option<Vec<f32>>,
    /// The AOV planes the integrator declares (`Integrator::aov_planes`), in its order: means
    /// over all samples, written to the EXR as `<name>.R/G/B`.
    pub aovs: Vec<AovPlane>,
}

/// An RGB plane an integrator adds to the film (e.g. `Direct`, `IndirectDiffuse`).
#[derive(Debug, Clone, PartialEq)]
pub struct AovPlane {
    /// The EXR layer name (see `super::check_aov_names`).
    pub name: String,
    /// Per-pixel means, row-major like the film's other planes.
    pub rgb: Vec<[f32; 3]>,
}

impl Film {
    /// A zero-filled film without a variance plane or AOV planes.
    pub fn new(width: u32, height: u32) -> Film {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            beauty: vec![[0.0; 3]; n],
            albedo: vec![[0.0; 3]; n],
            normal: vec![[0.0; 3]; n],
            depth: vec![0.0; n],
            emission: vec![[0.0; 3]; n],
            variance: None,
            samples: None,
            aovs: Vec::new(),
        }
    }

    /// Number of pixels, `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}
