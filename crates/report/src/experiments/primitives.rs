//! Experiment `primitives`: render time (and tests per ray) against the number of
//! primitives M of the `soup:M` and `spheres:M` generators and of the subdivided icosahedron
//! `icosphere:L` (whose silhouette, so the share of camera rays that hit, stays put), 64 x 64
//! camera rays; with the speed-up of every backend over the oracle where it ran, each
//! point's hit fraction, and the charts' `x` marked where the data outgrow each cache.

use super::{
    About, Chart, Ctx, Observed, Plot, Point, Scaling, fit_chart, points_of, series_of, square,
};
use crate::charts::{Series, XMark};
use crate::fmt::section;
use crate::results::{CONSTANT_HITS_PP, Caches, HitFractions, Results, ScalingPoint};
use raybench_core::Mode;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

/// Experiment `primitives`.
pub(super) struct Primitives;

/// Its name and axes.
const ABOUT: About = About {
    name: "primitives",
    x_label: "primitives in the scene",
    axis: Some(
        "the number of primitives M (`soup:M`, `spheres:M`, `icosphere:L` generators, 64 x \
             64 camera rays)",
    ),
};

/// The subdivision levels of the `icosphere` series: 20 4^L triangles, 1,280 to 1,310,720.
const ICOSPHERE_LEVELS: std::ops::RangeInclusive<u32> = 3..=8;

impl Scaling for Primitives {
    type State = ();

    fn about(&self) -> &About {
        &ABOUT
    }

    fn points(&self, _ctx: &Ctx) -> Result<Vec<Point>, String> {
        let mut plan = Vec::new();
        for series in ["soup", "spheres"] {
            for e in 1..=6 {
                let m = 10u64.pow(e);
                plan.push(Point {
                    series: series.to_string(),
                    x: m as f64,
                    spec: format!("{series}:{m}"),
                    workload: square(64, 1, Mode::Cast),
                });
            }
        }
        // The constant-hit-rate family: finer tessellations of one sphere, whose outline
        // (and so the share of camera rays that hit) hardly moves as M grows.
        for level in ICOSPHERE_LEVELS {
            plan.push(Point {
                series: "icosphere".into(),
                x: (20u64 << (2 * level)) as f64,
                spec: format!("icosphere:{level}"),
                workload: square(64, 1, Mode::Cast),
            });
        }
        Ok(plan)
    }

    /// The memory of primitives plus structure, where the charts mark the caches.
    fn record(&self, _state: &mut (), seen: &Observed, point: &mut ScalingPoint) {
        point.memory_bytes = Some(seen.memory_bytes);
    }

    /// Render time and the extra charts per series, as every scaling experiment, each with
    /// the `x` where the data outgrow each cache marked ([`cache_marks`]).
    fn charts(&self, results: &Results) -> Vec<Chart> {
        let mut out = Vec::new();
        for (series, backends) in series_of(results, ABOUT.name) {
            let marks = cache_marks(results, &series).unwrap_or_default();
            let charts = fit_chart(
                results,
                ABOUT.name,
                &series,
                &backends,
                ABOUT.x_label,
                "seconds",
            )
            .into_iter()
            .chain(self.extra_charts(results, &series, &backends));
            out.extend(charts.map(|mut c| {
                if let Plot::LogLog(s) = c.plot {
                    c.plot = Plot::Marked(s, marks.clone());
                }
                c
            }));
        }
        out
    }

    /// The hit fraction of every point, whether each series kept it constant, and what the
    /// charts' cache marks are.
    fn write(&self, results: &Results, s: &mut String) {
        write_hits(results, s);
    }

    /// Tests per ray against M, and the speed-up over the oracle where it ran.
    fn extra_charts(
        &self,
        results: &Results,
        series_name: &str,
        backends: &BTreeSet<String>,
    ) -> Vec<Chart> {
        let name = ABOUT.name;
        let mut out: Vec<Chart> = fit_chart(
            results,
            name,
            series_name,
            backends,
            ABOUT.x_label,
            "tests_per_ray",
        )
        .into_iter()
        .collect();
        let oracle = raybench_registry::name_with(raybench_registry::Roles::ORACLE);
        if !backends.contains(oracle) {
            return out;
        }
        let reference: BTreeMap<u64, f64> = points_of(results, name, series_name)
            .filter(|p| p.backend == oracle)
            .map(|p| (p.x as u64, p.seconds))
            .collect();
        let series: Vec<Series> = backends
            .iter()
            .filter(|b| *b != oracle)
            .map(|b| Series {
                label: b.clone(),
                points: points_of(results, name, series_name)
                    .filter(|p| &p.backend == b)
                    .filter_map(|p| {
                        reference
                            .get(&(p.x as u64))
                            .map(|n| (p.x, n / p.seconds.max(1e-12)))
                    })
                    .collect(),
                fit: None,
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        if !series.is_empty() {
            out.push(Chart {
                title: format!("Speed-up over {oracle} against primitives: {series_name}"),
                stem: format!("speedup-{series_name}"),
                x_label: ABOUT.x_label.into(),
                y_label: format!("speed-up ({oracle}'s time / the backend's)"),
                plot: Plot::LogLog(series),
            });
        }
        out
    }
}

/// Each series' hit fraction per `M` ([`Results::hit_fractions`]), the series without
/// any left out.
fn hits_of(results: &Results) -> Vec<(String, HitFractions)> {
    series_of(results, ABOUT.name)
        .into_keys()
        .map(|series| {
            let hits = results.hit_fractions(ABOUT.name, &series);
            (series, hits)
        })
        .filter(|(_, hits)| !hits.0.is_empty())
        .collect()
}

/// The section with the hit fractions (where the points recorded them: files written
/// before they were have none) and the note on the cache marks; nothing when the experiment
/// did not run.
fn write_hits(results: &Results, s: &mut String) {
    if series_of(results, ABOUT.name).is_empty() {
        return;
    }
    let hits = hits_of(results);
    section(
        s,
        "Primitives: hit fractions and cache sizes",
        &format!(
            "A series whose hit fraction changes with M confounds its fit: a ray that hits \
             costs more than one that misses. `soup:M` (triangles shrinking as M^(-1/3)) and \
             `spheres:M` cover more of the image as M grows; `icosphere:L`, finer \
             tessellations of one sphere, keeps its outline. Constant: a spread of at most \
             {CONSTANT_HITS_PP} percentage point over the series."
        ),
    );
    if hits.is_empty() {
        let _ = writeln!(
            s,
            "No point recorded its hit fraction (a file written before they were).\n"
        );
    } else {
        let _ = writeln!(
            s,
            "| series | M: camera rays that hit | spread | constant |"
        );
        let _ = writeln!(s, "|---|---|---:|---|");
    }
    for (series, points) in &hits {
        let cells: Vec<String> = points
            .0
            .iter()
            .map(|(m, h)| format!("{}: {:.1}%", m, h * 100.0))
            .collect();
        let spread = points.spread_pp();
        let constant = match points.constant() {
            None => "-",
            Some(true) => "yes",
            Some(false) => "**no**",
        };
        let _ = writeln!(
            s,
            "| {series} | {} | {spread:.1} pp | {constant} |",
            cells.join(", ")
        );
    }
    if !hits.is_empty() {
        let _ = writeln!(s);
    }
    let caches = series_of(results, ABOUT.name)
        .into_keys()
        .find_map(|series| caches_of(results, &series));
    let _ = match caches {
        Some(c) => writeln!(
            s,
            "The charts mark (dotted, labelled) the M at which the memory of the primitives \
             plus the structure of the first backend to outgrow it reaches each cache of the \
             machine ({}), interpolated between the measured points on log-log axes; a cache \
             crossed below the smallest M or above the largest has no mark.\n",
            c.describe()
        ),
        None => writeln!(
            s,
            "The cache sizes of the machine are not known (the OS did not report them, or the \
             file predates them): the charts mark no cache.\n"
        ),
    };
}

/// The caches of the machine that measured `series` (the shard of its first point).
fn caches_of(results: &Results, series: &str) -> Option<Caches> {
    let p = points_of(results, ABOUT.name, series).next()?;
    results.shards.get(p.shard)?.machine.caches
}

/// The `x` at which `memory` (points `(x, bytes)`, ascending in `x`) reaches `size`:
/// interpolated on log-log axes between the last point below `size` and the next one;
/// `None` when no two consecutive points bracket it.
fn crossing(memory: &[(f64, u64)], size: u64) -> Option<f64> {
    let size = size as f64;
    memory.windows(2).find_map(|w| {
        let ((x0, m0), (x1, m1)) = ((w[0].0, w[0].1 as f64), (w[1].0, w[1].1 as f64));
        if !(m0 < size && size <= m1 && x0 > 0.0 && x1 > x0 && m0 > 0.0) {
            return None;
        }
        let f = (size / m0).ln() / (m1 / m0).ln();
        Some(x0 * (x1 / x0).powf(f))
    })
}

/// The cache marks of `series`' charts: per known cache level, the smallest `M` at which
/// any backend's memory (primitives plus structure) reaches the cache's size ([`crossing`]).
/// `None` when the caches are not known.
fn cache_marks(results: &Results, series: &str) -> Option<Vec<XMark>> {
    let caches = caches_of(results, series)?;
    let mut memory: BTreeMap<&str, Vec<(f64, u64)>> = BTreeMap::new();
    for p in points_of(results, ABOUT.name, series) {
        if let Some(m) = p.memory_bytes {
            memory.entry(&p.backend).or_default().push((p.x, m));
        }
    }
    for points in memory.values_mut() {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    Some(
        caches
            .levels()
            .into_iter()
            .filter_map(|(name, size)| {
                let (backend, x) = memory
                    .iter()
                    .filter_map(|(b, points)| Some((*b, crossing(points, size)?)))
                    .min_by(|a, b| a.1.total_cmp(&b.1))?;
                Some(XMark {
                    x,
                    label: name.trim_end_matches('d').into(),
                    title: format!(
                        "{name} ({}): {backend}'s primitives and structure reach it at M = {x:.0}",
                        crate::fmt::bytes(size)
                    ),
                })
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::{Machine, Shard};

    /// The crossing is exact on a power law between the bracketing points, and absent
    /// outside the measured range.
    #[test]
    fn crossings_interpolate_on_log_log_axes() {
        // 100 bytes per primitive: linear.
        let memory = [(10.0, 1_000), (100.0, 10_000), (1000.0, 100_000)];
        assert_eq!(crossing(&memory, 10_000), Some(100.0));
        let x = crossing(&memory, 40_000).unwrap();
        assert!((x - 400.0).abs() < 1e-9, "{x}");
        // On M^2: memory 1e2, 1e4 bytes at M = 10, 100: 1e3 bytes at M = sqrt(1000).
        let x = crossing(&[(10.0, 100), (100.0, 10_000)], 1000).unwrap();
        assert!((x - 1000f64.sqrt()).abs() < 1e-9, "{x}");
        assert_eq!(crossing(&memory, 1_000), None);
        assert_eq!(crossing(&memory, 500), None);
        assert_eq!(crossing(&memory, 100_001), None);
        assert_eq!(crossing(&memory[..1], 500), None);
    }

    /// A point of the `icosphere` series (read from JSON, so that fields added later with
    /// defaults need no change here).
    fn point(backend: &str, x: f64, memory: u64, hits: f64) -> ScalingPoint {
        serde_json::from_value(serde_json::json!({
            "shard": 0,
            "experiment": ABOUT.name,
            "series": "icosphere",
            "backend": backend,
            "x": x,
            "seconds": 1e-3,
            "rays": 4096,
            "memory_bytes": memory,
            "hit_fraction": hits,
        }))
        .unwrap()
    }

    fn results(caches: Option<Caches>) -> Results {
        Results {
            shards: vec![Shard {
                index: 1,
                count: 1,
                machine: Machine {
                    caches,
                    ..Machine::default()
                },
                started: String::new(),
                wall_seconds: 0.0,
                command: String::new(),
                quick: false,
                load: None,
                ranked_by_device: false,
                others: None,
                cache: None,
                pinned: false,
                repeat: String::new(),
                min_sample: 0.0,
                plan: None,
            }],
            scaling: vec![
                point("tree", 1e3, 64 << 10, 0.300),
                point("tree", 1e4, 640 << 10, 0.304),
                point("tree", 1e5, 6400 << 10, 0.305),
                point("list", 1e3, 32 << 10, 0.300),
                point("list", 1e4, 320 << 10, 0.304),
            ],
            ..Results::default()
        }
    }

    /// Each cache level is marked where the first backend (the one with the most bytes)
    /// reaches it; a level outside the measured range is not; unknown caches mark nothing.
    #[test]
    fn caches_are_marked_where_the_first_backend_reaches_them() {
        let caches = Caches {
            l1d: Some(48 << 10),
            l2: Some(2 << 20),
            l3: Some(1 << 30),
        };
        let marks = cache_marks(&results(Some(caches)), "icosphere").unwrap();
        // Memory is linear in M here. L1d (48 KiB): tree holds 64 KiB already at M = 1000,
        // list's 32 KiB reach it at 1000 x 48 / 32; L2 (2 MiB): only tree's range holds it,
        // between 640 KiB at 10^4 and 6400 KiB at 10^5: 10^4 x 2048 / 640; L3: beyond.
        assert_eq!(marks.len(), 2, "{marks:?}");
        assert_eq!(
            (marks[0].label.as_str(), marks[1].label.as_str()),
            ("L1", "L2")
        );
        assert!((marks[0].x - 1500.0).abs() < 1e-6, "{marks:?}");
        assert!((marks[1].x - 32_000.0).abs() < 1e-6, "{marks:?}");
        assert!(
            marks[0].title.starts_with("L1d (48.0 KiB): list's"),
            "{marks:?}"
        );
        assert!(
            marks[1].title.starts_with("L2 (2.0 MiB): tree's"),
            "{marks:?}"
        );
        assert_eq!(cache_marks(&results(None), "icosphere"), None);
    }

    /// The hit fractions per M, their spread and the verdict on constancy; the note on the
    /// marks names the caches, or says they are unknown.
    #[test]
    fn writes_the_hit_fractions_and_the_cache_note() {
        let caches = Caches {
            l1d: Some(48 << 10),
            l2: None,
            l3: None,
        };
        let mut s = String::new();
        write_hits(&results(Some(caches)), &mut s);
        assert!(
            s.contains("| icosphere | 1000: 30.0%, 10000: 30.4%, 100000: 30.5% | 0.5 pp | yes |"),
            "{s}"
        );
        assert!(s.contains("each cache of the machine (L1d 48 KiB)"), "{s}");
        let mut r = results(None);
        r.scaling[2].hit_fraction = Some(0.4);
        let mut s = String::new();
        write_hits(&r, &mut s);
        assert!(s.contains("| 10.0 pp | **no** |"), "{s}");
        assert!(s.contains("the charts mark no cache"), "{s}");
        // A file without hit fractions: said so, and the note on the caches still.
        for p in &mut r.scaling {
            p.hit_fraction = None;
        }
        let mut s = String::new();
        write_hits(&r, &mut s);
        assert!(
            s.contains("No point recorded its hit fraction") && !s.contains("| series |"),
            "{s}"
        );
        assert!(s.contains("the charts mark no cache"), "{s}");
        let mut s = String::new();
        write_hits(&Results::default(), &mut s);
        assert!(s.is_empty());
    }
}
