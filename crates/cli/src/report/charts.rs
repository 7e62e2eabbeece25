//! Charts drawn with `plotters`, each written as SVG and PNG.
//!
//! Text needs a TrueType font: the first of `RAYBENCH_FONT` and a few usual system paths
//! (Debian's `fonts-dejavu-core` provides the first of them) is registered once. Without
//! one, charts are skipped and the report says so.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Where fonts are looked for when `RAYBENCH_FONT` is not set.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers a font for chart text, once; the error says why there is none.
///
/// # Errors
/// When no font file is found or none can be parsed.
pub fn font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let candidates: Vec<String> = std::env::var("RAYBENCH_FONT")
            .into_iter()
            .chain(FONT_PATHS.iter().map(|s| (*s).to_string()))
            .collect();
        for path in &candidates {
            if let Ok(bytes) = std::fs::read(path) {
                // The font lives as long as the process: plotters keeps a reference to it.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return Ok(());
                }
            }
        }
        Err(format!(
            "no TrueType font found for chart text (set RAYBENCH_FONT to a .ttf file; tried {})",
            candidates.join(", ")
        ))
    })
    .clone()
}

/// A named polyline.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// Chart size in pixels (PNG) and user units (SVG).
const SIZE: (u32, u32) = (900, 560);

type DrawResult = Result<(), String>;

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Writes `stem.svg` and `stem.png` with `draw`; returns the two file names.
fn both(
    stem: &Path,
    draw: impl Fn(DrawingArea<SVGBackend<'_>, Shift>) -> DrawResult + Copy,
    draw_png: impl Fn(DrawingArea<BitMapBackend<'_>, Shift>) -> DrawResult,
) -> Result<[String; 2], String> {
    font()?;
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    // Through temporary names, like every file of a report.
    let atomic = |path: &Path, write: &dyn Fn(&Path) -> DrawResult| {
        raybench_render::write_atomically::<anyhow::Error>(path, |tmp| {
            write(tmp).map_err(anyhow::Error::msg)
        })
        .map_err(|e| format!("{e:#}"))
    };
    atomic(&svg, &|tmp| {
        draw(SVGBackend::new(tmp, SIZE).into_drawing_area())
    })?;
    atomic(&png, &|tmp| {
        draw_png(BitMapBackend::new(tmp, SIZE).into_drawing_area())
    })?;
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    Ok([name(&svg), name(&png)])
}

/// The range of positive values, widened to whole decades.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    let lo = 10f64.powf(lo.log10().floor());
    let hi = 10f64.powf(hi.log10().ceil());
    (lo, if hi > lo { hi } else { lo * 10.0 })
}

/// How a log-log chart joins its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Join {
    /// Each series a polyline through its points (scaling fits).
    Lines,
    /// Points only (one structure or preset per point: quality against time, build
    /// against trace).
    Points,
}

fn log_log_on<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    join: Join,
) -> DrawResult {
    root.fill(&WHITE).map_err(err)?;
    let (x0, x1) = decades(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let (y0, y1) = decades(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0)
            .collect();
        if join == Join::Lines {
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(err)?
                .label(s.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(err)?;
        } else {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 5, color.filled())))
                .map_err(err)?
                .label(s.label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
        }
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(err)
}

/// Draws the legend box of `chart` at `position`.
fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> DrawResult {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)
}

/// A log-log chart of `series`; returns the SVG and PNG file names.
///
/// # Errors
/// When no font is available or a file cannot be written.
pub fn log_log(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<[String; 2], String> {
    both(
        stem,
        |root| log_log_on(root, title, x_label, y_label, series, Join::Lines),
        |root| log_log_on(root, title, x_label, y_label, series, Join::Lines),
    )
}

/// A log-log scatter chart: each series its own colour, its points unjoined (one point per
/// structure, preset or scene); returns the SVG and PNG file names.
///
/// # Errors
/// When no font is available or a file cannot be written.
pub fn scatter(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<[String; 2], String> {
    both(
        stem,
        |root| log_log_on(root, title, x_label, y_label, series, Join::Points),
        |root| log_log_on(root, title, x_label, y_label, series, Join::Points),
    )
}

fn categories_on<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    names: &[String],
    series: &[(String, Vec<Option<f64>>)],
) -> DrawResult {
    root.fill(&WHITE).map_err(err)?;
    let (y0, y1) = decades(series.iter().flat_map(|s| s.1.iter().flatten().copied()));
    let n = names.len().max(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), (y0..y1).log_scale())
        .map_err(err)?;
    let label = |v: &f64| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 {
            names.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&label)
        .y_desc(y_label)
        .y_label_formatter(&|v| format!("{v}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let k = series.len().max(1) as f64;
    for (i, (name, values)) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        // Spread the backends of a scene side by side.
        let dx = (i as f64 - (k - 1.0) / 2.0) * (0.7 / k);
        let pts: Vec<(f64, f64)> = values
            .iter()
            .enumerate()
            .filter_map(|(j, v)| v.filter(|v| *v > 0.0).map(|v| (j as f64 + dx, v)))
            .collect();
        chart
            .draw_series(pts.iter().map(|&(x, y)| {
                Rectangle::new([(x - 0.3 / k, y0), (x + 0.3 / k, y)], color.filled())
            }))
            .map_err(err)?
            .label(name.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled()));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(err)
}

/// A bar chart on a log axis: one group per name, one bar per series; `None` leaves a gap.
///
/// # Errors
/// When no font is available or a file cannot be written.
pub fn categories(
    stem: &Path,
    title: &str,
    y_label: &str,
    names: &[String],
    series: &[(String, Vec<Option<f64>>)],
) -> Result<[String; 2], String> {
    both(
        stem,
        |root| categories_on(root, title, y_label, names, series),
        |root| categories_on(root, title, y_label, names, series),
    )
}
