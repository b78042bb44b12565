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

/// Formats a point for messages: `(3.0, 4.0)`.
pub(crate) fn point(x: f64, y: f64) -> String {
    format!("({}, {})", num(x), num(y))
}
