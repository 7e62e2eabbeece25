//! The report's experiments: the main matrix ([`matrix::Matrix`]) and the scaling
//! experiments, each one type in its own file that plans its units, runs them, and draws
//! and writes its part of the report. The run ([`super::run`]) and `REPORT.md`
//! ([`super::markdown`]) go through [`ALL`] and never test an experiment's name.
//!
//! A scaling experiment implements [`Scaling`] (its points, and what it adds to the shared
//! run, charts and text); [`Experiment`] then comes with it.

mod bezier;
mod empty_scene;
mod fixed_kernel;
mod heightfield;
mod instancing;
pub(crate) mod matrix;
mod motion;
mod pixels;
mod presets;
mod primitives;
mod quality;
mod spp;

pub(crate) use crate::charts::{Chart, Plot};
use crate::charts::{PowerLaw, Series};
use crate::ctx::{Ctx, Loaded, Workload, memory_bytes, skip};
use crate::results::{Results, ScalingPoint};
use anyhow::Result;
use raybench_core::{Mode, RaySet, Scene};
use raybench_registry::Backend;
use raybench_registry::measure::Measured;
use raybench_registry::measure::prepare;
use raybench_registry::progress::Progress;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;

/// Every experiment in the order it runs and is written: the matrix, then [`SCALING`].
pub(crate) const ALL: [&dyn Experiment; 9] = [
    &matrix::Matrix,
    SCALING[0],
    SCALING[1],
    SCALING[2],
    SCALING[3],
    SCALING[4],
    SCALING[5],
    SCALING[6],
    SCALING[7],
];

/// The scaling experiments, in the order they run (`--experiments` names them).
pub(crate) const SCALING: [&dyn Experiment; 8] = [
    &primitives::Primitives,
    &pixels::PIXELS,
    &spp::SPP,
    &heightfield::Heightfield,
    &bezier::Bezier,
    &presets::Presets,
    &instancing::Instancing,
    &motion::Motion,
];

/// A unit of an experiment ready to run, and how many progress steps it takes.
pub(crate) struct Planned {
    /// Steps of the progress bar (one per backend and workload or point).
    pub steps: usize,
    /// Its loaded scene (the matrix's units).
    pub scene: Option<Arc<Scene>>,
}

/// The plan of an experiment's unit that loads what it needs when it runs: `steps`
/// progress steps, or (`Err`) why it cannot run, which is recorded in `results` as a skip.
fn planned(results: &mut Results, unit: &str, steps: Result<usize, String>) -> Option<Planned> {
    match steps {
        Ok(steps) => Some(Planned { steps, scene: None }),
        Err(why) => {
            skip(results, "experiment", unit, "skipped", why);
            None
        }
    }
}

/// One part of the report: it splits into units (shards run whole units), plans and runs
/// them into [`Results`], and draws and writes its part from [`Results`] alone (so that a
/// merge of shards gives the same report as one run).
pub(crate) trait Experiment: Sync {
    /// Its name: `experiment` in `results.json`, `--experiments`, skip records.
    fn name(&self) -> &'static str;

    /// Whether it is a scaling experiment (chosen by `--experiments`, left out by
    /// `--no-scaling`) rather than the main matrix.
    fn scaling(&self) -> bool {
        true
    }

    /// The units it splits into (the matrix: one per scene; a scaling experiment: one).
    fn units(&self, _ctx: &Ctx) -> Vec<String> {
        vec![self.name().to_string()]
    }

    /// Prepares `unit` (loading what it needs) and counts its steps; `None`, recorded in
    /// `results` as skipped, when it cannot run.
    ///
    /// # Errors
    /// A scene that fails to load for another reason than a missing asset.
    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>>;

    /// Runs a planned unit, adding its runs or points (and what it skipped) to `results`.
    ///
    /// # Errors
    /// A render that fails, or an image that cannot be written.
    fn run(
        &self,
        ctx: &Ctx,
        unit: Planned,
        progress: &Progress,
        results: &mut Results,
    ) -> Result<()>;

    /// Its charts, from `results`.
    fn charts(&self, results: &Results) -> Vec<Chart>;

    /// Writes its sections of `REPORT.md` from `results` (nothing when it did not run).
    fn write(&self, results: &Results, s: &mut String);

    /// Its part of the sentence that introduces the table of scaling fits (what `x` is),
    /// if its fits belong there.
    fn axis(&self) -> Option<&'static str> {
        None
    }
}

/// One point of a scaling experiment's plan.
pub(crate) struct Point {
    /// The series it belongs to (`soup`, `direct`, ...).
    pub series: String,
    /// The varied quantity.
    pub x: f64,
    /// The scene spec rendered.
    pub spec: String,
    /// The workload.
    pub workload: Workload,
}

/// A measured point as a scaling experiment sees it, for [`Scaling::record`].
pub(crate) struct Observed<'a> {
    /// The point.
    pub point: &'a Point,
    /// The warm-up's ids, depths and colours.
    pub warm: &'a Measured,
    /// Seconds to load or generate the scene.
    pub load_seconds: f64,
    /// Seconds to build the backend's structure.
    pub build_seconds: f64,
    /// Bytes of the scene's primitives plus the backend's structure.
    pub memory_bytes: u64,
}

/// What names a scaling experiment and its axis: a const of each experiment, which
/// [`Scaling::about`] returns.
pub(crate) struct About {
    /// Its name: `experiment` in `results.json`, `--experiments`, skip records.
    pub name: &'static str,
    /// The title of its `x` axis, in plain words (`primitives in the scene`); also the
    /// charts' titles use it.
    pub x_label: &'static str,
    /// What its fits' `x` is, for the sentence before the fits table (`None`: its fits are
    /// not introduced there).
    pub axis: Option<&'static str>,
}

/// A scaling experiment: points of `(series, x)` measured with some backends, fitted on
/// log-log axes. What it shares with the others (loading each spec once, skipping
/// brute-force backends over budget, measuring, recording, the fits' charts) is written
/// once here.
pub(crate) trait Scaling: Sync {
    /// State carried from point to point (the `bezier` experiment's reference image).
    type State: Default;

    /// Its name and axes.
    fn about(&self) -> &About;

    /// Its points, in the order they run (points of one spec together: each spec is
    /// loaded once); `Err`: why it cannot run at all.
    ///
    /// # Errors
    /// When the built-in scene it needs has no `[benchmark]` table naming it.
    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String>;

    /// The backends that run its points.
    fn backends(&self, chosen: &[&'static Backend]) -> Vec<&'static Backend> {
        chosen.to_vec()
    }

    /// Loads a point's scene spec (inner `Err`: why it is skipped).
    ///
    /// # Errors
    /// As [`Ctx::load`].
    fn load(&self, ctx: &Ctx, spec: &str) -> Result<Loaded> {
        ctx.load(spec)
    }

    /// Adds what this experiment records beyond time, rays and tests to a point.
    fn record(&self, _state: &mut Self::State, _seen: &Observed, _point: &mut ScalingPoint) {}

    /// Its charts beyond render time against `x` per series (tests per ray, speed-ups).
    fn extra_charts(
        &self,
        _results: &Results,
        _series: &str,
        _backends: &BTreeSet<String>,
    ) -> Vec<Chart> {
        Vec::new()
    }

    /// Its charts: by default render time against `x`, one chart per series, then
    /// [`Self::extra_charts`].
    fn charts(&self, results: &Results) -> Vec<Chart> {
        let mut out = Vec::new();
        let About { name, x_label, .. } = *self.about();
        for (series, backends) in series_of(results, name) {
            out.extend(fit_chart(
                results, name, &series, &backends, x_label, "seconds",
            ));
            out.extend(self.extra_charts(results, &series, &backends));
        }
        out
    }

    /// Writes its own section of `REPORT.md` (its fits are in the shared table).
    fn write(&self, _results: &Results, _s: &mut String) {}
}

impl<T: Scaling> Experiment for T {
    fn name(&self) -> &'static str {
        self.about().name
    }

    fn plan(&self, ctx: &Ctx, unit: &str, results: &mut Results) -> Result<Option<Planned>> {
        let steps = self
            .points(ctx)
            .map(|points| points.len() * self.backends(ctx.chosen).len());
        Ok(planned(results, unit, steps))
    }

    fn run(&self, ctx: &Ctx, _: Planned, progress: &Progress, results: &mut Results) -> Result<()> {
        let name = self.about().name;
        let (points, skipped) = run_scaling(self, ctx, progress)?;
        if !skipped.is_empty() {
            let status = if points.is_empty() {
                "skipped"
            } else {
                "partial"
            };
            // Each reason once (the loader's error names the scene and the file; the
            // tessellations of the Bezier teapot share one).
            let mut reasons: Vec<&str> = Vec::new();
            for (_, why) in &skipped {
                if !reasons.contains(&why.as_str()) {
                    reasons.push(why);
                }
            }
            let reason = reasons.join("; ");
            skip(results, "experiment", name, status, reason);
        }
        results.scaling.extend(points);
        Ok(())
    }

    fn charts(&self, results: &Results) -> Vec<Chart> {
        Scaling::charts(self, results)
    }

    fn write(&self, results: &Results, s: &mut String) {
        Scaling::write(self, results, s);
    }

    fn axis(&self) -> Option<&'static str> {
        self.about().axis
    }
}

/// A 64 x 64 (or `width`-wide, square) camera-ray workload of `spp` samples.
fn square(width: u32, spp: u32, mode: Mode) -> Workload {
    Workload {
        mode,
        rays: RaySet::Primary,
        width,
        height: width,
        spp,
        replay: false,
    }
}

/// The built-in scene whose `[benchmark]` table names experiment `name`, or why there is
/// none.
fn scene_for(name: &str) -> Result<&'static str, String> {
    raybench_scene::for_experiment(name)
        .map(|b| b.name)
        .ok_or_else(|| {
            format!("no built-in scene names experiment `{name}` in its [benchmark] table")
        })
}

/// A scaling experiment over the built-in scene whose `[benchmark]` table names it: its one
/// series, a point per value of the quick or the full run, at the `(x, workload)` that `at`
/// makes of the value. What `pixels` and `spp` are, each a const of this type.
pub(crate) struct SceneSweep {
    /// Its name and axes.
    pub about: About,
    /// The values of the quick run.
    pub quick: &'static [u32],
    /// The values of the full run.
    pub full: &'static [u32],
    /// A value's `x` and workload.
    pub at: fn(u32) -> (f64, Workload),
}

impl Scaling for SceneSweep {
    type State = ();

    fn about(&self) -> &About {
        &self.about
    }

    fn points(&self, ctx: &Ctx) -> Result<Vec<Point>, String> {
        let scene = scene_for(self.about.name)?;
        let values = if ctx.opts.quick {
            self.quick
        } else {
            self.full
        };
        Ok(values
            .iter()
            .map(|&v| {
                let (x, workload) = (self.at)(v);
                Point {
                    series: scene.into(),
                    x,
                    spec: scene.into(),
                    workload,
                }
            })
            .collect())
    }
}

/// The baseline backend alone: for the experiments that compare two representations of
/// one surface, not structures.
fn baseline_only() -> Vec<&'static Backend> {
    raybench_registry::with_role(raybench_registry::Roles::BASELINE)
        .into_iter()
        .collect()
}

/// A scene spec that could not be loaded, and why.
type SkippedScene = (String, String);

/// The points of experiment `e`, and the scenes skipped (each once, with the reason).
fn run_scaling<E: Scaling>(
    e: &E,
    ctx: &Ctx,
    progress: &Progress,
) -> Result<(Vec<ScalingPoint>, Vec<SkippedScene>)> {
    let experiment = e.about().name;
    let mut points = Vec::new();
    let mut skipped: Vec<SkippedScene> = Vec::new();
    let mut loaded: Option<(String, Arc<Scene>, f64)> = None;
    let mut state = E::State::default();
    let backends = e.backends(ctx.chosen);
    let plan = e.points(ctx).unwrap_or_default();
    for point in &plan {
        let spec = &point.spec;
        let w = point.workload;
        let (scene, load_seconds) = match &loaded {
            Some((s, scene, secs)) if s == spec => (Arc::clone(scene), *secs),
            _ => {
                // Free the previous scene first: the largest terrains take gigabytes.
                loaded = None;
                if skipped.iter().any(|(s, _)| s == spec) {
                    progress.remove(backends.len());
                    continue;
                }
                let start = Instant::now();
                progress.begin(format!("scaling {experiment}: load {spec}"));
                match e.load(ctx, spec)? {
                    Ok(scene) => {
                        let secs = start.elapsed().as_secs_f64();
                        loaded = Some((spec.clone(), Arc::clone(&scene), secs));
                        (scene, secs)
                    }
                    Err(reason) => {
                        skipped.push((spec.clone(), reason));
                        progress.remove(backends.len());
                        continue;
                    }
                }
            }
        };
        for b in &backends {
            if b.is(raybench_registry::Roles::BRUTE_FORCE)
                && !ctx.naive_fits(&w, scene.geometry.total_len())
            {
                progress.remove(1);
                continue;
            }
            progress.begin(format!("scaling {experiment} {spec} {}: build", b.name));
            let Ok(raybench_registry::measure::Prepared {
                renderer: r, build, ..
            }) = prepare(b, &scene)
            else {
                progress.step(&format!(
                    "scaling {experiment} {spec} {}: unavailable",
                    b.name
                ));
                continue;
            };
            if let Err(why) = r.supports_mode(w.mode) {
                progress.step(&format!("scaling {experiment} {spec} {}: {why}", b.name));
                continue;
            }
            let x = point.x;
            progress.begin(format!("scaling {experiment} {spec} x={x} {}", b.name));
            let m = ctx.measure(r.as_ref(), &w, None)?;
            let mut p = m.point(r.as_ref(), experiment, point.series.clone(), b.name, x);
            let seen = Observed {
                point,
                warm: &m.warm,
                load_seconds,
                build_seconds: build,
                memory_bytes: memory_bytes(&scene, r.as_ref()),
            };
            e.record(&mut state, &seen, &mut p);
            points.push(p);
            progress.step(&format!(
                "scaling {experiment} {spec} x={x} {}: {:.4} s",
                b.name, m.timing.median
            ));
        }
    }
    Ok((points, skipped))
}

/// The series of experiment `name` in `results`, each with the backends that ran it.
fn series_of(results: &Results, name: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut groups: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for p in results.scaling.iter().filter(|p| p.experiment == name) {
        groups
            .entry(p.series.clone())
            .or_default()
            .insert(p.backend.clone());
    }
    groups
}

/// The points of one series of an experiment.
fn points_of<'r>(
    results: &'r Results,
    experiment: &'r str,
    series: &'r str,
) -> impl Iterator<Item = &'r ScalingPoint> {
    results
        .scaling
        .iter()
        .filter(move |p| p.experiment == experiment && p.series == series)
}

/// The fitted power law of `quantity` for one series and backend, when its fit has an
/// intercept (files written before it was added have none until merged anew).
fn power_law(
    results: &Results,
    experiment: &str,
    series: &str,
    backend: &str,
    quantity: &str,
) -> Option<PowerLaw> {
    let f = results.fit_of(experiment, series, backend, quantity)?;
    Some(PowerLaw {
        coefficient: 10f64.powf(f.intercept?),
        exponent: f.slope,
    })
}

/// The chart of `quantity` (`seconds` or `tests_per_ray`) against `x` for one series, each
/// backend a line with its fitted power law drawn dashed and its slope in the legend;
/// `None` when no point has it.
fn fit_chart(
    results: &Results,
    experiment: &str,
    series_name: &str,
    backends: &BTreeSet<String>,
    x_label: &str,
    quantity: &str,
) -> Option<Chart> {
    let (what, y_label) = if quantity == "seconds" {
        ("Render time", "render time (s)")
    } else {
        ("Tests per ray", "ray/primitive tests per ray")
    };
    let series: Vec<Series> = backends
        .iter()
        .map(|b| {
            let mut points: Vec<(f64, f64)> = points_of(results, experiment, series_name)
                .filter(|p| &p.backend == b)
                .filter_map(|p| match quantity {
                    "seconds" => Some((p.x, p.seconds)),
                    _ => p.tests_per_ray.map(|t| (p.x, t)),
                })
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: b.clone(),
                points,
                fit: power_law(results, experiment, series_name, b, quantity),
            }
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    (!series.is_empty()).then(|| Chart {
        title: format!("{what} against {x_label}: {series_name}"),
        stem: format!("scaling-{experiment}-{series_name}-{quantity}"),
        x_label: x_label.into(),
        y_label: y_label.into(),
        plot: Plot::LogLog(series),
    })
}

/// The sentence before the fits table, from every scaling experiment's [`Experiment::axis`].
pub(crate) fn fits_intro() -> String {
    let axes: Vec<&str> = SCALING.iter().filter_map(|e| e.axis()).collect();
    let joined = match axes.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        Some((last, _)) => (*last).to_string(),
        None => String::new(),
    };
    format!(
        "Log-log fits `y ~ x^slope` of render time (and tests per ray) against {joined}. \
         The claims under test: naive's time grows linearly with M (slope about 1), an \
         acceleration structure's barely (slope near 0, logarithmic in theory); time grows \
         linearly with N^2 and with K for every backend.\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ctx::Options;

    fn ctx_with<R>(quick: bool, f: impl FnOnce(&Ctx) -> R) -> R {
        let opts = Options {
            quick,
            scenes: None,
            backends: None,
            modes: None,
            out: std::env::temp_dir(),
            shard: (1, 1),
            size: None,
            repeat: None,
            min_sample: None,
            scaling: true,
            experiments: None,
            ray_sets: None,
            ao_rays: raybench_core::ray_sets::DEFAULT_AO_RAYS,
            assets: std::env::temp_dir(),
            threads: 1,
            command: String::new(),
            baseline: None,
            rays_file: None,
            device_time: false,
            pin: false,
        };
        let chosen: Vec<&'static Backend> = raybench_registry::BACKENDS.iter().collect();
        let ctx = Ctx {
            opts: &opts,
            replay: None,
            chosen: &chosen,
            modes: &Mode::ALL,
            size: 64,
            repeat: 1,
            policy: crate::rounds::Policy {
                repeat: crate::rounds::Repeat::Fixed(1),
                min_sample: 0.0,
                budget: 0.0,
            },
            budget: 0.0,
        };
        f(&ctx)
    }

    /// Every scaling experiment finds what it needs (its scene, by the scenes' `[benchmark]`
    /// tables) and plans points; the names are unique and the matrix comes first.
    #[test]
    fn every_experiment_plans() {
        assert!(!ALL[0].scaling() && ALL[1..].iter().all(|e| e.scaling()));
        let names: BTreeSet<&str> = ALL.iter().map(|e| e.name()).collect();
        assert_eq!(names.len(), ALL.len());
        for quick in [true, false] {
            ctx_with(quick, |ctx| {
                for e in SCALING {
                    let mut results = Results::default();
                    let planned = e.plan(ctx, e.name(), &mut results).unwrap();
                    assert!(
                        planned.is_some_and(|p| p.steps > 0) && results.skipped.is_empty(),
                        "{}: {:?}",
                        e.name(),
                        results.skipped
                    );
                }
                assert!(!ALL[0].units(ctx).is_empty());
            });
        }
    }

    /// A built-in scene's `experiments` must name an experiment that exists (a typo would
    /// leave the scene unused and the experiment skipped).
    #[test]
    fn scenes_name_known_experiments() {
        for b in raybench_scene::BUILTIN_SCENES {
            for e in b.benchmark.experiments {
                assert!(
                    SCALING.iter().any(|s| s.name() == *e),
                    "bench-scenes/{}.toml: [benchmark] experiments: no experiment `{e}` \
                     (known: {:?})",
                    b.name,
                    crate::experiments()
                );
            }
        }
    }

    /// The sentence before the fits table names every experiment's axis, joined as prose.
    #[test]
    fn the_fits_intro_joins_the_axes() {
        let intro = fits_intro();
        assert!(intro.starts_with("Log-log fits `y ~ x^slope` of render time"));
        assert!(intro.contains(
            "64 x 64 camera rays), the pixel count N^2 (bunny), the samples per pixel K \
             (Cornell box, path tracing, 64 x 64) and the height-field cell count N^2"
        ));
    }
}
