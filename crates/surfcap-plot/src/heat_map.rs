//! Heat maps of matrices (pose distance matrices, transition costs), optionally with a path
//! drawn on them (a DTW warp, thesis Fig. 2.10-2.11), as SVG and PNG, each with its colour bar:
//! the colour ramp beside the matrix, ticked with the values it stands for and named by
//! [`HeatMap::value_label`].
//!
//! Large matrices are averaged into at most `MAX_CELLS` x `MAX_CELLS` blocks before drawing, so
//! a 2,000-frame distance matrix gives a light SVG; the axes keep the matrix's own indices.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::{Error, Result, write_svg_and_png};

/// Drawn cells per side at most.
const MAX_CELLS: usize = 200;

/// A matrix to draw: row `r` (y axis, from the top) and column `c` (x axis).
#[derive(Debug, Clone)]
pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Row-major `rows x cols` values; non-finite cells are drawn grey.
    pub values: Vec<f64>,
    pub rows: usize,
    pub cols: usize,
    /// Index of the first row and column (a window of a larger matrix keeps its indices).
    pub origin: (usize, usize),
    /// Values drawn from the first to the last colour of the ramp (clamped outside); `None`:
    /// the finite values' own range. Two maps drawn with one range compare by colour.
    pub range: Option<(f64, f64)>,
    /// Cells (row, col) joined by a line on top (in matrix indices, origin included).
    pub path: Vec<(usize, usize)>,
    /// What a colour stands for, with its unit when it has one (e.g. "distance error (m)"):
    /// the colour bar's name.
    pub value_label: String,
}

/// Steps of the colour bar, each a rectangle of one colour of the ramp.
pub const COLOUR_BAR_STEPS: usize = 64;

/// The colour bar's fills from its top (the range's high end) to its bottom, as `#rrggbb`: the
/// ramp at the middle of each step. A drawn colour bar is these rectangles, one above the other.
pub fn colour_bar_fills() -> Vec<String> {
    (0..COLOUR_BAR_STEPS)
        .rev()
        .map(|k| {
            let c = ramp((k as f64 + 0.5) / COLOUR_BAR_STEPS as f64);
            format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
        })
        .collect()
}

/// A tick's text: about four significant digits, in scientific notation far from 1.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.2e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// Viridis-like colour ramp (5 stops) for t in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Block means: (block rows, block cols, values, rows per block, cols per block).
fn blocks(h: &HeatMap) -> (usize, usize, Vec<f64>, usize, usize) {
    let (sr, sc) = (h.rows.div_ceil(MAX_CELLS).max(1), h.cols.div_ceil(MAX_CELLS).max(1));
    let (br, bc) = (h.rows.div_ceil(sr), h.cols.div_ceil(sc));
    let mut out = vec![0.0; br * bc];
    for i in 0..br {
        for j in 0..bc {
            let (mut s, mut n) = (0.0, 0usize);
            for r in i * sr..((i + 1) * sr).min(h.rows) {
                for c in j * sc..((j + 1) * sc).min(h.cols) {
                    let v = h.values[r * h.cols + c];
                    if v.is_finite() {
                        s += v;
                        n += 1;
                    }
                }
            }
            out[i * bc + j] = if n > 0 { s / n as f64 } else { f64::NAN };
        }
    }
    (br, bc, out, sr, sc)
}

/// Width of the colour bar's strip (ramp, ticks and name) at the right of the figure.
const BAR_STRIP: u32 = 110;

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, plotters::coord::Shift>, h: &HeatMap) -> DrawResult<(), DB>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (br, bc, v, sr, sc) = blocks(h);
    let finite = v.iter().copied().filter(|x| x.is_finite());
    let (lo, hi) =
        h.range.unwrap_or_else(|| finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x))));
    // No finite value at all: the bar still says which colour is low and which high.
    let lo = if lo.is_finite() { lo } else { 0.0 };
    let span = if hi > lo { hi - lo } else { 1.0 };
    let (r0, c0) = (h.origin.0 as f64, h.origin.1 as f64);
    let (width, _) = root.dim_in_pixel();
    let (matrix, strip) = root.split_horizontally(width.saturating_sub(BAR_STRIP));
    let mut bar = ChartBuilder::on(&strip)
        .margin_top(48)
        .margin_bottom(52)
        .margin_right(12)
        .y_label_area_size(72)
        .build_cartesian_2d(0.0..1.0, lo..lo + span)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_formatter(&|y| tick(*y))
        .y_desc(h.value_label.as_str())
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 14))
        .draw()?;
    let step = span / COLOUR_BAR_STEPS as f64;
    bar.draw_series((0..COLOUR_BAR_STEPS).rev().map(|k| {
        let colour = ramp((k as f64 + 0.5) / COLOUR_BAR_STEPS as f64);
        let (y0, y1) = (lo + k as f64 * step, lo + (k + 1) as f64 * step);
        Rectangle::new([(0.0, y0), (1.0, y1)], colour.filled())
    }))?;
    let mut c = ChartBuilder::on(&matrix)
        .caption(&h.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(c0..c0 + h.cols as f64, (r0 + h.rows as f64)..r0)?;
    c.configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .x_desc(h.x_label.as_str())
        .y_desc(h.y_label.as_str())
        .label_style(("sans-serif", 13))
        .draw()?;
    let cells = (0..br).flat_map(|i| (0..bc).map(move |j| (i, j))).map(|(i, j)| {
        let x = v[i * bc + j];
        let colour = if x.is_finite() { ramp((x - lo) / span) } else { RGBColor(200, 200, 200) };
        let (y0, x0) = (r0 + (i * sr) as f64, c0 + (j * sc) as f64);
        let (y1, x1) = (r0 + ((i + 1) * sr).min(h.rows) as f64, c0 + ((j + 1) * sc).min(h.cols) as f64);
        Rectangle::new([(x0, y0), (x1, y1)], colour.filled())
    });
    c.draw_series(cells)?;
    if h.path.len() > 1 {
        let pts = h.path.iter().map(|&(r, col)| (col as f64 + 0.5, r as f64 + 0.5));
        c.draw_series(LineSeries::new(pts, RGBColor(230, 30, 30).stroke_width(2)))?;
    }
    root.present()
}

/// Writes `<stem>.svg` and `<stem>.png` (810 x 640: the matrix, then its colour bar) and
/// returns their paths.
pub fn write_heat_map(stem: &Path, h: &HeatMap) -> Result<Vec<PathBuf>> {
    if h.rows == 0 || h.cols == 0 || h.values.len() != h.rows * h.cols {
        return Err(Error::HeatMapShape {
            stem: stem.to_path_buf(),
            values: h.values.len(),
            rows: h.rows,
            cols: h.cols,
        });
    }
    write_svg_and_png(stem, (700 + BAR_STRIP, 640), |root| draw(root, h), |root| draw(root, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_matrices_are_averaged_and_paths_drawn() {
        let d = tempfile::tempdir().unwrap();
        let n = 450;
        let values: Vec<f64> = (0..n * n).map(|k| ((k / n) as f64 - (k % n) as f64).abs()).collect();
        let h = HeatMap {
            title: "distances".into(),
            x_label: "frame".into(),
            y_label: "frame".into(),
            values,
            rows: n,
            cols: n,
            origin: (0, 0),
            range: None,
            path: (0..n).map(|k| (k, k)).collect(),
            value_label: "|r - c|".into(),
        };
        let (br, bc, v, sr, _) = blocks(&h);
        assert_eq!((br, bc, sr), (150, 150, 3));
        assert!((v[0] - 8.0 / 9.0).abs() < 1e-12, "mean |r - c| over a 3 x 3 block: {}", v[0]);
        let files = write_heat_map(&d.path().join("h"), &h).unwrap();
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert!(svg.contains("distances") && svg.matches("<rect").count() >= br * bc);
        // The colour bar: the ramp's steps from the high end down, named, ticked up to near
        // the largest value (the block means reach 447).
        let fills: Vec<&str> = svg
            .lines()
            .filter(|l| l.starts_with("<rect"))
            .filter_map(|l| l.split("fill=\"").nth(1)?.get(..7))
            .collect();
        let want = colour_bar_fills();
        assert_eq!(want.len(), COLOUR_BAR_STEPS);
        assert_eq!(fills.windows(want.len()).filter(|w| *w == want.as_slice()).count(), 1, "one colour bar");
        assert!(svg.contains("|r - c|"));
        assert!(svg.lines().any(|l| l == "100") && svg.lines().any(|l| l == "400"), "the bar's ticks");
        assert_eq!(&std::fs::read(&files[1]).unwrap()[1..4], b"PNG");
        // A fixed range: the same colours whatever the values.
        let fixed = HeatMap { range: Some((0.0, 1000.0)), ..h.clone() };
        assert!(write_heat_map(&d.path().join("fixed"), &fixed).unwrap()[1].is_file());
        let bad = HeatMap { rows: 3, ..h };
        assert!(write_heat_map(&d.path().join("bad"), &bad).is_err());
    }
}
