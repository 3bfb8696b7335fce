//! Image outputs: multi-layer EXR and sRGB PNG.
//!
//! The EXR holds every plane of a [`Film`] as 32-bit float channels in one part, named the
//! classic way (`R`,`G`,`B`, `Albedo.R`, `N.X`, `Z`, ..., and `<Name>.R/G/B` for each AOV plane
//! the integrator declares) so compositing and denoising tools find them. The PNG is a
//! display-referred preview of the beauty only.

mod file;
mod metadata;
mod openexr;
mod png;

use std::path::{Path, PathBuf};

pub use file::{
    abort_writes, check_distinct, check_writable, resolve_target, same_file, temp_path_for,
    write_atomically,
};
pub use metadata::image_metadata;
pub use openexr::{ExrImage, read_exr, read_reference, write_exr};
pub use png::{SrgbEncoder, write_png, write_rgb8_png};

pub use crate::film::{AovPlane, Film};

/// Checks that the film is non-empty and every plane has `width * height` pixels; `path` is
/// the file being written, for the error message.
pub(crate) fn validate_film(film: &Film, path: &Path) -> Result<(), OutputError> {
    if film.width == 0 || film.height == 0 {
        return Err(OutputError::EmptyFilm {
            path: path.to_path_buf(),
            width: film.width,
            height: film.height,
        });
    }
    let expected = film.pixel_count();
    let names: Vec<&str> = film.aovs.iter().map(|a| a.name.as_str()).collect();
    if let Err(reason) = crate::film::check_aov_names(&names) {
        return Err(OutputError::AovName {
            path: path.to_path_buf(),
            reason,
        });
    }
    let planes = [
        ("beauty", film.beauty.len()),
        ("albedo", film.albedo.len()),
        ("normal", film.normal.len()),
        ("depth", film.depth.len()),
        ("emission", film.emission.len()),
        (
            "variance",
            film.variance.as_ref().map_or(expected, Vec::len),
        ),
        (
            "sample count",
            film.samples.as_ref().map_or(expected, Vec::len),
        ),
    ];
    let aovs = film.aovs.iter().map(|a| (a.name.as_str(), a.rgb.len()));
    for (plane, len) in planes.into_iter().chain(aovs) {
        if len != expected {
            return Err(OutputError::PlaneSize {
                path: path.to_path_buf(),
                plane: plane.to_string(),
                width: film.width,
                height: film.height,
                len,
            });
        }
    }
    Ok(())
}

/// Facts about a render, stored as EXR header attributes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImageMetadata {
    pub spp: u32,
    /// Steady-state rendering: the passes' wall time (`illum.renderSeconds`).
    pub render_seconds: f64,
    /// Everything before the first pass: kernel compilation, upload, trace-structure build and
    /// the warm-up dispatch (`illum.setupSeconds`).
    pub setup_seconds: f64,
    pub device: String,
    pub seed: u64,
    /// Further string attributes, e.g. `("illum.technique", "mis")`.
    pub extra: Vec<(String, String)>,
}

/// Errors of this module. Every message names the file and includes the underlying cause, so
/// printing the error with `{}` is enough.
impl From<OutputError> for crate::Error {
    fn from(e: OutputError) -> crate::Error {
        crate::Error::Output(Box::new(e))
    }
}

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {}: the film is empty ({width}x{height})", .path.display())]
    EmptyFilm {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error(
        "cannot write {}: film plane `{plane}` has {len} pixels, expected {width}x{height}",
        .path.display()
    )]
    PlaneSize {
        path: PathBuf,
        plane: String,
        width: u32,
        height: u32,
        len: usize,
    },
    #[error("cannot write {}: {reason}", .path.display())]
    AovName { path: PathBuf, reason: String },
    #[error("cannot write {}: EXR attribute `{name}`: {reason}", .path.display())]
    Attribute {
        path: PathBuf,
        name: String,
        reason: String,
    },
    #[error("cannot write EXR {}: {cause}", .path.display())]
    ExrWrite {
        path: PathBuf,
        cause: exr::error::Error,
    },
    #[error("cannot read EXR {}: {cause}", .path.display())]
    ExrRead {
        path: PathBuf,
        cause: exr::error::Error,
    },
    #[error("cannot read EXR {}: {reason}", .path.display())]
    ExrUnsupported { path: PathBuf, reason: String },
    #[error(
        "EXR {} has no RGB beauty (R/G/B or <layer>.R/G/B); its channels are: {}",
        .path.display(), .channels.join(", ")
    )]
    NoBeauty {
        path: PathBuf,
        channels: Vec<String>,
    },
    #[error("cannot write PNG {}: {cause}", .path.display())]
    Png {
        path: PathBuf,
        cause: image::ImageError,
    },
    #[error("cannot write {}: {reason}", .path.display())]
    NotWritable { path: PathBuf, reason: String },
    #[error("did not write {}: a second signal asked to quit at once", .path.display())]
    Aborted { path: PathBuf },
    #[error(
        "reference {} is {width}x{height}, the render {expected_width}x{expected_height}",
        .path.display()
    )]
    ReferenceSize {
        path: PathBuf,
        width: u32,
        height: u32,
        expected_width: u32,
        expected_height: u32,
    },
    #[error("cannot write {}: {cause}", .path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn film_new_is_zeroed_and_valid() {
        let film = Film::new(3, 2);
        assert_eq!(film.pixel_count(), 6);
        assert!(film.beauty.iter().all(|p| *p == [0.0; 3]));
        assert!(film.depth.iter().all(|d| *d == 0.0));
        assert!(film.variance.is_none());
        validate_film(&film, Path::new("x.exr")).unwrap();
    }

    #[test]
    fn validate_names_plane_and_file() {
        let mut film = Film::new(3, 2);
        film.variance = Some(vec![[0.0; 3]; 5]);
        let msg = validate_film(&film, Path::new("dir/out.exr"))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("dir/out.exr") && msg.contains("variance"),
            "{msg}"
        );
        let msg = validate_film(&Film::new(0, 4), Path::new("e.png"))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("e.png") && msg.contains("0x4"), "{msg}");
    }
}
