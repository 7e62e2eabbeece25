//! Experiment `primitives`: render time (and tests per ray) against the number of
//! primitives M of the `soup:M` and `spheres:M` generators, 64 x 64 camera rays; with the
//! speed-up of every backend over the oracle where it ran.

use super::{About, Chart, Ctx, Plot, Point, Scaling, fit_chart, points_of, square};
use crate::charts::Series;
use crate::results::Results;
use raybench_core::Mode;
use std::collections::{BTreeMap, BTreeSet};

/// Experiment `primitives`.
pub(super) struct Primitives;

/// Its name and axes.
const ABOUT: About = About {
    name: "primitives",
    x_label: "primitives in the scene",
    axis: Some(
        "the number of primitives M (`soup:M`, `spheres:M` generators, 64 x 64 camera \
             rays)",
    ),
};

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
        Ok(plan)
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
