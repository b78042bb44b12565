//! The one error type of the crate: every message is one line that names the file, the problem
//! and what was expected.

use std::path::{Path, PathBuf};

/// A file that could not be read, parsed or validated (or written).
///
/// `Display` is a single line starting with the file's path, e.g.
/// `buildings/x.toml: walls[3].thickness: must be a positive number of metres, got -0.2`.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened, read or written.
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        /// What was attempted ("read", "write", "create directory").
        action: &'static str,
        source: std::io::Error,
    },
    /// The text is not valid YAML/TOML/world syntax, or has the wrong shape.
    #[error("{}: {message}", path.display())]
    Syntax { path: PathBuf, message: String },
    /// A value parsed but is not acceptable; `field` locates it (`walls[3].polygon`).
    #[error("{}: {field}: {problem}", path.display())]
    Invalid {
        path: PathBuf,
        field: String,
        problem: String,
    },
    /// An image (named by `field` of the file at `path`) that could not be decoded.
    #[error("{}: {field}: {}: not a readable image ({message}); expected a PGM (P5/P2) or PNG file", path.display(), image.display())]
    Image {
        path: PathBuf,
        field: String,
        image: PathBuf,
        message: String,
    },
    /// Something valid but outside what floorcast supports.
    #[error("{}: unsupported: {what}", path.display())]
    Unsupported { path: PathBuf, what: String },
}

impl Error {
    pub(crate) fn io(path: &Path, action: &'static str, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            action,
            source,
        }
    }
    pub(crate) fn syntax(path: &Path, message: impl AsRef<str>) -> Self {
        Error::Syntax {
            path: path.to_path_buf(),
            message: one_line(message.as_ref()),
        }
    }
    pub(crate) fn invalid(path: &Path, field: impl Into<String>, problem: impl AsRef<str>) -> Self {
        Error::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            problem: one_line(problem.as_ref()),
        }
    }
    pub(crate) fn image(path: &Path, field: &str, image: &Path, message: impl AsRef<str>) -> Self {
        Error::Image {
            path: path.to_path_buf(),
            field: field.to_string(),
            image: image.to_path_buf(),
            message: one_line(message.as_ref()),
        }
    }
    pub(crate) fn unsupported(path: &Path, what: impl AsRef<str>) -> Self {
        Error::Unsupported {
            path: path.to_path_buf(),
            what: one_line(what.as_ref()),
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Error::Io { path, .. }
            | Error::Syntax { path, .. }
            | Error::Invalid { path, .. }
            | Error::Image { path, .. }
            | Error::Unsupported { path, .. } => path,
        }
    }
}

/// Something a reader changed or doubted in a file that it still read (a polygon repaired):
/// one line, like an [`Error`]'s, `path: field: message`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    pub path: PathBuf,
    /// Where in the file (`space[12] (R_3)/bounding_polygon`, `rooms[2].polygon`).
    pub field: String,
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {}: {}",
            self.path.display(),
            self.field,
            one_line(&self.message)
        )
    }
}

/// Joins the lines of a (library) message so that every error stays on one line.
pub(crate) fn one_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// Formats a number for messages: short, and always with a decimal point (`3.0`, `0.05`).
pub(crate) fn num(v: f64) -> String {
    if v.is_finite() && v == v.trunc() && v.abs() < 1e15 {
        format!("{v:.1}")
    } else if v.is_finite() && (v.abs() >= 1e15 || v.abs() < 1e-4) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Formats a length or coordinate in metres (or an area in m²) for messages, rounded to the
/// millimetre: `54.0` (not `54.00000000000001`), `0.412`; as [`num`] when too large to round.
pub(crate) fn metres(v: f64) -> String {
    if !v.is_finite() || v.abs() >= 1e12 {
        return num(v);
    }
    // n / 1000 is the double nearest the decimal: it prints with at most 3 decimals.
    let r = (v * 1000.0).round() / 1000.0;
    num(if r == 0.0 { 0.0 } else { r })
}

/// Formats a point for messages, in metres to the millimetre: `(3.0, 4.25)`.
pub(crate) fn point(x: f64, y: f64) -> String {
    format!("({}, {})", metres(x), metres(y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (value, as printed)
    #[test]
    fn coordinates_print_to_the_millimetre() {
        let cases: &[(f64, &str)] = &[
            (54.00000000000001, "54.0"),
            (53.99999999999999, "54.0"),
            (0.1 + 0.2, "0.3"),
            (3.0, "3.0"),
            (-2.5, "-2.5"),
            (0.41251, "0.413"),
            (0.0004, "0.0"),
            (-0.0004, "0.0"),
            (-0.0, "0.0"),
            (123456.78949, "123456.789"),
            (2e15, "2e15"),
            (f64::INFINITY, "inf"),
        ];
        for (v, want) in cases {
            assert_eq!(metres(*v), *want, "{v}");
        }
        assert_eq!(
            point(54.00000000000001, -0.30000000000000004),
            "(54.0, -0.3)"
        );
    }
}
