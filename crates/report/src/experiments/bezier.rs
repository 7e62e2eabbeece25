//! Experiment `bezier`: the Bezier patches of the built-in scene whose `[benchmark]` table
//! names it (the teapot) intersected directly, against their tessellations into `2 N^2`
//! triangles per patch, both in the baseline backend, with each tessellation's image
//! difference from the direct rendering.

use super::{
    About, Chart, Ctx, Observed, Plot, Point, Scaling, baseline_only, power_law, scene_for, square,
};
use crate::charts::Series;
use crate::ctx::{Loaded, skip_missing_asset};
use crate::fmt::{opt, section};
use crate::images::{self, Rgb8};
use crate::results::{ImageDifference, Results, ScalingPoint};
use anyhow::Result;
use raybench_core::{Mode, NO_HIT};
use raybench_registry::Backend;
use std::fmt::Write as _;

/// Experiment `bezier`.
pub(super) struct Bezier;

/// The direct rendering the tessellations are compared with: ids, depths and the image.
#[derive(Default)]
pub(super) struct Reference {
    ids: Vec<u32>,
    t: Vec<f32>,
    image: Option<Rgb8>,
}

/// The suffix of a spec that tessellates the experiment's scene: `NAME:tessellate=N`.
const TESSELLATE: &str = ":tessellate=";

/// Its name and axes.
const ABOUT: About = About {
    name: "bezier",
    x_label: "primitives (32 patches, or 2 N² triangles per patch)",
    axis: None,
};

impl Scaling for Bezier {
    type State = Reference;

    fn about(&self) -> &About {
        &ABOUT
    }

    /// The direct patches at x = their primitive count, then the tessellations at x = their
    /// triangle count (spec `NAME:tessellate=N`).
    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let scene = scene_for(ABOUT.name)?;
        let w = square(256, 1, Mode::Cast);
        let mut plan = vec![Point {
            series: "direct".into(),
            x: 32.0,
            spec: scene.into(),
            workload: w,
        }];
        let ns: &[u32] = if ctx.opts.quick {
            &[1, 2, 4, 8, 16]
        } else {
            &[1, 2, 4, 8, 16, 32]
        };
        for &n in ns {
            plan.push(Point {
                series: "tessellated".into(),
                x: f64::from(2 * n * n * 32),
                spec: format!("{scene}{TESSELLATE}{n}"),
                workload: w,
            });
        }
        Ok(plan)
    }

    /// The baseline alone (the comparison is of representations, not of structures).
    fn backends(&self, _chosen: &[&'static Backend]) -> Vec<&'static Backend> {
        baseline_only()
    }

    /// The built-in scene, and `NAME:tessellate=N`: the scene with its patches tessellated
    /// into `N x N` quads each.
    fn load(&self, ctx: &Ctx, spec: &str) -> Result<Loaded> {
        let Some((name, n)) = spec.split_once(TESSELLATE) else {
            return ctx.load(spec);
        };
        let source = raybench_scene::builtin(name)
            .map(|s| s.source)
            .unwrap_or_default()
            .replace(
                "kind = \"bezier\"",
                &format!("kind = \"bezier\"\ntessellate = {n}"),
            );
        skip_missing_asset(
            spec,
            raybench_scene::load_scene_str(&source, name, None, &ctx.opts.assets),
        )
    }

    /// Keeps the direct rendering as the reference, and compares a tessellated one with it
    /// (mean FLIP of the images; fractions of pixels whose patch differs, hit or miss
    /// included, and of pixels both hit whose depth differs by more than 1%). The
    /// tessellation of `x` triangles has `x / 32` triangles per patch, in patch order.
    fn record(&self, reference: &mut Reference, seen: &Observed, point: &mut ScalingPoint) {
        let w = &seen.point.workload;
        let m = seen.warm;
        let image = |c: &[raybench_core::Vec3]| Rgb8::from_linear(w.width, w.height, c);
        let color = m.color.as_deref().unwrap_or_default();
        if seen.point.series == "direct" {
            *reference = Reference {
                ids: m.ids.clone(),
                t: m.t.clone(),
                image: Some(image(color)),
            };
            return;
        }
        let Some(r_image) = &reference.image else {
            return;
        };
        let per_patch = (seen.point.x / 32.0).round().max(1.0) as u32;
        let (mean_flip, _) = images::flip(r_image, &image(color));
        let patch = |id: u32, per: u32| if id == NO_HIT { NO_HIT } else { id / per };
        let (mut patch_differs, mut depth_differs) = (0u64, 0u64);
        for i in 0..reference.ids.len() {
            let (a, b) = (patch(reference.ids[i], 1), patch(m.ids[i], per_patch));
            patch_differs += u64::from(a != b);
            depth_differs += u64::from(
                a != NO_HIT
                    && b != NO_HIT
                    && (reference.t[i] - m.t[i]).abs() > 0.01 * reference.t[i],
            );
        }
        let n = reference.ids.len().max(1) as f64;
        point.difference = Some(ImageDifference {
            mean_flip,
            patch_mismatch: patch_differs as f64 / n,
            depth_mismatch: depth_differs as f64 / n,
        });
    }

    /// Render time against primitives (the direct patches as one point at their count, 32,
    /// and as a level line across the triangle counts for comparison), and the
    /// tessellations' difference from the direct image against their triangle count (zero
    /// fractions are left off the log scale; the table has them).
    fn charts(&self, results: &Results) -> Vec<Chart> {
        let points = |series: &str| -> Vec<&ScalingPoint> {
            results
                .scaling
                .iter()
                .filter(|p| p.experiment == ABOUT.name && p.series == series)
                .collect()
        };
        let (direct, tess) = (points("direct"), points("tessellated"));
        let Some(d) = direct.first() else {
            return Vec::new();
        };
        if tess.is_empty() {
            return Vec::new();
        }
        let x_max = tess.iter().map(|p| p.x).fold(d.x, f64::max);
        let times = vec![
            Series {
                label: "tessellated (triangles)".into(),
                points: tess.iter().map(|p| (p.x, p.seconds)).collect(),
                fit: power_law(
                    results,
                    ABOUT.name,
                    "tessellated",
                    &tess[0].backend,
                    "seconds",
                ),
            },
            Series {
                label: "direct (32 patches; level line for comparison)".into(),
                points: vec![(d.x, d.seconds), (x_max, d.seconds)],
                fit: None,
            },
        ];
        let diff = |label: &str, f: fn(&ImageDifference) -> f64| Series {
            label: label.into(),
            points: tess
                .iter()
                .filter_map(|p| p.difference.as_ref().map(|q| (p.x, f(q))))
                .filter(|&(_, y)| y > 0.0)
                .collect(),
            fit: None,
        };
        let differences = vec![
            diff("mean FLIP", |q| q.mean_flip),
            diff("fraction of pixels: other patch or hit/miss", |q| {
                q.patch_mismatch
            }),
            diff("fraction of pixels: depth off by > 1%", |q| {
                q.depth_mismatch
            }),
        ]
        .into_iter()
        .filter(|s| !s.points.is_empty())
        .collect::<Vec<_>>();
        let mut out = vec![Chart {
            title: "Render time against primitives (Bezier teapot: direct against tessellated)"
                .to_string(),
            stem: "scaling-bezier-seconds".into(),
            x_label: ABOUT.x_label.into(),
            y_label: "render time (s)".into(),
            plot: Plot::LogLog(times),
        }];
        if !differences.is_empty() {
            out.push(Chart {
                title: "Difference from the direct image against triangles (Bezier teapot)"
                    .to_string(),
                stem: "scaling-bezier-difference".into(),
                x_label: "triangles (2 N² per patch × 32 patches)".into(),
                y_label: "difference (mean FLIP, or fraction of pixels)".into(),
                plot: Plot::LogLog(differences),
            });
        }
        out
    }

    fn write(&self, results: &Results, s: &mut String) {
        let bz: Vec<_> = results
            .scaling
            .iter()
            .filter(|p| p.experiment == ABOUT.name)
            .collect();
        if !bz.is_empty() {
            section(
                s,
                "Bezier patches: direct against tessellated",
                &format!(
                    "The Utah teapot's 32 bicubic patches (`teapot-bezier`) intersected directly \
                     (subdivision of the control-point boxes, then Newton iteration on (u, v, t)) \
                     against the same patches tessellated into N x N quads (2 N^2 triangles) each, \
                     vertices on the exact surface, both in the `{}` backend; 256 x 256 camera \
                     rays. Difference from the direct image: mean FLIP, the fraction of pixels \
                     whose patch differs (or one hits and the other misses), and the fraction hit \
                     in both whose depth differs by more than 1%.",
                    raybench_registry::name_with(raybench_registry::Roles::BASELINE)
                ),
            );
            let _ = writeln!(
                s,
                "| series | N | primitives | render s | mean FLIP | other patch | depth > 1% |"
            );
            let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
            for p in bz {
                let n = if p.series == "direct" {
                    "-".to_string()
                } else {
                    format!("{}", (p.x / 64.0).sqrt().round())
                };
                let d = p.difference;
                let _ = writeln!(
                    s,
                    "| {} | {n} | {} | {:.4} | {} | {} | {} |",
                    p.series,
                    p.x,
                    p.seconds,
                    opt(d.map(|d| d.mean_flip), |v| format!("{v:.4}")),
                    opt(d.map(|d| d.patch_mismatch), |v| format!(
                        "{:.3}%",
                        100.0 * v
                    )),
                    opt(d.map(|d| d.depth_mismatch), |v| format!(
                        "{:.3}%",
                        100.0 * v
                    )),
                );
            }
            let _ = writeln!(s);
        }
    }
}
