//! The one error type of surfcap-plot.

use std::path::PathBuf;

use plotters::prelude::*;

/// plotters' drawing error for the SVG backend (its backend error is an I/O error).
pub type SvgDrawingError = DrawingAreaErrorKind<<SVGBackend<'static> as DrawingBackend>::ErrorType>;
/// plotters' drawing error for the PNG (bitmap) backend.
pub type PngDrawingError = DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

/// Why a chart or heat map could not be written: data that does not fit the figure, a drawing
/// that plotters refused (its error kept as the source), or a file or folder that could not be
/// written (the I/O error kept as the source). Every message starts with the path concerned.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Drawing the SVG figure `path` failed.
    #[error("{}: {source}", path.display())]
    DrawSvg {
        path: PathBuf,
        #[source]
        source: SvgDrawingError,
    },
    /// Drawing (and encoding) the PNG figure `path` failed.
    #[error("{}: {source}", path.display())]
    DrawPng {
        path: PathBuf,
        #[source]
        source: PngDrawingError,
    },
    /// Writing `path` failed, or surfcap-mesh's writer refused the place (its message names
    /// the file and why).
    #[error("{}: cannot write the figure", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: Box<surfcap_mesh::Error>,
    },
    /// A heat map whose `values` do not fill its `rows` x `cols` (or that has no cell).
    #[error("{}: {values} values for a {rows} x {cols} heat map", stem.display())]
    HeatMapShape { stem: PathBuf, values: usize, rows: usize, cols: usize },
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
