//! The report's charts, drawn by plotters' SVG backend: one `STEM.svg` per [`Chart`], meant
//! to be shown as an image or embedded into an HTML page beside others.
//!
//! What every chart keeps to:
//! - **One colour and one marker per backend across every chart** ([`styles`]): keyed by
//!   the backend's place in the registry ([`raybench_registry::BACKENDS`], then [`raybench_registry::NOT_BUILT`]), a
//!   preset `BACKEND:PRESET` in its backend's colour with a marker of its own, any other
//!   series from a separate list by its sorted name.
//! - **Readable ticks** (`ticks`): log axes label every decade with minor ticks at 2..9, or
//!   1-2-5 steps (then every integer, then a linear step) where the data span too few
//!   decades, so that at least three labels show; values written plainly (`0.01`, `20`,
//!   `1k`, `2.5M`), never `1e0`.
//! - **Legends beside the plot** (`layout`), never over it; fitted power laws drawn dashed
//!   with their slope in the legend; bars of backends that did not run drawn as a hatched
//!   stub with an `×` and the reason.
//! - **Safe to embed**: presentation attributes only (no `<style>`, no classes, no ids),
//!   text escaped; every point, bar and stub has a `<title>` (a browser's tooltip) with its
//!   series and values (`tooltips`: the one step after plotters).
//!
//! `plot` draws with plotters; text is laid out from estimated widths, so no font is read.

mod layout;
mod plot;
mod ticks;
mod tooltips;

use std::path::Path;

/// A chart: its title, file stem (under `charts/`), axis titles and what it plots.
#[derive(Clone, Debug)]
pub struct Chart {
    /// Its title.
    pub title: String,
    /// Its file name without extension (`STEM.svg`).
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
    /// As [`Plot::LogLog`], with labelled vertical marks on the `x` axis (where the
    /// memory of the scaling experiment's data outgrows each cache level).
    Marked(Vec<Series>, Vec<XMark>),
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

/// A labelled vertical mark at `x` of a [`Plot::Marked`], drawn dashed across the plot
/// with its label at the top; one outside the `x` axis's range is not drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct XMark {
    /// Where it stands on the `x` axis.
    pub x: f64,
    /// Its short label (`L2`).
    pub label: String,
    /// Its tooltip: what it marks.
    pub title: String,
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
    /// A measured value with its confidence interval `[lo, hi]`, drawn as an error bar over
    /// the bar and named in its tooltip.
    Interval {
        /// The value (the bar's height).
        value: f64,
        /// Lower end of the interval.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
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
                .unwrap_or_else(|| crate::fnv1a(p.as_bytes()) as usize);
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

/// The SVG text of `chart`.
///
/// # Errors
/// When plotters fails to draw it.
pub fn svg(chart: &Chart) -> Result<String, String> {
    let (x, y) = plot::axes(chart);
    let entries = layout::legend_entries(chart);
    let lay = layout::layout(chart, &y, &entries);
    let mut tips = tooltips::Tips::default();
    let mut body = String::new();
    plot::draw(
        &mut body,
        chart,
        &lay,
        &entries,
        (x.as_ref(), &y),
        &mut tips,
    )?;
    tooltips::finish(
        &body,
        (lay.width as u32, lay.height as u32),
        &chart.title,
        &tips,
    )
}

/// Writes `dir/STEM.svg` (through a temporary name, like every file of a report); returns
/// its file name.
///
/// # Errors
/// When the chart cannot be drawn or the file cannot be written.
pub fn draw(dir: &Path, chart: &Chart) -> Result<String, String> {
    let name = format!("{}.svg", chart.stem);
    let path = dir.join(&name);
    let text = svg(chart)?;
    raybench_render::write_file(&path, text.as_bytes()).map_err(|e| e.to_string())?;
    Ok(name)
}

#[cfg(test)]
mod tests {
    use super::layout::{layout, legend_entries};
    use super::ticks::{Axis, linear_axis, log_axis, number, value};
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

    /// An element of a chart's SVG, read back: its tag, attributes and text, and the
    /// tooltip of the group it is in.
    #[derive(Debug)]
    struct Element {
        tag: String,
        attributes: Vec<(String, String)>,
        text: String,
        tip: Option<String>,
    }

    impl Element {
        fn get(&self, name: &str) -> Option<&str> {
            self.attributes
                .iter()
                .find(|(k, _)| k == name)
                .map(|(_, v)| v.as_str())
        }

        /// A pixel coordinate attribute.
        fn at(&self, name: &str) -> f64 {
            self.get(name)
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::NAN)
        }
    }

    fn unescape(s: &str) -> String {
        s.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&#39;", "'")
            .replace("&apos;", "'")
            .replace("&amp;", "&")
    }

    /// The elements of `svg` in document order (a reader for what the charts write, not
    /// for XML at large: no comments, no CDATA); a text element's or title's text trimmed.
    fn parse(svg: &str) -> Vec<Element> {
        let mut out: Vec<Element> = Vec::new();
        let mut groups: Vec<Option<String>> = Vec::new();
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = rest[start..].find('>').expect("a tag ends") + start;
            let tag = &rest[start + 1..end];
            let after = &rest[end + 1..];
            let text = unescape(after[..after.find('<').unwrap_or(after.len())].trim());
            rest = after;
            if tag.starts_with('/') {
                if tag == "/g" {
                    groups.pop();
                }
                continue;
            }
            let (name, attrs) = tag
                .trim_end_matches('/')
                .split_once(' ')
                .unwrap_or((tag.trim_end_matches('/'), ""));
            if name == "g" {
                groups.push(None);
            }
            if name == "title"
                && let Some(top) = groups.last_mut()
            {
                *top = Some(text.clone());
            }
            let mut attributes = Vec::new();
            for part in attrs.split('"').collect::<Vec<_>>().chunks(2) {
                if let [k, v] = part {
                    attributes.push((k.trim().trim_end_matches('=').to_string(), unescape(v)));
                }
            }
            out.push(Element {
                tag: name.to_string(),
                attributes,
                text,
                tip: groups.iter().rev().find_map(Clone::clone),
            });
        }
        out
    }

    /// The texts of `svg`'s text elements.
    fn texts(elements: &[Element]) -> Vec<&str> {
        elements
            .iter()
            .filter(|e| e.tag == "text")
            .map(|e| e.text.as_str())
            .collect()
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
    /// late frames together), labelled in 1-2-5 steps; every point is drawn, with its
    /// tooltip, left to right.
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
        let out = svg(&chart("frames", "t", Plot::Lines(vec![series(b(1), &pts)]))).unwrap();
        let markers = out.matches("\nprimitives in the scene: ").count();
        assert_eq!(markers, 32, "every frame, frame 0 included, has its marker");
        let elements = parse(&out);
        let colour = backend_style(b(1)).unwrap().colour;
        let xs: Vec<f64> = elements
            .iter()
            .filter(|e| e.tip.as_deref().is_some_and(|t| t.starts_with(b(1))))
            .filter(|e| e.get("fill") == Some(colour))
            .map(|e| match e.tag.as_str() {
                "circle" => e.at("cx"),
                _ => e.get("points").map_or(f64::NAN, |p| {
                    let xs: Vec<f64> = p
                        .split_whitespace()
                        .filter_map(|xy| xy.split(',').next()?.parse().ok())
                        .collect();
                    xs.iter().sum::<f64>() / xs.len() as f64
                }),
            })
            .collect();
        assert_eq!(xs.len(), 32, "{out}");
        assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        // One line through them in the series' colour.
        let line = elements
            .iter()
            .find(|e| e.tag == "polyline" && e.get("stroke") == Some(colour))
            .expect("a line");
        assert_eq!(line.get("points").unwrap().split_whitespace().count(), 32);
        for label in labels(&axis) {
            assert!(texts(&elements).contains(&label), "{label}: {out}");
        }
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

    /// The legend sits beside the plot, however many or long its entries: laid out so, and
    /// drawn so.
    #[test]
    fn the_legend_never_covers_the_plot() {
        let many: Vec<Series> = (0..40)
            .map(|i| {
                series(
                    &format!("a rather long series name number {i}"),
                    &[(1.0, 1.0 + f64::from(i))],
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
            // Drawn: every legend text right of the plot's frame, inside the picture.
            let out = svg(&c).unwrap();
            let elements = parse(&out);
            let frame = elements
                .iter()
                .find(|e| e.tag == "rect" && e.get("stroke") == Some("#444444"))
                .expect("the plot's frame");
            let right = frame.at("x") + frame.at("width");
            let width: f64 = out
                .split_once("width=\"")
                .and_then(|(_, w)| w.split('"').next()?.parse().ok())
                .unwrap();
            for (label, _) in &entries {
                let t = elements
                    .iter()
                    .find(|e| e.tag == "text" && e.text == *label)
                    .unwrap_or_else(|| panic!("{label}: {out}"));
                assert!(t.at("x") > right && t.at("x") < width, "{label}: {out}");
            }
        }
    }

    /// Every backend's bars in its colour with a tooltip each, stubs where one did not run
    /// (hatched, with an `×` and the reason); text escaped; no style sheet, class or id.
    #[test]
    fn bars_and_stubs_show_every_backend() {
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
                        values: vec![
                            Bar::Interval {
                                value: 30.0,
                                lo: 27.0,
                                hi: 33.0,
                            },
                            Bar::Unsupported("no <SDF>".into()),
                        ],
                    },
                ],
            ),
        };
        let s = svg(&c).unwrap();
        assert!(s.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 "));
        assert!(s.ends_with("</svg>\n"));
        assert!(
            s.contains("<title>a &lt;b&gt; &amp; &quot;c&quot;</title>"),
            "{s}"
        );
        assert!(s.contains("x&amp;y") && !s.contains("x&y"));
        assert!(!s.contains("<style") && !s.contains("class=") && !s.contains(" id="));
        // The chart's title, three bars and one stub with a tooltip each.
        assert_eq!(s.matches("<title>").count(), 1 + 3 + 1, "{s}");
        let elements = parse(&s);
        for (backend, values) in [(b(0), [1.5, 2.0]), (b(3), [30.0, 0.0])] {
            let colour = backend_style(backend).unwrap().colour;
            let bars: Vec<&Element> = elements
                .iter()
                .filter(|e| e.tag == "rect" && e.get("fill") == Some(colour) && e.tip.is_some())
                .collect();
            let expected = values.iter().filter(|v| **v > 0.0).count();
            assert_eq!(bars.len(), expected, "{backend}: {s}");
            for (bar, scene) in bars.iter().zip(["spheres", "x&y"]) {
                assert!(
                    bar.tip
                        .as_deref()
                        .is_some_and(|t| t.starts_with(&format!("{backend} on {scene}\n"))),
                    "{bar:?}"
                );
            }
        }
        // Taller bars for larger values (a log axis, from the same floor).
        let height = |v: f64| {
            elements
                .iter()
                .find(|e| {
                    e.tag == "rect"
                        && e.tip.as_deref().is_some_and(|t| {
                            t.ends_with(&value(v)) || t.contains(&format!("{} (95%", value(v)))
                        })
                })
                .map(|e| e.at("height"))
                .unwrap()
        };
        assert!(height(1.5) < height(2.0) && height(2.0) < height(30.0));
        // The interval's error bar: a vertical line and two caps over the bar, and the
        // interval in the bar's tooltip.
        let with_interval = format!("{} on spheres", b(3));
        assert!(elements.iter().any(|e| e.tip.as_deref().is_some_and(|t| {
            t.starts_with(&with_interval)
                && t.ends_with(&format!(
                    "(95% interval {} to {})",
                    value(27.0),
                    value(33.0)
                ))
        })));
        // Vertical lines: the y axis, the tick between the two groups, and the error bar.
        let vertical = elements
            .iter()
            .filter(|e| e.tag == "polyline")
            .filter_map(|e| {
                let xs: Vec<&str> = e
                    .get("points")?
                    .split_whitespace()
                    .filter_map(|p| p.split(',').next())
                    .collect();
                (xs.len() == 2 && xs[0] == xs[1]).then_some(())
            })
            .count();
        assert_eq!(vertical, 3, "{s}");
        let why = format!("{} on x&y: no <SDF>", b(3));
        let stub: Vec<&Element> = elements
            .iter()
            .filter(|e| e.tip.as_deref() == Some(why.as_str()))
            .collect();
        let colour = backend_style(b(3)).unwrap().colour;
        assert!(
            stub.iter()
                .any(|e| e.tag == "rect" && e.get("stroke") == Some(colour)),
            "{stub:?}"
        );
        assert!(stub.iter().any(|e| e.tag == "text" && e.text == "×"));
        assert!(
            stub.iter().filter(|e| e.tag == "polyline").count() >= 2,
            "hatched"
        );
        let t = texts(&elements);
        assert!(t.contains(&"× did not run (hover: why)"), "{t:?}");
        assert!(t.contains(&"rays per second (millions)") && t.contains(&"spheres"));
        for label in labels(&log_axis([1.5, 30.0, 0.45].into_iter())) {
            assert!(t.contains(&label), "{label}: {t:?}");
        }
    }

    /// A fitted power law is drawn dashed in the series' colour and named in the legend.
    #[test]
    fn fits_are_drawn_dashed() {
        let mut s = series(b(1), &[(10.0, 0.01), (100.0, 0.02), (1000.0, 0.04)]);
        s.fit = Some(PowerLaw {
            coefficient: 0.005,
            exponent: 0.3,
        });
        let out = svg(&chart("fit", "t", Plot::LogLog(vec![s]))).unwrap();
        let colour = backend_style(b(1)).unwrap().colour;
        let elements = parse(&out);
        let dashes = elements
            .iter()
            .filter(|e| {
                e.tip
                    .as_deref()
                    .is_some_and(|t| t.starts_with(&format!("{}: fitted 0.005 x^0.300", b(1))))
            })
            .filter(|e| e.tag == "polyline" && e.get("stroke") == Some(colour))
            .count();
        assert!(dashes >= 10, "{out}");
        assert!(texts(&elements).contains(&format!("{} (slope 0.30)", b(1)).as_str()));
        assert!(texts(&elements).contains(&"fitted y = a·x^slope"));
        assert_eq!(
            out.matches(&format!("<title>{}\n", b(1))).count(),
            3,
            "{out}"
        );
    }

    /// An `x` mark inside the axis's range is a dotted grey line across the plot with its
    /// label and tooltip; one outside the range is not drawn.
    #[test]
    fn x_marks_inside_the_range_are_drawn() {
        let mark = |x: f64, label: &str| XMark {
            x,
            label: label.into(),
            title: format!("{label} reached"),
        };
        let s = series(b(1), &[(10.0, 0.01), (1000.0, 0.04)]);
        let plot = Plot::Marked(vec![s], vec![mark(100.0, "L2"), mark(1e9, "L3")]);
        let out = svg(&chart("marked", "t", plot)).unwrap();
        let elements = parse(&out);
        let inside: Vec<&Element> = elements
            .iter()
            .filter(|e| e.tip.as_deref() == Some("L2 reached"))
            .collect();
        assert!(
            inside.iter().filter(|e| e.tag == "polyline").count() >= 10,
            "dotted: {out}"
        );
        assert!(inside.iter().any(|e| e.tag == "text" && e.text == "L2"));
        assert!(!out.contains("L3"), "{out}");
    }

    /// A mark's look-alike in a label stays text; the tooltips' groups are balanced.
    #[test]
    fn labels_cannot_pass_for_tooltip_marks() {
        let mut c = chart(
            "marks",
            "\u{E000}0",
            Plot::Scatter(vec![series("\u{E000}", &[(1.0, 2.0)])]),
        );
        c.x_label = "\u{E000}".into();
        let out = svg(&c).unwrap();
        assert!(!out.contains('\u{E000}'));
        assert_eq!(out.matches("<g>").count(), out.matches("</g>").count());
        assert_eq!(out.matches("<g>").count(), 1, "{out}");
    }

    /// Names too wide for their group are written upright, wholly below the plot.
    #[test]
    fn wide_names_stand_upright_below_the_plot() {
        let names: Vec<String> = (0..12)
            .map(|i| format!("a-rather-long-scene-{i}"))
            .collect();
        let bars: Vec<Bars> = (0..6)
            .map(|j| Bars {
                label: b(j).into(),
                values: (0..12).map(|i| Bar::Value(f64::from(1 + i))).collect(),
            })
            .collect();
        let out = svg(&chart("up", "t", Plot::Categories(names.clone(), bars))).unwrap();
        let elements = parse(&out);
        let frame = elements
            .iter()
            .find(|e| e.tag == "rect" && e.get("stroke") == Some("#444444"))
            .expect("the plot's frame");
        let bottom = frame.at("y") + frame.at("height");
        for name in &names {
            let t = elements
                .iter()
                .find(|e| e.tag == "text" && e.text == *name)
                .unwrap_or_else(|| panic!("{name}: {out}"));
            assert!(
                t.get("transform")
                    .is_some_and(|r| r.starts_with("rotate(270"))
            );
            // Anchored at its end below the plot, it runs downwards from there.
            assert_eq!(t.get("text-anchor"), Some("end"));
            assert!(t.at("y") > bottom, "{name}: {out}");
        }
    }
}
