//! Where a chart's parts go: the title above, the plot with its axes' labels, and the legend
//! beside the plot (never over it), in SVG user units (the plotters backend's pixels), from
//! estimated text widths.

use super::ticks::Axis;
use super::{Bar, Chart, Plot, Style, styles};

/// A rectangle in SVG user units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Rect {
    /// Its left edge.
    pub(super) x: f64,
    /// Its top edge.
    pub(super) y: f64,
    /// Its width.
    pub(super) w: f64,
    /// Its height.
    pub(super) h: f64,
}

impl Rect {
    /// Its right edge.
    pub(super) fn right(&self) -> f64 {
        self.x + self.w
    }

    /// Its bottom edge.
    pub(super) fn bottom(&self) -> f64 {
        self.y + self.h
    }

    /// Whether the two share any area.
    #[cfg(test)]
    pub(super) fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.right() && o.x < self.right() && self.y < o.bottom() && o.y < self.bottom()
    }
}

/// The title's font size (user units).
pub(super) const TITLE_SIZE: f64 = 16.0;
/// The axis titles' font size.
pub(super) const LABEL_SIZE: f64 = 13.0;
/// The tick labels' font size.
pub(super) const TICK_SIZE: f64 = 11.0;
/// The legend's font size.
pub(super) const LEGEND_SIZE: f64 = 12.0;
/// Average advance of a character over the font size (DejaVu Sans runs wide).
const CHAR_WIDTH: f64 = 0.62;
/// Height of a legend row.
pub(super) const LEGEND_ROW: f64 = 18.0;
/// The plot area of a chart of series (a bar chart's grows with its groups).
const PLOT: (f64, f64) = (560.0, 360.0);
/// The gap between a tick label and the plot's edge.
const TICK_GAP: f64 = 10.0;

/// Estimated width of `text` at font size `size`.
pub(super) fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * CHAR_WIDTH
}

/// How a legend entry shows its series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Key {
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
pub(super) struct Layout {
    /// The whole chart's width.
    pub(super) width: f64,
    /// The whole chart's height.
    pub(super) height: f64,
    /// The plot: its frame, inside the axes' labels.
    pub(super) plot: Rect,
    /// The height below the plot for the `x` tick labels and the axis title.
    pub(super) below: f64,
    /// The legend's box.
    pub(super) legend: Rect,
    /// Legend rows per column.
    pub(super) rows: usize,
    /// Width of a legend column.
    pub(super) column: f64,
    /// Category labels written upright (too wide for their group).
    pub(super) upright: bool,
}

/// The legend's entries of `chart`, with the series' styles.
pub(super) fn legend_entries(chart: &Chart) -> Vec<(String, Key)> {
    let mut out = Vec::new();
    match &chart.plot {
        Plot::LogLog(series)
        | Plot::Marked(series, _)
        | Plot::Scatter(series)
        | Plot::Lines(series) => {
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
pub(super) fn layout(chart: &Chart, y: &Axis, entries: &[(String, Key)]) -> Layout {
    let left = 14.0 + LABEL_SIZE + 10.0 + widest(y) + TICK_GAP;
    let top = 14.0 + TITLE_SIZE + 14.0;
    let (mut plot_w, plot_h) = PLOT;
    let mut labels_h = TICK_SIZE;
    let mut upright = false;
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
            upright = true;
            labels_h = longest;
        }
    }
    let below = TICK_GAP + labels_h + 12.0 + LABEL_SIZE + 10.0;
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
    let height = (plot.bottom() + below).max(legend.bottom() + 12.0);
    Layout {
        width: width.ceil(),
        height: height.ceil(),
        plot,
        below,
        legend,
        rows,
        column,
        upright,
    }
}
