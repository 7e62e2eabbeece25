//! A chart drawn by plotters' SVG backend: the mesh, ticks and axis titles by its chart
//! builder, lines, fits and bars as its series and elements in the chart's coordinates,
//! markers, stubs and the legend as its elements in pixels. Log axes are drawn in `log10` of
//! their values on a linear plotters axis, with the ticks and labels of [`super::ticks`].

use super::layout::{Key, LABEL_SIZE, LEGEND_ROW, LEGEND_SIZE, Layout, TICK_SIZE, TITLE_SIZE};
use super::ticks::{Axis, value};
use super::tooltips::{Tips, plain};
use super::{Bar, Bars, Chart, Marker, Plot, Series, Style, XMark, styles};
use plotters::coord::Shift;
use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The drawing area of a whole chart, in pixels from its top left corner.
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// What drawing can fail with (plotters' error, as text).
type Drawn = Result<(), String>;

/// The font of every text: DejaVu Sans first, whose widths [`super::layout`] estimates.
const FONT: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";
/// Text.
const INK: RGBColor = RGBColor(0x22, 0x22, 0x22);
/// The plot's frame and axes.
const FRAME: RGBColor = RGBColor(0x44, 0x44, 0x44);
/// A labelled tick's grid line.
const GRID: RGBColor = RGBColor(0xd0, 0xd0, 0xd0);
/// An unlabelled tick's grid line.
const GRID_MINOR: RGBColor = RGBColor(0xee, 0xee, 0xee);
/// The legend's box.
const LEGEND_FRAME: RGBColor = RGBColor(0xbb, 0xbb, 0xbb);
/// The hatching of stubs, and the keys that stand for no one series.
const GREY: RGBColor = RGBColor(0x55, 0x55, 0x55);
/// Height of the hatched stub that marks a series that did not run.
const STUB: i32 = 12;
/// The margin left of the `y` axis title.
const MARGIN: i32 = 8;
/// A marker's half-size.
const R: i32 = 4;

/// An axis as plotters' coordinate: linear over `lo..hi` (a log axis in `log10` of its
/// values), with the ticks of [`super::ticks`] as its bold and light points.
#[derive(Clone, Debug)]
struct Ticked {
    /// The low end.
    lo: f64,
    /// The high end.
    hi: f64,
    /// The labelled ticks.
    bold: Vec<f64>,
    /// The unlabelled ticks.
    light: Vec<f64>,
}

impl Ranged for Ticked {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, (from, to): (i32, i32)) -> i32 {
        let f = (v - self.lo) / (self.hi - self.lo);
        from + (f * f64::from(to - from)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// plotters' error as text.
fn failed(e: impl std::fmt::Display) -> String {
    format!("cannot draw a chart: {e}")
}

/// A `#RRGGBB` colour of the palette as plotters' colour.
fn rgb(hex: &str) -> RGBColor {
    let channel = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            .unwrap_or(0)
    };
    RGBColor(channel(1), channel(3), channel(5))
}

/// A text style of `FONT` whose SVG `font-size` is `size`.
fn font(size: f64) -> TextStyle<'static> {
    font_in(size, FontStyle::Normal)
}

/// A text style of `FONT` in `style` whose SVG `font-size` is `size`: plotters writes its
/// size over 1.24, so the one `f64` that gives back `size` exactly is looked for beside
/// `size * 1.24`.
fn font_in(size: f64, style: FontStyle) -> TextStyle<'static> {
    let mut scaled = size * 1.24;
    for candidate in [scaled, scaled.next_up(), scaled.next_down()] {
        if candidate / 1.24 == size {
            scaled = candidate;
            break;
        }
    }
    TextStyle::from((FONT, scaled, style)).color(&INK)
}

/// `text` at pixel `at`, placed by `pos`.
fn text(area: &Area, s: &str, at: (i32, i32), style: &TextStyle, pos: Pos) -> Drawn {
    area.draw(&Text::new(plain(s), at, style.pos(pos)))
        .map_err(failed)
}

/// Draws `inside` as a group whose tooltip is `title`.
fn tip(area: &Area, tips: &mut Tips, title: String, inside: impl FnOnce() -> Drawn) -> Drawn {
    let mark = font(1.0);
    let at = Pos::new(HPos::Left, VPos::Top);
    area.draw(&Text::new(tips.open(title), (0, 0), mark.pos(at)))
        .map_err(failed)?;
    inside()?;
    area.draw(&Text::new(Tips::close(), (0, 0), mark.pos(at)))
        .map_err(failed)
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

/// The labels of `axis` by coordinate, a label left empty where it would touch the one
/// before it over `length` pixels (its tick and grid line stay).
fn tick_labels(axis: &Axis, length: f64) -> Vec<(f64, String)> {
    let mut free_from = f64::NEG_INFINITY;
    axis.major
        .iter()
        .map(|(v, label)| {
            let at = axis.frac(*v) * length;
            let half = super::layout::text_width(label, TICK_SIZE) / 2.0;
            let shown = at - half >= free_from;
            if shown {
                free_from = at + half + 6.0;
            }
            (
                axis.at(*v),
                if shown { label.clone() } else { String::new() },
            )
        })
        .collect()
}

/// The label of the tick at coordinate `at` (the nearest of `labels`).
fn label_at(labels: &[(f64, String)], at: f64) -> String {
    labels
        .iter()
        .min_by(|a, b| (a.0 - at).abs().total_cmp(&(b.0 - at).abs()))
        .map(|(_, l)| plain(l))
        .unwrap_or_default()
}

/// A marker centred on pixel `(x, y)`.
fn marker(area: &Area, (x, y): (i32, i32), style: Style) -> Drawn {
    let colour = rgb(style.colour);
    let filled = colour.filled();
    let stroked = colour.stroke_width(2);
    let polygon = |pts: &[(f64, f64)]| {
        let f = f64::from(R);
        let pts: Vec<(i32, i32)> = pts
            .iter()
            .map(|(px, py)| (x + (px * f).round() as i32, y + (py * f).round() as i32))
            .collect();
        area.draw(&Polygon::new(pts, filled)).map_err(failed)
    };
    match style.marker {
        Marker::Circle => area.draw(&Circle::new((x, y), R, filled)).map_err(failed),
        Marker::Square => polygon(&[(-0.9, -0.9), (0.9, -0.9), (0.9, 0.9), (-0.9, 0.9)]),
        Marker::TriangleUp => polygon(&[(0.0, -1.25), (1.1, 0.75), (-1.1, 0.75)]),
        Marker::TriangleDown => polygon(&[(0.0, 1.25), (1.1, -0.75), (-1.1, -0.75)]),
        Marker::Diamond => polygon(&[(0.0, -1.3), (1.1, 0.0), (0.0, 1.3), (-1.1, 0.0)]),
        Marker::Star => {
            let pts: Vec<(f64, f64)> = (0..10)
                .map(|i| {
                    let a = std::f64::consts::PI * (f64::from(i) / 5.0 - 0.5);
                    let k = if i % 2 == 0 { 1.45 } else { 0.6 };
                    (k * a.cos(), k * a.sin())
                })
                .collect();
            polygon(&pts)
        }
        Marker::Cross | Marker::Plus => {
            // A nearly transparent disc under the strokes makes the tooltip easier to reach.
            area.draw(&Circle::new((x, y), R + 2, WHITE.mix(0.01).filled()))
                .map_err(failed)?;
            let k = R + 1;
            let strokes = if style.marker == Marker::Cross {
                [
                    [(x - k, y - k), (x + k, y + k)],
                    [(x - k, y + k), (x + k, y - k)],
                ]
            } else {
                [[(x - k, y), (x + k, y)], [(x, y - k), (x, y + k)]]
            };
            for s in strokes {
                area.draw(&PathElement::new(s.to_vec(), stroked))
                    .map_err(failed)?;
            }
            Ok(())
        }
    }
}

/// A hatched rectangle from pixel `(x0, y0)` to `(x1, y1)`, outlined in `outline`.
fn hatched(area: &Area, (x0, y0): (i32, i32), (x1, y1): (i32, i32), outline: RGBColor) -> Drawn {
    let (w, h) = (x1 - x0, y1 - y0);
    // Lines at 45 degrees every 5 pixels, cut at the rectangle's edges.
    for t in (4..w + h).step_by(5) {
        let from = if t <= w {
            (x0 + t, y0)
        } else {
            (x1, y0 + t - w)
        };
        let to = if t >= h {
            (x0 + t - h, y1)
        } else {
            (x0, y0 + t)
        };
        area.draw(&PathElement::new(vec![from, to], GREY.mix(0.8)))
            .map_err(failed)?;
    }
    area.draw(&Rectangle::new([(x0, y0), (x1, y1)], outline))
        .map_err(failed)
}

/// The legend box and its entries, beside the plot.
fn legend(area: &Area, lay: &Layout, entries: &[(String, Key)]) -> Drawn {
    if entries.is_empty() {
        return Ok(());
    }
    let l = lay.legend;
    let px = |v: f64| v.round() as i32;
    area.draw(&Rectangle::new(
        [(px(l.x), px(l.y)), (px(l.right()), px(l.bottom()))],
        LEGEND_FRAME,
    ))
    .map_err(failed)?;
    let style = font(LEGEND_SIZE);
    for (i, (label, key)) in entries.iter().enumerate() {
        let (col, row) = (i / lay.rows, i % lay.rows);
        let x = px(l.x + 8.0 + col as f64 * lay.column);
        let y = px(l.y + 5.0 + (row as f64 + 0.5) * LEGEND_ROW);
        match *key {
            Key::Line(st) => {
                area.draw(&PathElement::new(
                    vec![(x, y), (x + 24, y)],
                    rgb(st.colour).stroke_width(2),
                ))
                .map_err(failed)?;
                marker(area, (x + 12, y), st)?;
            }
            Key::Point(st) => marker(area, (x + 12, y), st)?,
            Key::Swatch(st) => area
                .draw(&Rectangle::new(
                    [(x + 6, y - 6), (x + 18, y + 6)],
                    rgb(st.colour).filled(),
                ))
                .map_err(failed)?,
            Key::Dashed => {
                for (a, b) in [(0, 7), (11, 18), (22, 24)] {
                    area.draw(&PathElement::new(
                        vec![(x + a, y), (x + b, y)],
                        GREY.stroke_width(2),
                    ))
                    .map_err(failed)?;
                }
            }
            Key::Hatched => hatched(area, (x + 6, y - 6), (x + 18, y + 6), GREY)?,
        }
        text(
            area,
            label,
            (x + 30, y),
            &style,
            Pos::new(HPos::Left, VPos::Center),
        )?;
    }
    Ok(())
}

/// What a chart's marks are drawn on: the whole chart (pixels) and its plot (the axes'
/// coordinates).
struct Canvas<'c, 'a, 'b> {
    /// The whole chart.
    root: &'c Area<'b>,
    /// The plot.
    plot: &'c mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<Ticked, Ticked>>,
    /// What it plots.
    chart: &'c Chart,
    /// Its `y` axis.
    y: &'c Axis,
    /// The tooltips drawn so far.
    tips: &'c mut Tips,
}

impl Canvas<'_, '_, '_> {
    /// Each series a line (but in a scatter plot) through its markers, its fitted power law
    /// dashed, over `x`.
    fn series(&mut self, series: &[Series], x: &Axis) -> Drawn {
        let lines = !matches!(self.chart.plot, Plot::Scatter(_));
        let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
        let y = self.y;
        let at = |(u, v): (f64, f64)| (x.at(u), y.at(v));
        for (s, st) in series.iter().zip(styles(&labels)) {
            let colour = rgb(st.colour);
            if let (Some(f), Some((a, b))) = (s.fit, x_range(s)) {
                let title = format!(
                    "{}: fitted {} x^{:.3}",
                    s.label,
                    value(f.coefficient),
                    f.exponent
                );
                let ends = [at((a, f.at(a))), at((b, f.at(b)))];
                let plot = &mut *self.plot;
                tip(self.root, self.tips, title, || {
                    plot.draw_series(DashedLineSeries::new(ends, 7, 4, colour.stroke_width(2)))
                        .map(|_| ())
                        .map_err(failed)
                })?;
            }
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(u, v)| x.shows(u) && v > 0.0 && v.is_finite())
                .collect();
            if lines && points.len() > 1 {
                self.plot
                    .draw_series(LineSeries::new(
                        points.iter().map(|p| at(*p)),
                        colour.stroke_width(2),
                    ))
                    .map_err(failed)?;
            }
            for &(u, v) in &points {
                let title = format!(
                    "{}\n{}: {}\n{}: {}",
                    s.label,
                    axis_name(&self.chart.x_label, "x"),
                    value(u),
                    axis_name(&self.chart.y_label, "y"),
                    value(v)
                );
                let centre = self.plot.backend_coord(&at((u, v)));
                let root = self.root;
                tip(root, self.tips, title, || marker(root, centre, st))?;
            }
        }
        Ok(())
    }

    /// Each mark inside the `x` axis's range a dotted grey line across the plot, its label
    /// at the top right of the line and its title the tooltip; drawn before the series, so
    /// that they lie on top.
    fn marks(&mut self, marks: &[XMark], x: &Axis) -> Drawn {
        let y = self.y;
        let inside = |m: &&XMark| x.shows(m.x) && (x.lo..=x.hi).contains(&x.at(m.x));
        for m in marks.iter().filter(inside) {
            let u = x.at(m.x);
            let top = self.plot.backend_coord(&(u, y.hi));
            let bottom = self.plot.backend_coord(&(u, y.lo));
            let root = self.root;
            tip(root, self.tips, m.title.clone(), || {
                let mut from = top.1;
                while from < bottom.1 {
                    let to = (from + 3).min(bottom.1);
                    root.draw(&PathElement::new(
                        vec![(top.0, from), (top.0, to)],
                        GREY.stroke_width(1),
                    ))
                    .map_err(failed)?;
                    from += 6;
                }
                text(
                    root,
                    &m.label,
                    (top.0 + 3, top.1 + 3),
                    &font(TICK_SIZE),
                    Pos::new(HPos::Left, VPos::Top),
                )
            })?;
        }
        Ok(())
    }

    /// One group of bars per name over a plot `width` pixels wide, a hatched stub with an
    /// `×` where a series did not run; the names written `upright` below their groups when
    /// too wide for them.
    fn bars(&mut self, names: &[String], bars: &[Bars], width: f64, upright: bool) -> Drawn {
        let root = self.root;
        let (xs, ys) = self.plot.plotting_area().get_pixel_range();
        let px = |v: f64| v.round() as i32;
        let slot = width / names.len().max(1) as f64;
        let k = bars.len().max(1) as f64;
        // At most 28 units a bar: a few wide groups would look like blocks.
        let bar_w = ((slot - 12.0).max(1.0) / k).min(28.0);
        let first = (slot - bar_w * k) / 2.0;
        // Between groups, a short tick below the plot.
        for i in 1..names.len() {
            let x = xs.start + px(i as f64 * slot);
            root.draw(&PathElement::new(vec![(x, ys.end), (x, ys.end + 5)], FRAME))
                .map_err(failed)?;
        }
        if upright {
            // Read from bottom to top, ending just below the plot.
            let style = font(TICK_SIZE).transform(FontTransform::Rotate270);
            for (i, name) in names.iter().enumerate() {
                let at = (xs.start + px((i as f64 + 0.5) * slot), ys.end + 8);
                text(root, name, at, &style, Pos::new(HPos::Right, VPos::Center))?;
            }
        }
        let labels: Vec<&str> = bars.iter().map(|b| b.label.as_str()).collect();
        for (j, (b, st)) in bars.iter().zip(styles(&labels)).enumerate() {
            let colour = rgb(st.colour);
            for (i, v) in b.values.iter().enumerate() {
                let Some(name) = names.get(i) else { break };
                let x0 = xs.start + px(i as f64 * slot + first + j as f64 * bar_w);
                let x1 = x0 + px(bar_w - 1.0).max(1);
                let interval = match v {
                    Bar::Interval { lo, hi, .. } if lo.is_finite() && hi.is_finite() => {
                        Some((*lo, *hi))
                    }
                    _ => None,
                };
                match v {
                    Bar::Value(v) | Bar::Interval { value: v, .. } if *v > 0.0 && v.is_finite() => {
                        let top = self.plot.backend_coord(&(0.0, self.y.at(*v))).1;
                        let mut title = format!(
                            "{} on {name}\n{}: {}",
                            b.label,
                            axis_name(&self.chart.y_label, "value"),
                            value(*v)
                        );
                        if let Some((lo, hi)) = interval {
                            title.push_str(&format!(
                                " (95% interval {} to {})",
                                value(lo),
                                value(hi)
                            ));
                        }
                        tip(root, self.tips, title, || {
                            root.draw(&Rectangle::new(
                                [(x0, top.min(ys.end - 1)), (x1, ys.end)],
                                colour.filled(),
                            ))
                            .map_err(failed)
                        })?;
                        if let Some((lo, hi)) = interval.filter(|(lo, _)| *lo > 0.0) {
                            self.whisker((x0 + x1) / 2, (lo, hi), (x1 - x0) / 3)?;
                        }
                    }
                    Bar::Unsupported(why) => {
                        let title = format!("{} on {name}: {why}", b.label);
                        tip(root, self.tips, title, || {
                            hatched(root, (x0, ys.end - STUB), (x1, ys.end), colour)?;
                            text(
                                root,
                                "×",
                                ((x0 + x1) / 2, ys.end - STUB - 2),
                                &font(TICK_SIZE).color(&colour),
                                Pos::new(HPos::Center, VPos::Bottom),
                            )
                        })?;
                    }
                    Bar::Value(_) | Bar::Interval { .. } | Bar::Absent => {}
                }
            }
        }
        Ok(())
    }

    /// An error bar at pixel column `x` from value `lo` to `hi`, with caps `half` pixels to
    /// each side, in the frame's colour over the bar.
    fn whisker(&mut self, x: i32, (lo, hi): (f64, f64), half: i32) -> Drawn {
        let root = self.root;
        let (_, ys) = self.plot.plotting_area().get_pixel_range();
        let at = |v: f64| {
            self.plot
                .backend_coord(&(0.0, self.y.at(v)))
                .1
                .clamp(ys.start, ys.end)
        };
        let (bottom, top) = (at(lo), at(hi));
        let half = half.max(2);
        for line in [
            vec![(x, bottom), (x, top)],
            vec![(x - half, top), (x + half, top)],
            vec![(x - half, bottom), (x + half, bottom)],
        ] {
            root.draw(&PathElement::new(line, FRAME)).map_err(failed)?;
        }
        Ok(())
    }
}

/// The axes of `chart`: `x` (none for bars) and `y`.
pub(super) fn axes(chart: &Chart) -> (Option<Axis>, Axis) {
    use super::ticks::{linear_axis, log_axis};
    match &chart.plot {
        Plot::LogLog(series) | Plot::Marked(series, _) | Plot::Scatter(series) => {
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
                .flat_map(|v| match v {
                    Bar::Value(v) if *v > 0.0 && v.is_finite() => vec![*v],
                    Bar::Interval { value, hi, .. } if *value > 0.0 && value.is_finite() => {
                        vec![*value, *hi]
                    }
                    _ => Vec::new(),
                })
                .filter(|v| *v > 0.0 && v.is_finite())
                .collect();
            // Bars rise from the bottom of a log axis: room below the lowest value keeps its
            // bar tall enough to read (and unlike a stub).
            let floor = values.iter().copied().fold(f64::INFINITY, f64::min) * 0.3;
            (None, log_axis(values.into_iter().chain([floor])))
        }
    }
}

/// Draws `chart` laid out by `lay` with its legend's `entries` on its axes into plotters'
/// SVG document `out`, the tooltips' texts into `tips`.
pub(super) fn draw(
    out: &mut String,
    chart: &Chart,
    lay: &Layout,
    entries: &[(String, Key)],
    (x_axis, y_axis): (Option<&Axis>, &Axis),
    tips: &mut Tips,
) -> Drawn {
    let size = (lay.width as u32, lay.height as u32);
    let root = SVGBackend::with_string(out, size).into_drawing_area();
    root.fill(&WHITE).map_err(failed)?;
    text(
        &root,
        &chart.title,
        (size.0 as i32 / 2, 14),
        &font_in(TITLE_SIZE, FontStyle::Bold),
        Pos::new(HPos::Center, VPos::Top),
    )?;
    let p = lay.plot;
    let px = |v: f64| v.round() as i32;
    // The plot and its label areas, a margin left of the `y` axis title: the plot's frame
    // lands on `lay.plot`.
    let area = root.margin(
        px(p.y),
        size.1 as i32 - px(p.bottom() + lay.below),
        MARGIN,
        size.0 as i32 - px(p.right()),
    );
    let categories = match &chart.plot {
        Plot::Categories(names, _) => Some(names),
        _ => None,
    };
    let (x_lo, x_hi, x_labels, x_minor) = match (x_axis, categories) {
        (Some(x), _) => (
            x.lo,
            x.hi,
            tick_labels(x, p.w),
            x.minor.iter().map(|v| x.at(*v)).collect(),
        ),
        (None, names) => {
            let names = names.map_or(&[][..], |n| &n[..]);
            let labels = names
                .iter()
                .enumerate()
                .map(|(i, n)| (i as f64 + 0.5, n.clone()))
                .collect();
            (0.0, names.len().max(1) as f64, labels, Vec::new())
        }
    };
    let y_labels: Vec<(f64, String)> = y_axis
        .major
        .iter()
        .map(|(v, l)| (y_axis.at(*v), l.clone()))
        .collect();
    let x_coords = Ticked {
        lo: x_lo,
        hi: x_hi,
        // Upright names are drawn with the bars: plotters centres a label on its tick,
        // which would put half of an upright one inside the plot.
        bold: if lay.upright {
            Vec::new()
        } else {
            x_labels.iter().map(|l| l.0).collect()
        },
        light: x_minor,
    };
    let y_coords = Ticked {
        lo: y_axis.lo,
        hi: y_axis.hi,
        bold: y_labels.iter().map(|l| l.0).collect(),
        light: y_axis.minor.iter().map(|v| y_axis.at(*v)).collect(),
    };
    let mut plot = ChartBuilder::on(&area)
        .y_label_area_size(px(p.x) - MARGIN)
        .x_label_area_size(px(lay.below))
        .build_cartesian_2d(x_coords, y_coords)
        .map_err(failed)?;
    let x_title = plain(&chart.x_label);
    let y_title = plain(&chart.y_label);
    let x_label = |v: &f64| label_at(&x_labels, *v);
    let y_label = |v: &f64| label_at(&y_labels, *v);
    let mut mesh = plot.configure_mesh();
    mesh.x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .x_label_style(font(TICK_SIZE))
        .y_label_style(font(TICK_SIZE))
        .axis_desc_style(font(LABEL_SIZE))
        .bold_line_style(GRID)
        .light_line_style(GRID_MINOR)
        .axis_style(FRAME)
        .set_all_tick_mark_size(6)
        .x_label_offset(0)
        .y_desc(y_title);
    if !x_title.is_empty() {
        mesh.x_desc(x_title);
    }
    if categories.is_some() {
        mesh.disable_x_mesh()
            .set_tick_mark_size(LabelAreaPosition::Bottom, 0);
    }
    mesh.draw().map_err(failed)?;
    let (xs, ys) = plot.plotting_area().get_pixel_range();
    // The frame.
    root.draw(&Rectangle::new(
        [(xs.start, ys.start), (xs.end, ys.end)],
        FRAME,
    ))
    .map_err(failed)?;
    let mut canvas = Canvas {
        root: &root,
        plot: &mut plot,
        chart,
        y: y_axis,
        tips,
    };
    match (&chart.plot, x_axis) {
        (Plot::LogLog(series) | Plot::Scatter(series) | Plot::Lines(series), Some(x)) => {
            canvas.series(series, x)?;
        }
        (Plot::Marked(series, marks), Some(x)) => {
            canvas.marks(marks, x)?;
            canvas.series(series, x)?;
        }
        (Plot::Categories(names, bars), _) => canvas.bars(names, bars, p.w, lay.upright)?,
        _ => return Err("a chart of series has no x axis".into()),
    }
    legend(&root, lay, entries)?;
    root.present().map_err(failed)
}
