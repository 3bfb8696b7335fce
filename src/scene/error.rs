//! Scene loading errors. Every message names the file, the field path inside it and the
//! offending value, so that a user can fix the file without reading the source.

use std::fmt::Display;

/// Why a scene (or a file it references) was rejected.
///
/// `file` is the file as the user named it (or the origin passed to
/// [`from_json_str`](crate::scene::from_json_str)); `field` is a path such as
/// `shapes.ball.sphere.radius` or, inside a glTF file, `meshes[2].primitives[0].mode`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The scene file itself could not be read.
    #[error("{file}: cannot read: {message}")]
    Io { file: String, message: String },

    /// Malformed JSON or a value of the wrong type / an unknown field.
    #[error(
        "{file}: line {line} column {column}: {}{message}",
        field_prefix(field)
    )]
    Parse {
        file: String,
        line: usize,
        column: usize,
        field: String,
        message: String,
    },

    /// A well-formed value that breaks a rule of the format.
    #[error("{file}: {field}: {reason}, got {value}")]
    Invalid {
        file: String,
        field: String,
        value: String,
        reason: String,
    },

    /// Something the format (or illum's glTF support) does not allow, with no single value to
    /// show (e.g. a required glTF extension).
    #[error("{file}: {field}: {message}")]
    Unsupported {
        file: String,
        field: String,
        message: String,
    },

    /// A file referenced by the scene (texture, glTF, glTF buffer or image) could not be read.
    #[error("{file}: {field}: cannot read \"{path}\": {message}")]
    FileRead {
        file: String,
        field: String,
        path: String,
        message: String,
    },

    /// A referenced image or buffer was read but could not be decoded.
    #[error("{file}: {field}: cannot decode \"{path}\": {message}")]
    Decode {
        file: String,
        field: String,
        path: String,
        message: String,
    },
}

fn field_prefix(field: &str) -> String {
    if field.is_empty() || field == "." {
        String::new()
    } else {
        format!("{field}: ")
    }
}

impl SceneError {
    pub(crate) fn invalid(
        file: &str,
        field: impl Into<String>,
        value: impl Display,
        reason: impl Into<String>,
    ) -> Self {
        SceneError::Invalid {
            file: file.to_owned(),
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    pub(crate) fn unsupported(
        file: &str,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Unsupported {
            file: file.to_owned(),
            field: field.into(),
            message: message.into(),
        }
    }

    pub(crate) fn file_read(
        file: &str,
        field: impl Into<String>,
        path: impl Display,
        err: &std::io::Error,
    ) -> Self {
        SceneError::FileRead {
            file: file.to_owned(),
            field: field.into(),
            path: path.to_string(),
            message: io_message(err),
        }
    }

    pub(crate) fn decode(
        file: &str,
        field: impl Into<String>,
        path: impl Display,
        message: impl Display,
    ) -> Self {
        SceneError::Decode {
            file: file.to_owned(),
            field: field.into(),
            path: path.to_string(),
            message: message.to_string(),
        }
    }

    /// A serde_json error (with or without a tracked field path) from parsing `file`.
    pub(crate) fn from_json(file: &str, field: String, err: &serde_json::Error) -> Self {
        let suffix = format!(" at line {} column {}", err.line(), err.column());
        let text = err.to_string();
        let message = text.strip_suffix(&suffix).unwrap_or(&text);
        SceneError::Parse {
            file: file.to_owned(),
            line: err.line(),
            column: err.column(),
            field,
            // serde quotes names with backticks; JSON users expect double quotes.
            message: message.replace('`', "\""),
        }
    }
}

/// Most bytes read from a scene file (JSON text; larger meshes belong in glTF files).
pub const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;
/// Most bytes read from a file a scene references: a texture, a glTF file or a glTF buffer.
pub const MAX_ASSET_FILE_BYTES: u64 = 1 << 30;

/// Reads a whole file, but no more than `cap` bytes: a link to an endless stream (/dev/zero, a
/// pipe that never closes) is an error naming the cap instead of a read that grows without bound.
pub(crate) fn read_capped(path: &std::path::Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    let too_large = || {
        std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!(
                "larger than {} MiB, the most illum reads from such a file{}",
                cap >> 20,
                if meta.is_file() {
                    ""
                } else {
                    " (it is not a regular file: an endless stream such as /dev/zero?)"
                }
            ),
        )
    };
    if meta.is_file() && meta.len() > cap {
        return Err(too_large());
    }
    let mut bytes = Vec::new();
    file.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(too_large());
    }
    Ok(bytes)
}

/// The OS message without Rust's " (os error N)" suffix.
pub(crate) fn io_message(err: &std::io::Error) -> String {
    let text = err.to_string();
    match text.rfind(" (os error ") {
        Some(i) if text.ends_with(')') => text[..i].to_owned(),
        _ => text,
    }
}

/// Formats a number the way it looks in JSON: `-1`, `0.5`, `1e300` (not 300 digits).
pub(crate) fn fmt_num(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-6..1e16).contains(&a) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// Formats a vector as `[a, b, c]`.
pub(crate) fn fmt_vec(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|&x| fmt_num(x)).collect();
    format!("[{}]", items.join(", "))
}

/// Formats a string value quoted, as in the file.
pub(crate) fn quoted(s: &str) -> String {
    format!("\"{s}\"")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_as_in_json() {
        assert_eq!(fmt_num(-1.0), "-1");
        assert_eq!(fmt_num(0.5), "0.5");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(1e300), "1e300");
        assert_eq!(fmt_num(-2.5e-9), "-2.5e-9");
        assert_eq!(fmt_vec(&[1.0, -0.25, 1e20]), "[1, -0.25, 1e20]");
    }

    #[test]
    fn reads_are_capped() {
        let e = read_capped(std::path::Path::new("/dev/zero"), 1 << 20).unwrap_err();
        let m = io_message(&e);
        assert!(
            m.contains("larger than 1 MiB") && m.contains("/dev/zero"),
            "{m}"
        );
        let dir = std::env::temp_dir().join(format!("illum-cap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("two-mib.bin");
        std::fs::write(&f, vec![0u8; 2 << 20]).unwrap();
        let m = io_message(&read_capped(&f, 1 << 20).unwrap_err());
        assert!(
            m.contains("larger than 1 MiB") && !m.contains("regular"),
            "{m}"
        );
        assert_eq!(read_capped(&f, 2 << 20).unwrap().len(), 2 << 20);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn io_messages_drop_the_os_error_code() {
        let e = std::fs::read("/definitely/not/here").unwrap_err();
        assert_eq!(io_message(&e), "No such file or directory");
    }
}
