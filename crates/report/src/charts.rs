//! The report's charts, written as SVG by hand: one `STEM.svg` per [`Chart`], meant to be
//! shown as an image or inlined into an HTML page beside others.
//!
//! What every chart keeps to:
//! - **One colour and one marker per backend across every chart** ([`styles`]): keyed by
//!   the backend's place in the registry ([`raybench_registry::BACKENDS`], then [`raybench_registry::NOT_BUILT`]), a
//!   preset `BACKEND:PRESET` in its backend's colour with a marker of its own, any other
//!   series from a separate list by its sorted name.
//! - **Readable ticks**: log axes label every decade with minor ticks at 2..9, or 1-2-5
//!   steps (then every integer, then a linear step) where the data span too few decades, so
//!   that at least three labels show ([`log_axis`]); values written plainly (`0.01`, `20`,
//!   `1k`, `2.5M`), never `1e0`.
//! - **Legends beside the plot**, never over it; fitted power laws drawn dashed; bars of
//!   backends that did not run drawn as a hatched stub with an `×` and the reason.
//! - **Safe to inline**: presentation attributes only (no `<style>`, no classes), every
//!   `id` prefixed with the chart's stem, text escaped; every point and bar has a `<title>`
//!   (a browser's tooltip) with its series and values.

use std::fmt::Write as _;
use std::path::Path;

/// A chart: its title, file stem (under `charts/`), axis titles and what it plots.
#[derive(Clone, Debug)]
pub struct Chart {
    /// Its title.
    pub title: String,
    /// Its file name without extension (`STEM.svg`); also the prefix of its SVG ids.
    pub stem: String,
    /// The `x` axis title, in plain words with the unit (`primitives in the scene`); empty
    /// for none.
    pub x_label: String,
    /// The `y` axis title (`render time (s)`).
    pub y_label: String,
    /// The data.
    pub plot: Plot,
}

/// What a chart plots.
#[derive(Clone, Debug)]
pub enum Plot {
    /// Each series a line through its points on log-log axes, with its fitted power law.
    LogLog(Vec<Series>),
    /// Unjoined points on log-log axes (one point per structure, preset or scene).
    Scatter(Vec<Series>),
    /// Bars on a log axis: one group per category name, one bar per series.
    Categories(Vec<String>, Vec<Bars>),
    /// Each series a line through its points over a linear `x` axis (a count from 0, such
    /// as an animation's frames) and a log `y` axis.
    Lines(Vec<Series>),
}

/// A named set of points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Whose points: a backend (`bvh`), a preset (`bvh:fast`) or another name
    /// (`mean FLIP`); it picks the colour and marker ([`styles`]) and is the legend's text.
    pub label: String,
    /// Points `(x, y)`, in drawing order; those not positive cannot sit on log axes and are
    /// left out.
    pub points: Vec<(f64, f64)>,
    /// A power law fitted to the points, drawn dashed over their `x` range; its exponent is
    /// given in the legend.
    pub fit: Option<PowerLaw>,
}

/// `y = coefficient * x^exponent`: a straight line on log-log axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLaw {
    /// The factor `a`.
    pub coefficient: f64,
    /// The exponent (the slope on log-log axes).
    pub exponent: f64,
}

impl PowerLaw {
    /// `y` at `x`.
    #[must_use]
    pub fn at(&self, x: f64) -> f64 {
        self.coefficient * x.powf(self.exponent)
    }
}

/// One series of a bar chart: a value (or why there is none) per category.
#[derive(Clone, Debug)]
pub struct Bars {
    /// Whose bars (a backend); picks the colour like [`Series::label`].
    pub label: String,
    /// One per category, in the order of the chart's names.
    pub values: Vec<Bar>,
}

/// One bar.
#[derive(Clone, Debug, PartialEq)]
pub enum Bar {
    /// A measured value (not positive: drawn as [`Bar::Absent`]).
    Value(f64),
    /// The series did not run there (unsupported, unavailable): why. Drawn as a hatched
    /// stub with an `×`, the reason its tooltip.
    Unsupported(String),
    /// Nothing for this category: a gap.
    Absent,
}

// ---------------------------------------------------------------------------------------
// Colours and markers.

/// The colours of the registry's backends, by index: Okabe-Ito's eight colour-blind-safe
/// colours first (for the backends most reports run), then Paul Tol's, all readable on
/// white. Markers tell apart what colours alone might not.
const BACKEND_COLOURS: [&str; 16] = [
    "#000000", // naive
    "#0072B2", // bvh
    "#E69F00", // obvhs
    "#009E73", // grid
    "#44AA99", // grid2
    "#D55E00", // packet
    "#AA4499", // packet-sse4.1
    "#882255", // packet-avx512
    "#997700", // packet-portable
    "#56B4E9", // bvh-crate
    "#332288", // wgpu
    "#CC79A7", // wgpu-cwbvh
    "#999933", // embree
    "#661100", // embree-packet
    "#6699CC", // spare
    "#555555", // spare
];

/// The colours of series that are not backends (`mean FLIP`, `tessellated`), by their
/// sorted name within a chart: none is a backend's colour.
const OTHER_COLOURS: [&str; 6] = [
    "#E15759", "#4E79A7", "#59A14F", "#B07AA1", "#F28E2B", "#9C755F",
];

/// A point's mark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A disc.
    Circle,
    /// A square.
    Square,
    /// A triangle pointing up.
    TriangleUp,
    /// A diamond.
    Diamond,
    /// A triangle pointing down.
    TriangleDown,
    /// An `×` (stroked).
    Cross,
    /// A `+` (stroked).
    Plus,
    /// A five-pointed star.
    Star,
}

/// The markers, in the order backends take them.
const MARKERS: [Marker; 8] = [
    Marker::Circle,
    Marker::Square,
    Marker::TriangleUp,
    Marker::Diamond,
    Marker::TriangleDown,
    Marker::Cross,
    Marker::Plus,
    Marker::Star,
];

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Style {
    /// Its colour (`#RRGGBB`).
    pub colour: &'static str,
    /// Its points' marker.
    pub marker: Marker,
}

/// Every backend name in registry order: the built ones, then those this build lacks (the
/// same order either way: the lacking ones close the registry).
fn registry() -> impl Iterator<Item = &'static str> {
    raybench_registry::BACKENDS
        .iter()
        .map(|b| b.name)
        .chain(raybench_registry::NOT_BUILT.iter().map(|n| n.name))
}

/// A stable small hash (FNV-1a) of a name, for presets this build does not know.
fn fnv(s: &str) -> usize {
    s.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    }) as usize
}

/// The style of a backend (`bvh`) or of a preset of one (`bvh:fast`: its backend's colour,
/// a marker by the preset's place among the backend's presets); `None` for other names.
#[must_use]
pub fn backend_style(label: &str) -> Option<Style> {
    let (base, preset) = match label.split_once(':') {
        Some((b, p)) => (b, Some(p)),
        None => (label, None),
    };
    let i = registry().position(|n| n == base)?;
    let colour = BACKEND_COLOURS[i % BACKEND_COLOURS.len()];
    let marker = match preset {
        None => MARKERS[i % MARKERS.len()],
        Some(p) => {
            let place = raybench_registry::presets::presets_of(base)
                .position(|q| q.preset == p)
                .unwrap_or_else(|| fnv(p));
            MARKERS[(i + 1 + place) % MARKERS.len()]
        }
    };
    Some(Style { colour, marker })
}

/// The styles of a chart's series, in the order of `labels`: a backend's or preset's from
/// [`backend_style`], whatever the chart; any other label's from [`OTHER_COLOURS`] by its
/// place among the chart's other labels sorted by name.
#[must_use]
pub fn styles(labels: &[&str]) -> Vec<Style> {
    let mut others: Vec<&str> = labels
        .iter()
        .copied()
        .filter(|l| backend_style(l).is_none())
        .collect();
    others.sort_unstable();
    others.dedup();
    labels
        .iter()
        .map(|l| {
            backend_style(l).unwrap_or_else(|| {
                let k = others.binary_search(l).unwrap_or(0);
                Style {
                    colour: OTHER_COLOURS[k % OTHER_COLOURS.len()],
                    marker: MARKERS[k % MARKERS.len()],
                }
            })
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Axes and tick labels.

/// An axis (log, or linear for [`Plot::Lines`]'s `x`): its range and its ticks.
#[derive(Clone, Debug, PartialEq)]
struct Axis {
    /// `log10` of the lowest value shown (a linear axis: the value).
    lo: f64,
    /// `log10` of the highest value shown (a linear axis: the value).
    hi: f64,
    /// Whether values are placed linearly rather than by their logarithm.
    linear: bool,
    /// Labelled ticks: value and label.
    major: Vec<(f64, String)>,
    /// Unlabelled ticks.
    minor: Vec<f64>,
}

impl Axis {
    /// Where `v` falls along the axis, 0 at its low end and 1 at its high end.
    fn frac(&self, v: f64) -> f64 {
        let v = if self.linear { v } else { v.log10() };
        (v - self.lo) / (self.hi - self.lo)
    }

    /// Whether `v` can be placed on the axis (a log axis: positive values only).
    fn shows(&self, v: f64) -> bool {
        v.is_finite() && (self.linear || v > 0.0)
    }
}

/// Superscript digits and sign, for `10⁻⁵`.
fn superscript(e: i32) -> String {
    e.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect()
}

/// Decimals that show a multiple of `step` exactly.
fn decimals_for(step: f64) -> usize {
    if step >= 1.0 - 1e-9 {
        0
    } else {
        ((-step.log10() - 1e-9).ceil() as usize).min(12)
    }
}

/// `v` with `decimals` decimals, trailing zeros dropped.
fn trimmed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A value written plainly, exact to `step`: `0.001`, `0.25`, `20`, `1k`, `2.5M`; below
/// 0.0001 as `2×10⁻⁵`.
fn number(v: f64, step: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if a < 1e-4 * (1.0 - 1e-9) {
        let e = a.log10().floor() as i32;
        let scale = 10f64.powi(e);
        let m = trimmed(v / scale, decimals_for(step / scale));
        return if m == "1" {
            format!("10{}", superscript(e))
        } else {
            format!("{m}×10{}", superscript(e))
        };
    }
    let (div, suffix) = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")]
        .into_iter()
        .find(|(d, _)| a >= d * (1.0 - 1e-9))
        .unwrap_or((1.0, ""));
    format!("{}{suffix}", trimmed(v / div, decimals_for(step / div)))
}

/// A measured value for a tooltip: four significant digits.
fn value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor();
    number(v, 10f64.powf(e - 3.0))
}

/// The values `m * 10^k` in `[lo, hi]` (logs) for each `m` of `mantissas`, ascending.
fn log_candidates(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in (lo.floor() as i32 - 1)..=(hi.ceil() as i32) {
        for &m in mantissas {
            let v = m * 10f64.powi(k);
            let l = v.log10();
            if l >= lo - 1e-9 && l <= hi + 1e-9 {
                out.push(v);
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// The step of a multiple of 10 that shows `v` exactly (`300` → 100, `0.02` → 0.01).
fn power_step(v: f64) -> f64 {
    10f64.powf((v.abs().log10() + 1e-9).floor())
}

/// A log axis over the positive finite `values`: a little wider than their range, labelled
/// at every decade with minor ticks at 2..9 when at least three decades show; else at 1-2-5
/// steps, every integer multiple of a decade, or a plain step, whichever first gives three
/// labels or more.
fn log_axis(values: impl Iterator<Item = f64>) -> Axis {
    let (min, max) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (mut lo, mut hi) = if min.is_finite() {
        (min.log10(), max.log10())
    } else {
        (0.0, 1.0)
    };
    // A little room around the data; a single value gets a factor of 1.4 either side.
    let pad = if hi - lo < 1e-9 {
        0.15
    } else {
        ((hi - lo) * 0.04).max(0.02)
    };
    lo -= pad;
    hi += pad;
    let labelled = |values: Vec<f64>| -> Vec<(f64, String)> {
        values
            .into_iter()
            .map(|v| (v, number(v, power_step(v))))
            .collect()
    };
    let decades = log_candidates(lo, hi, &[1.0]);
    if decades.len() >= 3 {
        // More than ten decades: every other one labelled, the rest minor.
        let every = if decades.len() > 10 { 2 } else { 1 };
        let (mut major, mut minor) = (Vec::new(), Vec::new());
        for (i, v) in decades.iter().copied().enumerate() {
            if i % every == 0 {
                major.push(v);
            } else {
                minor.push(v);
            }
        }
        if decades.len() <= 8 {
            minor.extend(log_candidates(
                lo,
                hi,
                &[2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
            ));
        }
        minor.sort_by(f64::total_cmp);
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(major),
            minor,
        };
    }
    let steps = log_candidates(lo, hi, &[1.0, 2.0, 5.0]);
    if steps.len() >= 3 {
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(steps),
            minor: log_candidates(lo, hi, &[3.0, 4.0, 6.0, 7.0, 8.0, 9.0]),
        };
    }
    let integers = log_candidates(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if integers.len() >= 3 {
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(integers),
            minor: Vec::new(),
        };
    }
    // A narrow range: the largest 1-2-5 step that fits three times.
    let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
    let third = (b - a) / 3.0;
    let p = power_step(third);
    let step = [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s <= third * (1.0 + 1e-9))
        .unwrap_or(p);
    Axis {
        lo,
        hi,
        linear: false,
        major: multiples(a, b, step),
        minor: Vec::new(),
    }
}

/// The multiples of `step` in `[a, b]`, labelled.
fn multiples(a: f64, b: f64, step: f64) -> Vec<(f64, String)> {
    let first = (a / step).ceil() as i64;
    let last = (b / step).floor() as i64;
    (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            (v, number(v, step))
        })
        .collect()
}

/// A linear axis over `values` (the finite ones), labelled every 1, 2 or 5 times a power of
/// ten: the smallest such step that gives at most 8 labels.
fn linear_axis(values: impl Iterator<Item = f64>) -> Axis {
    let (min, max) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (min, max) = if min.is_finite() {
        (min, max)
    } else {
        (0.0, 1.0)
    };
    let span = (max - min).max(max.abs().max(1.0) * 1e-9);
    let (lo, hi) = (min - span * 0.03, max + span * 0.03);
    let p = power_step(span / 8.0);
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| span / s <= 8.0 + 1e-9)
        .unwrap_or(10.0 * p);
    Axis {
        lo,
        hi,
        linear: true,
        major: multiples(lo, hi, step),
        minor: Vec::new(),
    }
}

// ---------------------------------------------------------------------------------------
// Layout.

/// A rectangle in SVG user units.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rect {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

impl Rect {
    fn right(&self) -> f64 {
        self.x + self.w
    }

    fn bottom(&self) -> f64 {
        self.y + self.h
    }

    /// Whether the two share any area.
    #[cfg(test)]
    fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.right() && o.x < self.right() && self.y < o.bottom() && o.y < self.bottom()
    }
}

/// Font sizes (user units) and the width of a character, estimated for sans-serif text.
const TITLE_SIZE: f64 = 16.0;
const LABEL_SIZE: f64 = 13.0;
const TICK_SIZE: f64 = 11.0;
const LEGEND_SIZE: f64 = 12.0;
/// Average advance of a character over the font size (DejaVu Sans runs wide).
const CHAR_WIDTH: f64 = 0.62;
/// Height of a legend row.
const LEGEND_ROW: f64 = 18.0;
/// The plot area of a log-log chart.
const PLOT: (f64, f64) = (560.0, 360.0);
/// Height of the hatched stub that marks a series that did not run.
const STUB: f64 = 12.0;

/// Estimated width of `text` at font size `size`.
fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * CHAR_WIDTH
}

/// How a legend entry shows its series.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Key {
    /// A short line with the marker on it.
    Line(Style),
    /// The marker alone.
    Point(Style),
    /// A filled square.
    Swatch(Style),
    /// A dashed grey line (the fitted power laws).
    Dashed,
    /// A hatched square (series that did not run).
    Hatched,
}

/// Where everything goes.
#[derive(Clone, Debug)]
struct Layout {
    width: f64,
    height: f64,
    plot: Rect,
    legend: Rect,
    /// Legend rows per column.
    rows: usize,
    /// Width of a legend column.
    column: f64,
    /// Category labels drawn at an angle (too wide for their group).
    slanted: bool,
}

/// The legend's entries of `chart`, with the series' styles.
fn legend_entries(chart: &Chart) -> Vec<(String, Key)> {
    let mut out = Vec::new();
    match &chart.plot {
        Plot::LogLog(series) | Plot::Scatter(series) | Plot::Lines(series) => {
            let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
            let lines = !matches!(chart.plot, Plot::Scatter(_));
            for (s, st) in series.iter().zip(styles(&labels)) {
                let text = match &s.fit {
                    Some(f) => format!("{} (slope {:.2})", s.label, f.exponent),
                    None => s.label.clone(),
                };
                out.push((text, if lines { Key::Line(st) } else { Key::Point(st) }));
            }
            if series.iter().any(|s| s.fit.is_some()) {
                out.push(("fitted y = a·x^slope".into(), Key::Dashed));
            }
        }
        Plot::Categories(_, bars) => {
            let labels: Vec<&str> = bars.iter().map(|b| b.label.as_str()).collect();
            for (b, st) in bars.iter().zip(styles(&labels)) {
                out.push((b.label.clone(), Key::Swatch(st)));
            }
            if bars
                .iter()
                .any(|b| b.values.iter().any(|v| matches!(v, Bar::Unsupported(_))))
            {
                out.push(("× did not run (hover: why)".into(), Key::Hatched));
            }
        }
    }
    out
}

/// The widest tick label of `axis`.
fn widest(axis: &Axis) -> f64 {
    axis.major
        .iter()
        .map(|(_, l)| text_width(l, TICK_SIZE))
        .fold(0.0, f64::max)
}

/// Places the plot, its axes' labels and the legend (to the right of the plot, in as many
/// columns as its rows need).
fn layout(chart: &Chart, y: &Axis, entries: &[(String, Key)]) -> Layout {
    let left = 14.0 + LABEL_SIZE + 10.0 + widest(y) + 8.0;
    let top = 14.0 + TITLE_SIZE + 14.0;
    let (mut plot_w, plot_h) = PLOT;
    let mut bottom = 10.0 + TICK_SIZE + 12.0 + LABEL_SIZE + 10.0;
    let mut slanted = false;
    if let Plot::Categories(names, bars) = &chart.plot {
        // Bars at least 7 units wide, groups 12 apart.
        let group = bars.len().max(1) as f64 * 7.0 + 12.0;
        plot_w = plot_w.max(names.len() as f64 * group);
        let slot = plot_w / names.len().max(1) as f64;
        let longest = names
            .iter()
            .map(|n| text_width(n, TICK_SIZE))
            .fold(0.0, f64::max);
        if longest > slot - 4.0 {
            slanted = true;
            bottom += longest * 0.5;
        }
    }
    let plot = Rect {
        x: left,
        y: top,
        w: plot_w,
        h: plot_h,
    };
    let rows = ((plot_h - 10.0) / LEGEND_ROW).floor().max(1.0) as usize;
    let columns = entries.len().div_ceil(rows).max(1);
    let column = 36.0
        + entries
            .iter()
            .map(|(t, _)| text_width(t, LEGEND_SIZE))
            .fold(0.0, f64::max);
    let legend = Rect {
        x: plot.right() + 24.0,
        y: plot.y,
        w: columns as f64 * column + 8.0,
        h: entries.len().min(rows) as f64 * LEGEND_ROW + 10.0,
    };
    let width = (legend.right() + 12.0).max(text_width(&chart.title, TITLE_SIZE) + 28.0);
    let height = (plot.bottom() + bottom).max(legend.bottom() + 12.0);
    Layout {
        width,
        height,
        plot,
        legend,
        rows,
        column,
        slanted,
    }
}

// ---------------------------------------------------------------------------------------
// Writing SVG.

/// `s` escaped for SVG and HTML text and attribute values (`REPORT.html` uses it too).
pub(super) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `stem` as the start of an XML id: letters, digits, `-` and `_`, starting with a letter.
fn id_prefix(stem: &str) -> String {
    let s: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s
    } else {
        format!("c-{s}")
    }
}

/// Text at `(x, y)`: `anchor` is `start`, `middle` or `end`; `extra` more attributes.
fn text(out: &mut String, x: f64, y: f64, size: f64, anchor: &str, extra: &str, s: &str) {
    let _ = writeln!(
        out,
        r##"<text x="{x:.1}" y="{y:.1}" font-size="{size}" text-anchor="{anchor}" fill="#222"{extra}>{}</text>"##,
        escape(s)
    );
}

/// A marker at `(x, y)` with a tooltip (`title`, already escaped; empty for none).
fn marker(out: &mut String, x: f64, y: f64, style: Style, title: &str) {
    let r = 4.2;
    let c = style.colour;
    let filled = format!(r##"fill="{c}" stroke="#fff" stroke-width="0.8""##);
    let stroked = format!(r#"fill="none" stroke="{c}" stroke-width="2.2""#);
    let tip = if title.is_empty() {
        String::new()
    } else {
        format!("<title>{title}</title>")
    };
    let poly = |pts: &[(f64, f64)]| -> String {
        let mut d = String::new();
        for (i, (px, py)) in pts.iter().enumerate() {
            let _ = write!(
                d,
                "{}{:.1},{:.1}",
                if i == 0 { "M" } else { "L" },
                x + px * r,
                y + py * r
            );
        }
        d.push('Z');
        d
    };
    let _ = match style.marker {
        Marker::Circle => writeln!(
            out,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" {filled}>{tip}</circle>"#
        ),
        Marker::Square => writeln!(
            out,
            r#"<path d="{}" {filled}>{tip}</path>"#,
            poly(&[(-0.9, -0.9), (0.9, -0.9), (0.9, 0.9), (-0.9, 0.9)])
        ),
        Marker::TriangleUp => writeln!(
            out,
            r#"<path d="{}" {filled}>{tip}</path>"#,
            poly(&[(0.0, -1.25), (1.1, 0.75), (-1.1, 0.75)])
        ),
        Marker::TriangleDown => writeln!(
            out,
            r#"<path d="{}" {filled}>{tip}</path>"#,
            poly(&[(0.0, 1.25), (1.1, -0.75), (-1.1, -0.75)])
        ),
        Marker::Diamond => writeln!(
            out,
            r#"<path d="{}" {filled}>{tip}</path>"#,
            poly(&[(0.0, -1.3), (1.1, 0.0), (0.0, 1.3), (-1.1, 0.0)])
        ),
        Marker::Star => {
            let pts: Vec<(f64, f64)> = (0..10)
                .map(|i| {
                    let a = std::f64::consts::PI * (f64::from(i) / 5.0 - 0.5);
                    let k = if i % 2 == 0 { 1.45 } else { 0.6 };
                    (k * a.cos(), k * a.sin())
                })
                .collect();
            writeln!(out, r#"<path d="{}" {filled}>{tip}</path>"#, poly(&pts))
        }
        Marker::Cross | Marker::Plus => {
            let k = if style.marker == Marker::Cross {
                0.85 * r
            } else {
                1.15 * r
            };
            let d = if style.marker == Marker::Cross {
                format!(
                    "M{:.1},{:.1}L{:.1},{:.1}M{:.1},{:.1}L{:.1},{:.1}",
                    x - k,
                    y - k,
                    x + k,
                    y + k,
                    x - k,
                    y + k,
                    x + k,
                    y - k
                )
            } else {
                format!(
                    "M{:.1},{y:.1}L{:.1},{y:.1}M{x:.1},{:.1}L{x:.1},{:.1}",
                    x - k,
                    x + k,
                    y - k,
                    y + k
                )
            };
            // A wider transparent stroke under it makes the tooltip easier to reach.
            writeln!(
                out,
                r##"<g>{tip}<path d="{d}" fill="none" stroke="#fff" stroke-opacity="0" stroke-width="8"/><path d="{d}" {stroked}/></g>"##
            )
        }
    };
}

/// The SVG text of `chart`.
#[must_use]
pub fn svg(chart: &Chart) -> String {
    let id = id_prefix(&chart.stem);
    let entries = legend_entries(chart);
    let (x_axis, y_axis) = match &chart.plot {
        Plot::LogLog(series) | Plot::Scatter(series) => {
            let fits = |s: &Series, pick: fn((f64, f64)) -> f64| -> Vec<f64> {
                match (s.fit, x_range(s)) {
                    (Some(f), Some((a, b))) => vec![pick((a, f.at(a))), pick((b, f.at(b)))],
                    _ => Vec::new(),
                }
            };
            let xs = series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0).chain(fits(s, |p| p.0)));
            let ys = series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1).chain(fits(s, |p| p.1)));
            (Some(log_axis(xs)), log_axis(ys))
        }
        Plot::Lines(series) => {
            let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
            let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
            (Some(linear_axis(xs)), log_axis(ys))
        }
        Plot::Categories(_, bars) => {
            let values: Vec<f64> = bars
                .iter()
                .flat_map(|b| &b.values)
                .filter_map(|v| match v {
                    Bar::Value(v) if *v > 0.0 && v.is_finite() => Some(*v),
                    _ => None,
                })
                .collect();
            // Bars rise from the bottom of a log axis: room below the lowest value keeps its
            // bar tall enough to read (and unlike a stub).
            let floor = values.iter().copied().fold(f64::INFINITY, f64::min) * 0.3;
            (None, log_axis(values.into_iter().chain([floor])))
        }
    };
    let lay = layout(chart, &y_axis, &entries);
    let p = lay.plot;
    let (w, h) = (lay.width.ceil(), lay.height.ceil());
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
    );
    let _ = writeln!(out, "<title>{}</title>", escape(&chart.title));
    let _ = writeln!(
        out,
        r##"<defs><pattern id="{id}-hatch" width="5" height="5" patternUnits="userSpaceOnUse" patternTransform="rotate(45)"><rect width="5" height="5" fill="#fff"/><line x1="0" y1="0" x2="0" y2="5" stroke="#777" stroke-width="1.6"/></pattern></defs>"##
    );
    let _ = writeln!(
        out,
        r##"<rect x="0" y="0" width="{w}" height="{h}" fill="#fff"/>"##
    );
    text(
        &mut out,
        w / 2.0,
        14.0 + TITLE_SIZE,
        TITLE_SIZE,
        "middle",
        r#" font-weight="bold""#,
        &chart.title,
    );

    // The y axis: grid lines, ticks, labels, title.
    let y_at = |v: f64| p.bottom() - y_axis.frac(v) * p.h;
    for &v in &y_axis.minor {
        rule(&mut out, p, Dir::Y, y_at(v), MINOR);
    }
    for (v, label) in &y_axis.major {
        let y = y_at(*v);
        rule(&mut out, p, Dir::Y, y, MAJOR);
        text(&mut out, p.x - 9.0, y + 4.0, TICK_SIZE, "end", "", label);
    }
    let (yx, yy) = (14.0 + LABEL_SIZE - 2.0, p.y + p.h / 2.0);
    text(
        &mut out,
        yx,
        yy,
        LABEL_SIZE,
        "middle",
        &format!(r#" transform="rotate(-90 {yx:.1} {yy:.1})""#),
        &chart.y_label,
    );
    let x_title_y = lay.height - 12.0;
    if !chart.x_label.is_empty() {
        text(
            &mut out,
            p.x + p.w / 2.0,
            x_title_y,
            LABEL_SIZE,
            "middle",
            "",
            &chart.x_label,
        );
    }

    match &chart.plot {
        Plot::LogLog(series) | Plot::Scatter(series) | Plot::Lines(series) => {
            let xa = x_axis.as_ref().expect("charts of series have an x axis");
            let x_at = |v: f64| p.x + xa.frac(v) * p.w;
            for &v in &xa.minor {
                rule(&mut out, p, Dir::X, x_at(v), MINOR);
            }
            // A label that would touch the one before it is left off (its tick stays).
            let mut free_from = f64::NEG_INFINITY;
            for (v, label) in &xa.major {
                let x = x_at(*v);
                rule(&mut out, p, Dir::X, x, MAJOR);
                let half = text_width(label, TICK_SIZE) / 2.0;
                if x - half < free_from {
                    continue;
                }
                free_from = x + half + 6.0;
                text(
                    &mut out,
                    x,
                    p.bottom() + 10.0 + TICK_SIZE,
                    TICK_SIZE,
                    "middle",
                    "",
                    label,
                );
            }
            frame(&mut out, p);
            let lines = !matches!(chart.plot, Plot::Scatter(_));
            let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
            for (s, st) in series.iter().zip(styles(&labels)) {
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|&(x, y)| xa.shows(x) && y > 0.0 && y.is_finite())
                    .collect();
                let _ = writeln!(out, "<g>");
                if let (Some(f), Some((a, b))) = (s.fit, x_range(s)) {
                    let _ = writeln!(
                        out,
                        r#"<path d="M{:.1},{:.1}L{:.1},{:.1}" stroke="{}" stroke-width="1.6" stroke-dasharray="7 4" fill="none"><title>{}: fitted {} x^{:.3}</title></path>"#,
                        x_at(a),
                        y_at(f.at(a)),
                        x_at(b),
                        y_at(f.at(b)),
                        st.colour,
                        escape(&s.label),
                        value(f.coefficient),
                        f.exponent
                    );
                }
                if lines && pts.len() > 1 {
                    let mut d = String::new();
                    for (i, &(x, y)) in pts.iter().enumerate() {
                        let _ = write!(
                            d,
                            "{}{:.1},{:.1}",
                            if i == 0 { "M" } else { "L" },
                            x_at(x),
                            y_at(y)
                        );
                    }
                    let _ = writeln!(
                        out,
                        r#"<path d="{d}" stroke="{}" stroke-width="1.8" stroke-linejoin="round" fill="none"/>"#,
                        st.colour
                    );
                }
                for &(x, y) in &pts {
                    let tip = escape(&format!(
                        "{}\n{}: {}\n{}: {}",
                        s.label,
                        axis_name(&chart.x_label, "x"),
                        value(x),
                        axis_name(&chart.y_label, "y"),
                        value(y)
                    ));
                    marker(&mut out, x_at(x), y_at(y), st, &tip);
                }
                let _ = writeln!(out, "</g>");
            }
        }
        Plot::Categories(names, bars) => {
            let n = names.len().max(1) as f64;
            let slot = p.w / n;
            let k = bars.len().max(1) as f64;
            // At most 28 units a bar: a few wide groups would look like blocks.
            let bar_w = ((slot - 12.0).max(1.0) / k).min(28.0);
            let first = (slot - bar_w * k) / 2.0;
            for (i, name) in names.iter().enumerate() {
                let cx = p.x + (i as f64 + 0.5) * slot;
                let ty = p.bottom() + 10.0 + TICK_SIZE;
                if lay.slanted {
                    text(
                        &mut out,
                        cx,
                        ty,
                        TICK_SIZE,
                        "end",
                        &format!(r#" transform="rotate(-30 {cx:.1} {ty:.1})""#),
                        name,
                    );
                } else {
                    text(&mut out, cx, ty, TICK_SIZE, "middle", "", name);
                }
                if i > 0 {
                    let x = p.x + i as f64 * slot;
                    let _ = writeln!(
                        out,
                        r##"<path d="M{x:.1},{:.1}v5" stroke="#444" stroke-width="1"/>"##,
                        p.bottom()
                    );
                }
            }
            let labels: Vec<&str> = bars.iter().map(|b| b.label.as_str()).collect();
            for (j, (b, st)) in bars.iter().zip(styles(&labels)).enumerate() {
                let _ = writeln!(out, "<g>");
                for (i, v) in b.values.iter().enumerate() {
                    let Some(name) = names.get(i) else { break };
                    let x = p.x + i as f64 * slot + first + j as f64 * bar_w;
                    match v {
                        Bar::Value(v) if *v > 0.0 && v.is_finite() => {
                            let top = y_at(*v).min(p.bottom() - 1.0);
                            let _ = writeln!(
                                out,
                                r#"<rect x="{x:.1}" y="{top:.1}" width="{:.1}" height="{:.1}" fill="{}"><title>{}</title></rect>"#,
                                (bar_w - 1.0).max(0.5),
                                p.bottom() - top,
                                st.colour,
                                escape(&format!(
                                    "{} on {name}\n{}: {}",
                                    b.label,
                                    axis_name(&chart.y_label, "value"),
                                    value(*v)
                                ))
                            );
                        }
                        Bar::Unsupported(why) => {
                            let tip = escape(&format!("{} on {name}: {why}", b.label));
                            let _ = writeln!(
                                out,
                                r#"<g><title>{tip}</title><rect x="{x:.1}" y="{:.1}" width="{:.1}" height="{STUB}" fill="url(#{id}-hatch)" stroke="{}" stroke-width="1"/><text x="{:.1}" y="{:.1}" font-size="{TICK_SIZE}" text-anchor="middle" fill="{}">×</text></g>"#,
                                p.bottom() - STUB,
                                (bar_w - 1.0).max(0.5),
                                st.colour,
                                x + bar_w / 2.0 - 0.5,
                                p.bottom() - STUB - 3.0,
                                st.colour
                            );
                        }
                        Bar::Value(_) | Bar::Absent => {}
                    }
                }
                let _ = writeln!(out, "</g>");
            }
            frame(&mut out, p);
        }
    }
    legend(&mut out, &lay, &entries, &id);
    out.push_str("</svg>\n");
    out
}

/// The axis title for a tooltip, or `fallback` when there is none.
fn axis_name<'a>(label: &'a str, fallback: &'a str) -> &'a str {
    if label.is_empty() { fallback } else { label }
}

/// The range of a series' positive `x`.
fn x_range(s: &Series) -> Option<(f64, f64)> {
    let (a, b) = s
        .points
        .iter()
        .map(|p| p.0)
        .filter(|x| *x > 0.0 && x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    a.is_finite().then_some((a, b))
}

/// Which axis a rule marks a value of.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Dir {
    /// A vertical line at an `x` value.
    X,
    /// A horizontal line at a `y` value.
    Y,
}

/// A labelled tick: its tick's length outside the plot and its grid line's colour.
const MAJOR: (f64, &str) = (6.0, "#d0d0d0");
/// An unlabelled tick.
const MINOR: (f64, &str) = (3.0, "#eeeeee");

/// A grid line across the plot at `at` (user units) and its tick outside the plot.
fn rule(out: &mut String, p: Rect, dir: Dir, at: f64, (tick, colour): (f64, &str)) {
    let d = match dir {
        Dir::X => format!(
            "M{at:.1},{:.1}V{:.1}M{at:.1},{:.1}v{tick}",
            p.y,
            p.bottom(),
            p.bottom()
        ),
        Dir::Y => format!(
            "M{:.1},{at:.1}H{:.1}M{:.1},{at:.1}h-{tick}",
            p.x,
            p.right(),
            p.x
        ),
    };
    let _ = writeln!(
        out,
        r#"<path d="{d}" stroke="{colour}" stroke-width="1" fill="none"/>"#
    );
}

/// The plot's frame.
fn frame(out: &mut String, p: Rect) {
    let _ = writeln!(
        out,
        r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#444" stroke-width="1"/>"##,
        p.x, p.y, p.w, p.h
    );
}

/// The legend box and its entries.
fn legend(out: &mut String, lay: &Layout, entries: &[(String, Key)], id: &str) {
    if entries.is_empty() {
        return;
    }
    let l = lay.legend;
    let _ = writeln!(
        out,
        r##"<g><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="#fff" stroke="#bbbbbb" stroke-width="1"/>"##,
        l.x, l.y, l.w, l.h
    );
    for (i, (label, key)) in entries.iter().enumerate() {
        let (col, row) = (i / lay.rows, i % lay.rows);
        let x = l.x + 8.0 + col as f64 * lay.column;
        let y = l.y + 5.0 + (row as f64 + 0.5) * LEGEND_ROW;
        match *key {
            Key::Line(st) => {
                let _ = writeln!(
                    out,
                    r#"<path d="M{x:.1},{y:.1}h24" stroke="{}" stroke-width="1.8"/>"#,
                    st.colour
                );
                marker(out, x + 12.0, y, st, "");
            }
            Key::Point(st) => marker(out, x + 12.0, y, st, ""),
            Key::Swatch(st) => {
                let _ = writeln!(
                    out,
                    r#"<rect x="{:.1}" y="{:.1}" width="12" height="12" fill="{}"/>"#,
                    x + 6.0,
                    y - 6.0,
                    st.colour
                );
            }
            Key::Dashed => {
                let _ = writeln!(
                    out,
                    r##"<path d="M{x:.1},{y:.1}h24" stroke="#555" stroke-width="1.6" stroke-dasharray="7 4"/>"##
                );
            }
            Key::Hatched => {
                let _ = writeln!(
                    out,
                    r##"<rect x="{:.1}" y="{:.1}" width="12" height="12" fill="url(#{id}-hatch)" stroke="#555" stroke-width="1"/>"##,
                    x + 6.0,
                    y - 6.0
                );
            }
        }
        text(out, x + 30.0, y + 4.0, LEGEND_SIZE, "start", "", label);
    }
    let _ = writeln!(out, "</g>");
}

/// Writes `dir/STEM.svg` (through a temporary name, like every file of a report); returns
/// its file name.
///
/// # Errors
/// When the file cannot be written.
pub fn draw(dir: &Path, chart: &Chart) -> Result<String, String> {
    let name = format!("{}.svg", chart.stem);
    let path = dir.join(&name);
    let text = svg(chart);
    raybench_render::write_atomically::<anyhow::Error>(&path, |tmp| {
        std::fs::write(tmp, text.as_bytes()).map_err(anyhow::Error::from)
    })
    .map_err(|e| format!("cannot write {}: {e:#}", path.display()))?;
    Ok(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `i`-th backend of the registry (tests name no backend themselves: `tests/tidy.rs`).
    fn b(i: usize) -> &'static str {
        raybench_registry::BACKENDS[i].name
    }

    fn labels(axis: &Axis) -> Vec<&str> {
        axis.major.iter().map(|(_, l)| l.as_str()).collect()
    }

    fn series(label: &str, points: &[(f64, f64)]) -> Series {
        Series {
            label: label.into(),
            points: points.to_vec(),
            fit: None,
        }
    }

    fn chart(stem: &str, title: &str, plot: Plot) -> Chart {
        Chart {
            title: title.into(),
            stem: stem.into(),
            x_label: "primitives in the scene".into(),
            y_label: "render time (s)".into(),
            plot,
        }
    }

    /// Data within one decade still get three labels or more, never `1e0`-style ones.
    #[test]
    fn narrow_ranges_get_at_least_three_labels() {
        for (lo, hi) in [
            (1.2, 3.4),
            (0.3, 0.9),
            (0.011, 0.019),
            (40.0, 44.0),
            (1.02, 1.05),
            (7.0, 7.0),
            (2500.0, 9000.0),
            (1.5e-6, 3e-6),
            (0.3, 15.0),
        ] {
            let axis = log_axis([lo, hi].into_iter());
            let l = labels(&axis);
            assert!(l.len() >= 3, "{lo}..{hi}: {l:?}");
            assert!(l.iter().all(|s| !s.contains('e')), "{lo}..{hi}: {l:?}");
            // Every label inside the range shown, and all distinct.
            for (v, _) in &axis.major {
                let f = axis.frac(*v);
                assert!((-1e-9..=1.0 + 1e-9).contains(&f), "{lo}..{hi}: {v}");
            }
            let mut d = l.clone();
            d.dedup();
            assert_eq!(d.len(), l.len(), "{lo}..{hi}: {l:?}");
        }
        assert_eq!(
            labels(&log_axis([1.2, 3.4].into_iter())),
            ["1.5", "2", "2.5", "3", "3.5"]
        );
        assert_eq!(
            labels(&log_axis([0.3, 15.0].into_iter())),
            ["0.5", "1", "2", "5", "10"]
        );
    }

    /// Several decades: one label per decade, minor ticks at 2..9 between.
    #[test]
    fn decades_are_labelled_with_minor_ticks() {
        let axis = log_axis([0.0015, 0.02, 80.0].into_iter());
        // The range shown, a little wider than the data's, takes in 0.001 and 100.
        assert_eq!(labels(&axis), ["0.001", "0.01", "0.1", "1", "10", "100"]);
        // 2..9 times each decade from 0.001 to 10.
        assert_eq!(axis.minor.len(), 8 * 5);
        for m in [0.002, 0.05, 3.0, 70.0] {
            assert!(axis.minor.iter().any(|v| (v / m - 1.0).abs() < 1e-9), "{m}");
        }
        let big = log_axis([10.0, 1e6].into_iter());
        assert_eq!(labels(&big), ["10", "100", "1k", "10k", "100k", "1M"]);
        let tiny = log_axis([1e-6, 1e-3].into_iter());
        assert_eq!(labels(&tiny), ["10⁻⁶", "10⁻⁵", "0.0001", "0.001"]);
    }

    /// Frames go on a linear axis from frame 0 (a log axis cannot place 0, and squeezes the
    /// late frames together), labelled in 1-2-5 steps; every point is drawn.
    #[test]
    fn line_charts_place_frames_linearly_from_zero() {
        let pts: Vec<(f64, f64)> = (0..32)
            .map(|f| (f64::from(f), 0.01 + f64::from(f) * 1e-3))
            .collect();
        let axis = linear_axis(pts.iter().map(|p| p.0));
        assert_eq!(labels(&axis), ["0", "5", "10", "15", "20", "25", "30"]);
        let mid = (axis.frac(0.0) + axis.frac(30.0)) / 2.0;
        assert!((axis.frac(15.0) - mid).abs() < 1e-12, "not linear");
        assert!(axis.frac(0.0) > 0.0 && axis.frac(31.0) < 1.0);
        let out = svg(&chart("frames", "t", Plot::Lines(vec![series(b(1), &pts)])));
        let markers = out.matches("\nprimitives in the scene: ").count();
        assert_eq!(markers, 32, "every frame, frame 0 included, has its marker");
    }

    #[test]
    fn numbers_are_plain() {
        assert_eq!(number(2000.0, 1000.0), "2k");
        assert_eq!(number(2.5e6, 1e5), "2.5M");
        assert_eq!(number(0.05, 0.01), "0.05");
        assert_eq!(number(1.0, 1.0), "1");
        assert_eq!(number(3e-6, 1e-6), "3×10⁻⁶");
        assert_eq!(value(0.012_345_6), "0.01235");
        assert_eq!(value(123_456.0), "123.5k");
    }

    /// A backend keeps its colour and marker whatever the other series and their order; a
    /// preset takes its backend's colour; other series never take a backend's colour.
    #[test]
    fn a_backend_has_one_style_everywhere() {
        let (x, y, z) = (b(0), b(1), b(2));
        let a = styles(&[x, y, z]);
        let c = styles(&[z, "mean FLIP", y]);
        assert_eq!(a[1], c[2]);
        assert_eq!(a[2], c[0]);
        assert_ne!(a[0].colour, a[1].colour);
        let fast = backend_style(&format!("{}:fast", b(1))).unwrap();
        assert_eq!(fast.colour, a[1].colour);
        assert_ne!(
            fast.marker,
            backend_style(&format!("{}:quality", b(1))).unwrap().marker
        );
        assert!(!BACKEND_COLOURS.contains(&c[1].colour));
        // Every registry backend has a colour of its own.
        let all: Vec<&str> = registry().collect();
        assert!(all.len() <= BACKEND_COLOURS.len());
        let mut colours: Vec<&str> = styles(&all).iter().map(|s| s.colour).collect();
        colours.sort_unstable();
        colours.dedup();
        assert_eq!(colours.len(), all.len());
        assert!(OTHER_COLOURS.iter().all(|c| !BACKEND_COLOURS.contains(c)));
        // Other series: by sorted name, whatever their order.
        let c = styles(&["zeta", "alpha"]);
        assert_eq!(c[1].colour, OTHER_COLOURS[0]);
        assert_eq!(c[0].colour, OTHER_COLOURS[1]);
    }

    /// The legend sits beside the plot, however many or long its entries.
    #[test]
    fn the_legend_never_covers_the_plot() {
        let many: Vec<Series> = (0..40)
            .map(|i| {
                series(
                    &format!("a rather long series name number {i}"),
                    &[(1.0, 1.0)],
                )
            })
            .collect();
        let bars = Plot::Categories(
            vec!["spheres".into(), "a-very-long-scene-name".into()],
            vec![Bars {
                label: b(1).into(),
                values: vec![Bar::Value(2.0), Bar::Unsupported("why".into())],
            }],
        );
        for c in [
            chart("one", "t", Plot::LogLog(vec![series(b(1), &[(1.0, 2.0)])])),
            chart("many", "t", Plot::Scatter(many)),
            chart("bars", "t", bars),
        ] {
            let entries = legend_entries(&c);
            let y = log_axis([1.0, 2.0].into_iter());
            let lay = layout(&c, &y, &entries);
            assert!(!lay.legend.overlaps(&lay.plot), "{}", c.stem);
            assert!(lay.legend.right() <= lay.width && lay.legend.bottom() <= lay.height);
            assert!(
                lay.rows * lay.legend.w.div_euclid(lay.column).max(1.0) as usize >= entries.len()
            );
        }
    }

    /// Text is escaped; ids start with the stem; no style sheet; every point a tooltip.
    #[test]
    fn svg_is_safe_to_inline() {
        let c = Chart {
            title: "a <b> & \"c\"".into(),
            stem: "throughput-cast-primary".into(),
            x_label: String::new(),
            y_label: "rays per second (millions)".into(),
            plot: Plot::Categories(
                vec!["spheres".into(), "x&y".into()],
                vec![
                    Bars {
                        label: b(0).into(),
                        values: vec![Bar::Value(1.5), Bar::Value(2.0)],
                    },
                    Bars {
                        label: b(3).into(),
                        values: vec![Bar::Value(30.0), Bar::Unsupported("no <SDF>".into())],
                    },
                ],
            ),
        };
        let s = svg(&c);
        assert!(s.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 "));
        assert!(
            s.contains("<title>a &lt;b&gt; &amp; &quot;c&quot;</title>"),
            "{s}"
        );
        assert!(s.contains("x&amp;y") && !s.contains("x&y"));
        assert!(
            s.contains(&format!("{} on x&amp;y: no &lt;SDF&gt;", b(3))),
            "{s}"
        );
        assert!(!s.contains("<style") && !s.contains("class="));
        for part in s.split("id=\"").skip(1) {
            assert!(part.starts_with("throughput-cast-primary-"), "{part}");
        }
        for part in s.split("url(#").skip(1) {
            assert!(part.starts_with("throughput-cast-primary-"), "{part}");
        }
        // The chart's title, three bars and one stub with a tooltip each; both backends'
        // colours.
        assert_eq!(s.matches("<title>").count(), 1 + 3 + 1, "{s}");
        assert!(s.contains(backend_style(b(3)).unwrap().colour));
        assert!(s.contains(backend_style(b(0)).unwrap().colour));
        assert!(s.contains(">×</text>"));
        assert_eq!(id_prefix("3d.x"), "c-3d_x");
    }

    /// A fitted power law is drawn dashed in the series' colour and named in the legend.
    #[test]
    fn fits_are_drawn_dashed() {
        let mut s = series(b(1), &[(10.0, 0.01), (100.0, 0.02), (1000.0, 0.04)]);
        s.fit = Some(PowerLaw {
            coefficient: 0.005,
            exponent: 0.3,
        });
        let out = svg(&chart("fit", "t", Plot::LogLog(vec![s])));
        let colour = backend_style(b(1)).unwrap().colour;
        assert!(
            out.contains(&format!(
                "stroke=\"{colour}\" stroke-width=\"1.6\" stroke-dasharray"
            )),
            "{out}"
        );
        assert!(out.contains(&format!("{} (slope 0.30)", b(1))));
        assert_eq!(out.matches("<title>bvh\n").count(), 3, "{out}");
    }
}
