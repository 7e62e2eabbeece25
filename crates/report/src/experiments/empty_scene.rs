//! The frame pipeline's fixed cost per camera ray, measured on a scene without primitives:
//! one unit of the matrix ([`UNIT`]) that times every chosen backend's ray-casting frame and
//! the same camera rays traced as a batch, where every ray misses (`results.json`'s
//! `empty_scene`), and the table of the matrix's summary that shows it.

use crate::ctx::{Ctx, skip};
use crate::fmt::{noisy_mark, repetitions};
use crate::results::{EmptyScene, Results};
use anyhow::Result;
use raybench_core::{Mode, RaySet, SceneBuilder};
use raybench_registry::TimedRenderer;
use raybench_registry::measure::{Prepared, RayBatch, prepare, primary_rays};
use raybench_registry::progress::Progress;
use std::fmt::Write as _;
use std::sync::Arc;

/// The matrix's unit that measures the empty scene (not a scene spec: parentheses are in
/// no built-in name and no generator's).
pub(crate) const UNIT: &str = "(empty scene)";

/// Whether the matrix measures the empty scene: when it runs ray casting's camera rays
/// (their frames are what the fixed cost is subtracted from).
pub(crate) fn wanted(ctx: &Ctx) -> bool {
    let primary = match &ctx.opts.ray_sets {
        Some(sets) => sets.contains(&RaySet::Primary),
        None => ctx.replay.is_none(),
    };
    ctx.modes.contains(&Mode::Cast) && primary
}

/// Every chosen backend on a scene without primitives at the matrix's frame size (so that
/// the per-frame costs, the threads' start among them, are spread over as many rays as in
/// the matrix): the whole frame of camera rays and the same rays as a closest-hit batch,
/// each timed in rounds over the backends ([`Ctx::measure_all`]). A backend that cannot
/// run it is recorded as skipped.
///
/// # Errors
/// A render that fails.
pub(crate) fn run(ctx: &Ctx, progress: &Progress, out: &mut Results) -> Result<()> {
    let scene = Arc::new(SceneBuilder::new("empty").build());
    let w = super::square(ctx.size, 1, Mode::Cast);
    let mut prepared: Vec<(&str, Prepared)> = Vec::new();
    for b in ctx.chosen {
        progress.begin(format!("{UNIT} {}: build", b.name));
        match prepare(b, &scene).and_then(|p| p.renderer.supports_mode(w.mode).map(|()| p)) {
            Ok(p) => prepared.push((b.name, p)),
            Err(why) => {
                progress.step(&format!("{UNIT} {}: {why}", b.name));
                skip(
                    out,
                    "workload",
                    &format!("{UNIT} {}", b.name),
                    "skipped",
                    why,
                );
            }
        }
    }
    if prepared.is_empty() {
        return Ok(());
    }
    let renderers: Vec<&dyn TimedRenderer> =
        prepared.iter().map(|(_, p)| p.renderer.as_ref()).collect();
    let settings = w.settings();
    progress.begin(format!(
        "{UNIT}: frames, {} backends in rounds",
        renderers.len()
    ));
    let frames = ctx.measure_all(&renderers, &settings, &[(None, None)])?;
    progress.begin(format!(
        "{UNIT}: batches, {} backends in rounds",
        renderers.len()
    ));
    let batch = RayBatch {
        rays: primary_rays(&scene, &settings)?,
        any_hit: false,
        facing_away: 0,
    };
    let traced = ctx.measure_all(&renderers, &settings, &[(None, Some(batch))])?;
    for (((name, _), (frame, _)), (trace, _)) in prepared.iter().zip(frames).zip(traced) {
        let e = EmptyScene {
            shard: 0,
            backend: (*name).into(),
            threads: ctx.opts.threads,
            width: w.width,
            height: w.height,
            rays: frame.warm.rays,
            frame: frame.timing,
            trace: Some(trace.timing),
        };
        progress.step(&format!(
            "{UNIT} {name}: {:.1} ns per camera ray",
            e.frame_ns_per_ray()
        ));
        out.empty_scene.push(e);
    }
    Ok(())
}

/// The table of the empty scene's costs per camera ray, after the matrix's summary;
/// nothing when it was not measured.
pub(crate) fn write(results: &Results, s: &mut String) {
    let rows = &results.empty_scene;
    let Some(first) = rows.first() else {
        return;
    };
    let _ = writeln!(
        s,
        "The pipeline's fixed cost on an empty scene (no primitives: all {} x {} camera rays \
         miss), per camera ray: the whole frame (ray generation, shading a miss, the image) \
         and the same rays traced as a batch (the traversal's fixed cost). Subtract them from \
         a scene's figures to see what its geometry costs.\n",
        first.width, first.height
    );
    let _ = writeln!(
        s,
        "| backend | threads | frame ns/ray [interval] | trace ns/ray [interval] | repetitions: frame, trace |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for e in rows {
        let per_ray = |t: &crate::results::Timing| {
            let rays = e.rays.max(1) as f64;
            let interval = t.interval.map_or("[?]".into(), |[lo, hi]| {
                format!("[{:.1}-{:.1}]", lo / rays * 1e9, hi / rays * 1e9)
            });
            format!("{:.1} {interval}{}", t.median / rays * 1e9, noisy_mark(t))
        };
        let (trace, trace_reps) = e
            .trace
            .as_ref()
            .map_or(("-".into(), "-".into()), |t| (per_ray(t), repetitions(t)));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {trace} | {}, {trace_reps} |",
            e.backend,
            e.threads,
            per_ray(&e.frame),
            repetitions(&e.frame),
        );
    }
    let _ = writeln!(s);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::Timing;

    fn timing(median: f64) -> Timing {
        Timing {
            interval: Some([median * 0.98, median * 1.02]),
            confidence: Some(0.95),
            ..Timing::of(vec![median; 6])
        }
    }

    /// The costs per ray are the medians over the rays, in nanoseconds, with their
    /// intervals; a missing batch is `-`.
    #[test]
    fn writes_nanoseconds_per_camera_ray() {
        let mut r = Results::default();
        let mut s = String::new();
        write(&r, &mut s);
        assert!(s.is_empty());
        r.empty_scene = vec![
            EmptyScene {
                shard: 0,
                backend: "tree".into(),
                threads: 2,
                width: 100,
                height: 100,
                rays: 10_000,
                frame: timing(2e-4),
                trace: Some(timing(5e-5)),
            },
            EmptyScene {
                shard: 0,
                backend: "list".into(),
                threads: 2,
                width: 100,
                height: 100,
                rays: 10_000,
                frame: timing(1e-4),
                trace: None,
            },
        ];
        assert_eq!(r.empty_scene[0].frame_ns_per_ray(), 20.0);
        assert_eq!(r.empty_scene[0].trace_ns_per_ray(), Some(5.0));
        write(&r, &mut s);
        assert!(s.contains("all 100 x 100 camera rays miss"), "{s}");
        let rows: Vec<&str> = s
            .lines()
            .filter(|l| l.starts_with("| tree") || l.starts_with("| list"))
            .collect();
        let reps = repetitions(&r.empty_scene[0].frame);
        assert_eq!(
            rows,
            [
                format!("| tree | 2 | 20.0 [19.6-20.4] | 5.0 [4.9-5.1] | {reps}, {reps} |"),
                format!("| list | 2 | 10.0 [9.8-10.2] | - | {reps}, - |"),
            ]
        );
    }
}
