//! Experiment `heightfield`: the direct height field (`heightfield:N`, one primitive walked
//! by its min-max quadtree) against the same terrain tessellated into triangles
//! (`terrain:N`), both in the baseline backend, for growing grids: load, build, memory and
//! render time.

use super::{About, Ctx, Observed, Point, Scaling, baseline_only, square};
use crate::fmt::{bytes, opt, section};
use crate::results::{Results, ScalingPoint};
use raybench_core::Mode;
use raybench_registry::Backend;
use std::fmt::Write as _;

/// Experiment `heightfield`.
pub(super) struct Heightfield;

/// Its name and axes.
const ABOUT: About = About {
    name: "heightfield",
    x_label: "height-field cells (N²)",
    axis: Some("the height-field cell count N^2 (direct and tessellated, see below)"),
};

impl Scaling for Heightfield {
    type State = ();

    fn about(&self) -> &About {
        &ABOUT
    }

    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let sides: &[u32] = if ctx.opts.quick {
            &[256, 512, 1024]
        } else {
            &[256, 512, 1024, 2048, 4096]
        };
        let mut plan = Vec::new();
        for &n in sides {
            for (series, generator) in [("direct", "heightfield"), ("tessellated", "terrain")] {
                plan.push(Point {
                    series: series.into(),
                    x: f64::from(n) * f64::from(n),
                    spec: format!("{generator}:{n}"),
                    workload: square(256, 1, Mode::Cast),
                });
            }
        }
        Ok(plan)
    }

    /// The baseline alone (the comparison is of representations, not of structures).
    fn backends(&self, _chosen: &[&'static Backend]) -> Vec<&'static Backend> {
        baseline_only()
    }

    fn record(&self, _state: &mut (), seen: &Observed, point: &mut ScalingPoint) {
        point.load_seconds = Some(seen.load_seconds);
        point.build_seconds = Some(seen.build_seconds);
        point.memory_bytes = Some(seen.memory_bytes);
    }

    fn write(&self, results: &Results, s: &mut String) {
        let hf: Vec<_> = results
            .scaling
            .iter()
            .filter(|p| p.experiment == ABOUT.name)
            .collect();
        if !hf.is_empty() {
            section(
                s,
                "Height fields: direct against tessellated",
                &format!(
                    "The `terrain:N` heights as one height-field primitive intersected directly \
                     (min-max quadtree over the cells, `heightfield:N`) against the same terrain \
                     tessellated into 2 N^2 triangles (`terrain:N`), both in the `{}` backend; 256 \
                     x 256 camera rays. Both give the same hits and `t` bit for bit. Load: \
                     generating the heights and tessellating, or building the min-max levels; \
                     build: the BVH; memory: primitives plus structure; a height field counts as \
                     one primitive test per ray.",
                    raybench_registry::name_with(raybench_registry::Roles::BASELINE)
                ),
            );
            let _ = writeln!(
                s,
                "| cells | series | memory | load s | build s | render s | tests/ray |"
            );
            let _ = writeln!(s, "|---:|---|---:|---:|---:|---:|---:|");
            for p in hf {
                let _ = writeln!(
                    s,
                    "| {}^2 | {} | {} | {} | {} | {:.4} | {} |",
                    p.x.sqrt().round(),
                    p.series,
                    p.memory_bytes.map_or("-".into(), bytes),
                    opt(p.load_seconds, |v| format!("{v:.3}")),
                    opt(p.build_seconds, |v| format!("{v:.3}")),
                    p.seconds,
                    opt(p.tests_per_ray, |v| format!("{v:.1}"))
                );
            }
            let _ = writeln!(s);
        }
    }
}
