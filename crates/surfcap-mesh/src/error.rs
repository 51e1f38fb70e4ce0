//! One error type for every reader, writer and check of the data layer.
//!
//! An error always says *which file*, *where in it* (line, frame, byte offset, face) and *what was
//! expected*, so that a user can open the file and fix it. Library code never panics on input data.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file (or in a sequence) a problem was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of a text file.
    Line(usize),
    /// 0-based frame of a sequence.
    Frame(usize),
    /// Byte offset in a binary file.
    Byte(u64),
    /// 0-based triangle of a topology.
    Face(usize),
    /// Frame (0-based) of a sequence, then line of that frame's file.
    FrameLine { frame: usize, line: usize },
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Frame(i) => write!(f, "frame {i}"),
            Location::Byte(b) => write!(f, "byte {b}"),
            Location::Face(i) => write!(f, "triangle {i}"),
            Location::FrameLine { frame, line } => write!(f, "frame {frame}, line {line}"),
        }
    }
}

/// What kind of problem it is, so callers and tests can match on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The operating system refused a read or write.
    Io,
    /// A token or header could not be parsed.
    Syntax,
    /// A NaN or infinite coordinate.
    NonFinite,
    /// A face index that is zero (OBJ is 1-based), negative beyond the list, or past the end.
    IndexOutOfRange,
    /// A face that uses the same vertex twice, or has fewer than three corners.
    DegenerateFace,
    /// A file with no data where data was required.
    Empty,
    /// A binary file that ends before the size its header declares.
    Truncated,
    /// An array element type that cannot be used here.
    DType,
    /// An array shape that does not match what is expected.
    Shape,
    /// A frame whose vertex count or faces differ from the template's.
    TopologyMismatch,
    /// Metadata that is missing or contradicts other metadata (fps, up axis, units, names).
    Metadata,
    /// A request the program does not support (unknown format, bad argument value).
    Unsupported,
    /// An output that would destroy what surfcap did not write: one of the command's inputs, a
    /// device, FIFO or socket, or a folder without surfcap's marker.
    Refused,
}

/// An error of the data layer: what went wrong, in which file, and where.
#[derive(Debug)]
pub struct Error {
    pub kind: ErrorKind,
    pub path: Option<PathBuf>,
    pub location: Option<Location>,
    pub message: String,
    source: Option<std::io::Error>,
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Error { kind, path: None, location: None, message: message.into(), source: None }
    }

    /// An I/O failure on `path`, keeping the OS error as the source.
    pub fn io(path: &Path, action: &str, err: std::io::Error) -> Self {
        Error {
            kind: ErrorKind::Io,
            path: Some(path.to_path_buf()),
            location: None,
            message: format!("cannot {action}: {err}"),
            source: Some(err),
        }
    }

    /// Attach the file, unless a more specific one is already set.
    pub fn in_file(mut self, path: &Path) -> Self {
        if self.path.is_none() {
            self.path = Some(path.to_path_buf());
        }
        self
    }

    /// Attach a location, unless a more specific one is already set.
    pub fn at(mut self, location: Location) -> Self {
        if self.location.is_none() {
            self.location = Some(location);
        }
        self
    }

    pub fn at_line(self, line: usize) -> Self {
        self.at(Location::Line(line))
    }

    pub fn at_frame(self, frame: usize) -> Self {
        match self.location {
            Some(Location::Line(line)) => Error { location: Some(Location::FrameLine { frame, line }), ..self },
            _ => self.at(Location::Frame(frame)),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.path, &self.location) {
            (Some(p), Some(l)) => write!(f, "{}: {l}: {}", p.display(), self.message),
            (Some(p), None) => write!(f, "{}: {}", p.display(), self.message),
            (None, Some(l)) => write!(f, "{l}: {}", self.message),
            (None, None) => write!(f, "{}", self.message),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.source.as_ref().map(|e| e as _)
    }
}

/// Shorthand for building an error of a given kind with a formatted message
/// (`err!(Syntax, "line {n}: ...")`); the format readers of `surfcap-formats` use it too.
#[macro_export]
macro_rules! err {
    ($kind:ident, $($arg:tt)*) => {
        $crate::error::Error::new($crate::error::ErrorKind::$kind, format!($($arg)*))
    };
}
pub use crate::err;
