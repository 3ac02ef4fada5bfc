//! The simulator's errors: typed, each saying where (file, line, column)
//! and what, so a program can match on the kind and a person reads one
//! line.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in an input an error is: a file (when known), a 1-based line and
/// optionally a column. Shown as `file:line:column`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file, when the input came from one.
    pub file: Option<PathBuf>,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, when known.
    pub column: Option<usize>,
}

impl Location {
    /// Line `line` of an input without a file name.
    pub fn line(line: usize) -> Self {
        Location {
            file: None,
            line,
            column: None,
        }
    }

    /// Line `line`, column `column` of `file`.
    pub fn at(file: impl Into<PathBuf>, line: usize, column: Option<usize>) -> Self {
        Location {
            file: Some(file.into()),
            line,
            column,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}:", file.display())?;
        }
        write!(f, "{}", self.line)?;
        if let Some(c) = self.column {
            write!(f, ":{c}")?;
        }
        Ok(())
    }
}

/// What can go wrong in the simulator.
///
/// ```
/// use std::path::Path;
/// let e = tilerast_sim::Scene::parse("[screen]\nwidth = 8\nheight = 8\nformat = \"rgb565\"\ndither = 3\n", Path::new("."))
///     .unwrap_err();
/// assert!(matches!(e, tilerast_sim::Error::Invalid { .. }));
/// assert_eq!(e.to_string(), "5: [screen] dither = 3 must be 0, 2, 4, 8 or 16");
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file is larger than [`Limits::max_bytes`](crate::Limits).
    #[error("{}: larger than the limit of {limit} bytes", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit, in bytes.
        limit: u64,
    },
    /// A line is longer than [`Limits::max_line`](crate::Limits).
    #[error("{at}: line longer than the limit of {limit} bytes")]
    LongLine {
        /// The line.
        at: Location,
        /// The limit, in bytes.
        limit: usize,
    },
    /// An input (scene, OBJ, MTL, encoded scene) says something invalid.
    #[error("{at}: {message}")]
    Invalid {
        /// Where.
        at: Location,
        /// What is wrong.
        message: String,
    },
    /// A PNG could not be read or written.
    #[error("{}: {message}", path.display())]
    Png {
        /// The file.
        path: PathBuf,
        /// What the PNG codec said.
        message: String,
    },
    /// Two images to compare differ in size.
    #[error("images differ in size: {a:?} vs {b:?}")]
    SizeMismatch {
        /// Width and height of the first.
        a: (u32, u32),
        /// Width and height of the second.
        b: (u32, u32),
    },
    /// A configuration the simulator does not build (an encoded scene's
    /// header asking for an unknown format or plane).
    #[error("{0}")]
    Unsupported(String),
    /// The raster core refused a command or a size.
    #[error(transparent)]
    Raster(#[from] tilerast::Error),
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// The same error, located in `file` when it had no file yet.
    pub fn in_file(self, file: &Path) -> Self {
        match self {
            Error::Invalid { mut at, message } if at.file.is_none() => {
                at.file = Some(file.to_path_buf());
                Error::Invalid { at, message }
            }
            Error::LongLine { mut at, limit } if at.file.is_none() => {
                at.file = Some(file.to_path_buf());
                Error::LongLine { at, limit }
            }
            e => e,
        }
    }
}

/// The simulator's results.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A number as a person reads it: `1e300`, not 300 digits.
pub(crate) struct Readable(pub(crate) f64);

impl std::fmt::Display for Readable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if v.is_finite() && v.abs() >= 1e7 {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}
