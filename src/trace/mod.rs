//! Trace structures behind the one GLSL trace interface (glsl/shared/trace.glsl): hardware ray
//! queries (acceleration structures) or illum's compute BVH.

pub mod rayquery;

/// Which implementation of the trace interface a render uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TraceMode {
    /// Ray queries when the device has them, else the compute BVH.
    #[default]
    Auto,
    RayQuery,
    Bvh,
}

impl std::str::FromStr for TraceMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(TraceMode::Auto),
            "rayquery" => Ok(TraceMode::RayQuery),
            "bvh" => Ok(TraceMode::Bvh),
            _ => Err(format!(
                "unknown trace mode {s:?} (expected auto, rayquery or bvh)"
            )),
        }
    }
}
