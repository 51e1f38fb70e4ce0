//! Line charts and heat maps written as SVG and PNG (plotters), with an embedded font (DejaVu Sans)
//! so that text renders on machines without system fonts: no fontconfig or freetype at build time,
//! so a fresh machine needs no system packages for plots. Heat maps are block-averaged to 200 x 200
//! cells, may carry a path drawn on top (a DTW warp) and an optional fixed colour range, so two maps
//! compare by colour. Both formats are drawn in memory and written through surfcap-mesh's atomic
//! writer, so a figure, like every output, replaces only a regular file and its temporary is
//! cleaned on a signal.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

pub mod error;
pub mod heat_map;

pub use error::{Error, PngDrawingError, Result, SvgDrawingError};
pub use heat_map::{HeatMap, write_heat_map};

static FONT: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn ensure_font() {
    REGISTER.call_once(|| {
        // The font is a valid TTF compiled into the binary; registration cannot fail on it.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One line of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text; an empty name draws the line without a legend entry.
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub color: (u8, u8, u8),
    pub dashed: bool,
    /// Draw a marker at every point.
    pub markers: bool,
}

/// A line chart.
#[derive(Debug, Clone)]
pub struct LineChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

fn bounds(series: &[Series]) -> ((f64, f64), (f64, f64)) {
    let pts = series.iter().flat_map(|s| s.points.iter()).filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |a: f64, b: f64| {
        let d = if b > a { (b - a) * 0.05 } else { 0.5 };
        (a - d, b + d)
    };
    (pad(x0, x1), pad(y0, y1))
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, plotters::coord::Shift>, chart: &LineChart) -> DrawResult<(), DB>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let ((x0, x1), (y0, y1)) = bounds(&chart.series);
    let mut c = ChartBuilder::on(&root)
        .caption(&chart.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    c.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .label_style(("sans-serif", 14))
        .draw()?;
    for s in &chart.series {
        let color = RGBColor(s.color.0, s.color.1, s.color.2);
        let style = color.stroke_width(2);
        let anno = if s.dashed {
            c.draw_series(DashedLineSeries::new(s.points.iter().copied(), 6, 4, style))?
        } else {
            c.draw_series(LineSeries::new(s.points.iter().copied(), style))?
        };
        if !s.name.is_empty() {
            anno.label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        }
        if s.markers {
            c.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        }
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    root.present()
}

/// Writes `<stem>.svg` and `<stem>.png` (800 x 500) and returns their paths.
pub fn write_line_chart(stem: &Path, chart: &LineChart) -> Result<Vec<PathBuf>> {
    write_svg_and_png(stem, (800, 500), |root| draw(root, chart), |root| draw(root, chart))
}

/// Draws a figure twice (SVG, PNG) into `<stem>.svg` and `<stem>.png`. Both are drawn in memory
/// and written through surfcap-mesh's atomic writer, so a plot, like every surfcap output, replaces
/// only a regular file (never a device, FIFO or folder of that name), and its temporary is
/// removed on SIGINT/SIGTERM and swept when stale.
pub(crate) fn write_svg_and_png(
    stem: &Path,
    size: (u32, u32),
    svg_draw: impl FnOnce(DrawingArea<SVGBackend, plotters::coord::Shift>) -> Result<(), SvgDrawingError>,
    png_draw: impl FnOnce(DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<(), PngDrawingError>,
) -> Result<Vec<PathBuf>> {
    ensure_font();
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    let mut text = String::new();
    svg_draw(SVGBackend::with_string(&mut text, size).into_drawing_area())
        .map_err(|source| Error::DrawSvg { path: svg.clone(), source })?;
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    png_draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())
        .map_err(|source| Error::DrawPng { path: png.clone(), source })?;
    let save = |path: &Path, write: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        surfcap_mesh::atomic::write_file(path, |w| write(w))
            .map_err(|source| Error::Write { path: path.to_path_buf(), source: Box::new(source) })
    };
    save(&svg, &|w| w.write_all(text.as_bytes()))?;
    save(&png, &|w| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(w)
            .write_image(&rgb, size.0, size.1, image::ColorType::Rgb8)
            .map_err(std::io::Error::other)
    })?;
    Ok(vec![svg, png])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> LineChart {
        LineChart {
            title: "Correlogram".into(),
            x_label: "distance class".into(),
            y_label: "r".into(),
            series: vec![Series {
                name: "ours".into(),
                points: vec![(0.0, 0.9), (1.0, 0.5), (2.0, -0.1)],
                color: (220, 30, 30),
                dashed: false,
                markers: true,
            }],
        }
    }

    #[test]
    fn writes_svg_with_text_and_a_png() {
        let d = tempfile::tempdir().unwrap();
        let files = write_line_chart(&d.path().join("c"), &chart()).unwrap();
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert!(svg.contains("Correlogram") && svg.contains("ours"));
        let png = std::fs::read(&files[1]).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 2, "no temporaries left");
    }

    /// Output safety for plots: a FIFO (or a folder) where a figure goes is refused, not
    /// replaced by a regular file.
    #[test]
    fn a_fifo_or_folder_in_the_way_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("c.svg");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        std::fs::create_dir(d.path().join("c.png")).unwrap();
        let e = write_line_chart(&d.path().join("c"), &chart()).unwrap_err();
        let chain = format!("{e}: {}", std::error::Error::source(&e).unwrap());
        assert!(chain.contains("c.svg") && chain.contains("FIFO"), "{chain}");
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        std::fs::remove_file(&fifo).unwrap();
        let e = write_line_chart(&d.path().join("c"), &chart()).unwrap_err();
        let chain = format!("{e}: {}", std::error::Error::source(&e).unwrap());
        assert!(chain.contains("c.png"), "{chain}");
        assert!(d.path().join("c.png").is_dir());
    }
}
