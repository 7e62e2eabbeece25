//! The services every experiment calls: the run's options and what was made of them
//! ([`Ctx`]), workloads, loading with skips, the naive budget and measurement with
//! repetitions. Experiments call down into this module; it knows no experiment.

use crate::results::{Results, ScalingPoint, Skipped, Timing};
use crate::rounds;
use anyhow::Result;
use raybench_core::{Mode, NO_HIT, RaySet, RenderSettings, Scene};
use raybench_registry::interference::Interference;
use raybench_registry::measure::{Measured, RayBatch, measure};
use raybench_registry::{Backend, TimedRenderer};
use std::path::PathBuf;
use std::sync::Arc;

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// The small matrix (under 5 minutes on 2 cores; without `backends`, the GPU backends are
    /// left out on a software adapter).
    pub quick: bool,
    /// Scenes (default: the built-in scenes of the chosen matrix, by their `[benchmark]`
    /// tables).
    pub scenes: Option<Vec<String>>,
    /// Backends (default: every backend but the variants).
    pub backends: Option<Vec<String>>,
    /// Modes (default: all; `mip` and `composite` run only on scenes with volumes).
    pub modes: Option<Vec<Mode>>,
    /// Output folder.
    pub out: PathBuf,
    /// This run's shard `(i, n)`, 1-based.
    pub shard: (u32, u32),
    /// Image side for the main matrix (default 256 quick, 512 full).
    pub size: Option<u32>,
    /// Timed repetitions after the warm-up (default [`rounds::Repeat::Auto`]).
    pub repeat: Option<rounds::Repeat>,
    /// Seconds a timed sample lasts at least (default [`crate::MIN_SAMPLE_QUICK`] or
    /// [`crate::MIN_SAMPLE_FULL`]).
    pub min_sample: Option<f64>,
    /// Run the scaling experiments.
    pub scaling: bool,
    /// Which scaling experiments (default: all of [`experiments()`]).
    pub experiments: Option<Vec<String>>,
    /// The ray sets of the ray-casting workloads (default: every set, [`RaySet::ALL`]).
    pub ray_sets: Option<Vec<RaySet>>,
    /// Ambient-occlusion rays per primary hit of the `ao` workloads.
    pub ao_rays: u32,
    /// A ray file (`docs/rays-format.md`) every scene of the matrix also traces, as the
    /// ray-casting workload `cast-file` (alone unless `ray_sets` names sets too).
    pub rays_file: Option<PathBuf>,
    /// Assets folder.
    pub assets: PathBuf,
    /// Worker threads.
    pub threads: usize,
    /// The command line, for the record.
    pub command: String,
    /// An earlier report (folder or `results.json`) to compare with ([`baseline`]).
    pub baseline: Option<PathBuf>,
    /// Rank backends on another device by their device time rather than wall time.
    pub device_time: bool,
    /// Whether the worker threads are pinned to cores (recorded; the caller pins them).
    pub pin: bool,
}

/// Naive's estimated ray/primitive tests per workload above which the quick run leaves it
/// out (it is then not the reference: `bvh` is, itself checked against naive by the
/// tests): the budget `compare` and `info` keep to by default as well.
pub(crate) const NAIVE_BUDGET_QUICK: f64 = raybench_registry::BRUTE_FORCE_BUDGET_TESTS;
/// [`NAIVE_BUDGET_QUICK`] for the full run.
pub(crate) const NAIVE_BUDGET_FULL: f64 = 2.0e10;

/// The tolerance a backend outside the equivalence contract must meet: at least this
/// fraction of identical ids ...
pub const PEER_MIN_ID_MATCH: f64 = 0.999;
/// ... and at most this mean FLIP error.
pub const PEER_MAX_FLIP: f64 = 0.05;

/// One render setting of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Workload {
    pub(crate) mode: Mode,
    pub(crate) rays: RaySet,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) spp: u32,
    /// Traces the rays of the run's ray file ([`Options::rays_file`]) instead of `rays`.
    pub(crate) replay: bool,
}

impl Workload {
    pub(crate) fn settings(&self) -> RenderSettings {
        RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            mode: self.mode,
            seed: 0,
            max_depth: 5,
            count: false,
            ..RenderSettings::default()
        }
    }

    pub(crate) fn key(&self) -> String {
        format!("{}-{}", self.mode.name(), self.ray_set())
    }

    /// The name of its rays in `results.json`: the ray set's, or `file` for a replay.
    pub(crate) fn ray_set(&self) -> &'static str {
        if self.replay {
            "file"
        } else {
            self.rays.name()
        }
    }
}

/// The scenes the full matrix adds to the built-in ones, flattened: a flat scene of several
/// million triangles made from the shared meshes (`bunny-field`'s 12.6 million), whose tree
/// no cache holds, beside the instanced form of the same scene.
pub const FLAT_SCENES: [&str; 1] = ["flat:bunny-field"];

/// The built-in scenes of the quick matrix (`--quick`) or the full one, in listing order
/// (each scene's `[benchmark]` table says which); the full one ends with [`FLAT_SCENES`].
#[must_use]
pub fn matrix_scenes(quick: bool) -> Vec<&'static str> {
    let mut scenes: Vec<&'static str> = raybench_scene::matrix(quick).map(|b| b.name).collect();
    if !quick {
        scenes.extend(FLAT_SCENES);
    }
    scenes
}

/// The cameras a workload is measured from, each with its explicit rays (`None` for a
/// rendered frame): indices into the scene's cameras, `None` for the scene's camera.
pub(crate) type Views = [(Option<u32>, Option<RayBatch>)];

/// A loaded scene, or why it is skipped.
pub(crate) type Loaded = Result<Arc<Scene>, String>;

/// The outcome of loading `spec`: the scene; why it is skipped (a missing asset, or a scene
/// over the memory budget); or, for any other failure and for a missing asset under
/// `CI=true` (where every asset is installed), an error.
pub(crate) fn skip_missing_asset(
    spec: &str,
    loaded: Result<Scene, raybench_scene::LoadError>,
) -> Result<Loaded> {
    match loaded {
        Ok(s) => Ok(Ok(Arc::new(s))),
        Err(e) if e.is_missing_asset() && std::env::var("CI").as_deref() != Ok("true") => {
            Ok(Err(e.to_string()))
        }
        // A scene over this machine's memory budget (the largest scaling points) is skipped
        // with the reason, CI or not: the rest of the run still means something.
        Err(e) if e.is_over_budget() => Ok(Err(e.to_string())),
        Err(e) => Err(anyhow::Error::new(e).context(format!("cannot load scene {spec}"))),
    }
}

/// Records a skipped scene or experiment in `results` and says so once on stderr.
pub(crate) fn skip(results: &mut Results, kind: &str, name: &str, status: &str, reason: String) {
    eprintln!("skipped {kind} {name}: {reason}");
    results.skipped.push(Skipped {
        shard: 0,
        kind: kind.into(),
        name: name.into(),
        status: status.into(),
        reason,
    });
}

/// What every experiment of one run shares: the options and what was made of them.
pub(crate) struct Ctx<'a> {
    pub(crate) opts: &'a Options,
    /// The rays of [`Options::rays_file`], read once.
    pub(crate) replay: Option<RayBatch>,
    pub(crate) chosen: &'a [&'static Backend],
    pub(crate) modes: &'a [Mode],
    pub(crate) size: u32,
    /// The repetitions every workload gets at least (what the naive budget and the build
    /// repetitions count): [`rounds::Repeat::minimum`].
    pub(crate) repeat: u32,
    /// How the timed repetitions are taken.
    pub(crate) policy: rounds::Policy,
    pub(crate) budget: f64,
}

/// A backend's measurements of one workload.
pub(crate) struct Measurement {
    pub(crate) warm: Measured,
    pub(crate) timing: Timing,
    /// For a backend on another device: the timed repetitions' device time (phase `gpu`).
    pub(crate) device: Option<Timing>,
    /// Medians of the timed repetitions' phases.
    pub(crate) phases: raybench_core::Timings,
}

impl Ctx<'_> {
    /// The scene `name`, or (inner `Err`) why it is skipped: a missing asset, except under
    /// `CI=true`, where that is an error too.
    pub(crate) fn load(&self, name: &str) -> Result<Loaded> {
        skip_missing_asset(name, raybench_scene::load(name, &self.opts.assets))
    }

    /// Whether a brute-force backend stays within its budget on `w` over a scene of `prims`
    /// primitives.
    pub(crate) fn naive_fits(&self, w: &Workload, prims: usize) -> bool {
        let tests = match (&self.replay, w.replay) {
            (Some(batch), true) => {
                batch.rays.len() as f64 * prims as f64 * f64::from(self.repeat + 1)
            }
            _ => {
                raybench_registry::brute_force_tests(&w.settings(), w.rays, prims, self.repeat + 1)
            }
        };
        tests <= self.budget
    }

    /// Warm-up (counted, kept for the comparison) and timed repetitions of one renderer.
    pub(crate) fn measure(
        &self,
        r: &dyn TimedRenderer,
        w: &Workload,
        rays: Option<&RayBatch>,
    ) -> Result<Measurement> {
        let views = [(None, rays.cloned())];
        let mut all = self.measure_all(&[r], &w.settings(), &views)?;
        Ok(all.remove(0).0)
    }

    /// Every renderer of `renderers` on the workload `settings` from each of `views`
    /// (indices into the scene's cameras, `None`: the scene's camera; with the rays of
    /// each): per renderer, the measurement over every view ([`Measurement::of_views`]) and each
    /// view's.
    ///
    /// Every renderer is warmed up first: a counted run per view (its ids, `t` and counters
    /// are what the comparison uses), then, for a backend on another device or a workload
    /// shorter than the minimum sample, an uncounted one that compiles what the timed runs
    /// will use and says how many runs fill a sample. Then the timed rounds
    /// ([`rounds::run`]): each renderer once per round in a rotated order, a sample being
    /// every view once (each run as often as fills its share of the minimum sample), a
    /// sample the machine interfered with taken again within the redo budget.
    pub(crate) fn measure_all(
        &self,
        renderers: &[&dyn TimedRenderer],
        settings: &RenderSettings,
        views: &Views,
    ) -> Result<Vec<(Measurement, Vec<Measurement>)>> {
        let per_view = |camera: Option<u32>| RenderSettings {
            camera,
            ..*settings
        };
        let share = self.policy.min_sample / views.len().max(1) as f64;
        // Warm-ups: per renderer and view, the counted run and the runs per sample.
        let mut warm = Vec::with_capacity(renderers.len());
        for r in renderers {
            let mut each = Vec::with_capacity(views.len());
            for (camera, rays) in views {
                let settings = per_view(*camera);
                let counted = measure(*r, &settings, rays.as_ref(), true)?;
                let device = r.device().is_some();
                let (once, first) = if device || counted.seconds < share {
                    let m = measure(*r, &settings, rays.as_ref(), false)?;
                    (m.seconds, device.then_some(m.seconds))
                } else {
                    (counted.seconds, None)
                };
                let runs = rounds::repetitions_per_sample(once, share);
                each.push((counted, runs, first));
            }
            warm.push(each);
        }
        let tallies = rounds::run(renderers.len(), &self.policy, |i| {
            self.sample(renderers[i], &per_view, views, &warm[i])
        })?;
        Ok(renderers
            .iter()
            .zip(warm)
            .zip(tallies)
            .map(|((_, warm), tally)| {
                let each: Vec<Measurement> = warm
                    .into_iter()
                    .enumerate()
                    .map(|(v, (counted, runs, first))| {
                        let samples = tally.extra.iter().map(|x| x[v].0).collect();
                        let mut phases = raybench_registry::measure::median_phases(
                            &tally
                                .extra
                                .iter()
                                .map(|x| x[v].1.clone())
                                .collect::<Vec<_>>(),
                        );
                        if let Some(first) = first {
                            phases.push("warm-up", first);
                        }
                        Measurement {
                            warm: counted,
                            timing: Timing {
                                redone: tally.redone,
                                contended: tally.contended,
                                per_sample: runs,
                                ..Timing::of(samples)
                            },
                            phases,
                            device: None,
                        }
                    })
                    .collect();
                let counts = |t: Timing| Timing {
                    redone: tally.redone,
                    contended: tally.contended,
                    per_sample: each.iter().map(|m| m.timing.per_sample).min().unwrap_or(1),
                    ..t
                };
                // The device's time of a sample: its `gpu` phase over every view.
                let device: Option<Vec<f64>> = tally
                    .extra
                    .iter()
                    .map(|x| x.iter().map(|(_, p)| p.get("gpu")).sum())
                    .collect();
                let all = Measurement::of_views(
                    &each,
                    counts(Timing::of(tally.seconds)),
                    device
                        .filter(|d| !d.is_empty())
                        .map(|d| counts(Timing::of(d))),
                );
                (all, each)
            })
            .collect())
    }

    /// One timed sample of `r`: every view run its `runs` times, uncounted. Its seconds
    /// are the sum over views of the seconds per run; the extra is each view's seconds per
    /// run and mean phases.
    fn sample(
        &self,
        r: &dyn TimedRenderer,
        per_view: &dyn Fn(Option<u32>) -> RenderSettings,
        views: &Views,
        warm: &[(Measured, u32, Option<f64>)],
    ) -> Result<rounds::Sample<Vec<(f64, raybench_core::Timings)>>> {
        let (mut seconds, mut elapsed) = (0.0, 0.0);
        let mut waited = Some(Interference::default());
        let mut extra = Vec::with_capacity(views.len());
        for ((camera, rays), (_, runs, _)) in views.iter().zip(warm) {
            let settings = per_view(*camera);
            let mut total = 0.0;
            let mut phases = raybench_core::Timings::default();
            for _ in 0..*runs {
                let m = measure(r, &settings, rays.as_ref(), false)?;
                total += m.seconds;
                waited = waited.zip(m.interference).map(|(a, b)| Interference {
                    cpu_seconds: a.cpu_seconds + b.cpu_seconds,
                    wait_seconds: a.wait_seconds + b.wait_seconds,
                });
                add_phases(&mut phases, &m.phases);
            }
            let n = f64::from(*runs);
            for (_, s) in &mut phases.0 {
                *s /= n;
            }
            seconds += total / n;
            elapsed += total;
            extra.push((total / n, phases));
        }
        Ok(rounds::Sample {
            seconds,
            elapsed,
            contended: waited.is_some_and(|i| i.contended()),
            extra,
        })
    }
}

/// Bytes of `scene`'s primitives plus `r`'s structure: the memory the experiments report.
pub(crate) fn memory_bytes(scene: &Scene, r: &dyn TimedRenderer) -> u64 {
    (scene.geometry.memory_bytes() + r.structure().map_or(0, |s| s.memory_bytes)) as u64
}

impl Measurement {
    /// This measurement of `r` as a point of a scaling experiment: the median seconds, the
    /// warm-up's rays and, where `r` counts them, its tests per ray; what only some
    /// experiments record (load and build seconds, memory, ...) is left for them to fill.
    pub(crate) fn point(
        &self,
        r: &dyn TimedRenderer,
        experiment: &str,
        series: String,
        backend: &str,
        x: f64,
    ) -> ScalingPoint {
        let rays = self.warm.rays.max(1);
        ScalingPoint {
            hit_fraction: (!self.warm.ids.is_empty()).then(|| {
                let hits = self.warm.ids.iter().filter(|&&id| id != NO_HIT).count();
                hits as f64 / self.warm.ids.len() as f64
            }),
            shard: 0,
            experiment: experiment.into(),
            series,
            backend: backend.into(),
            x,
            seconds: self.timing.median,
            timing: Some(self.timing.clone()),
            rays: self.warm.rays,
            tests_per_ray: self
                .warm
                .counters
                .filter(|_| r.counts_tests())
                .map(|c| c.prim_tests as f64 / rays as f64),
            load_seconds: None,
            build_seconds: None,
            memory_bytes: None,
            difference: None,
            stored_primitives: None,
            visits_per_ray: self
                .warm
                .counters
                .filter(|c| r.counts_tests() && c.node_visits > 0)
                .map(|c| c.node_visits as f64 / rays as f64),
            quality: None,
        }
    }

    /// Several cameras' measurements of one workload as one, with the `timing` and
    /// `device` time of the rounds that took them all: the warm-ups' ids, `t` and colours
    /// concatenated in camera order, their rays and counters summed, and each phase's
    /// median summed.
    pub(crate) fn of_views(
        each: &[Measurement],
        timing: Timing,
        device: Option<Timing>,
    ) -> Measurement {
        let mut phases = raybench_core::Timings::default();
        for m in each {
            add_phases(&mut phases, &m.phases);
        }
        let warm = if let [one] = each {
            one.warm.clone()
        } else {
            let mut warm = Measured {
                ids: Vec::new(),
                t: Vec::new(),
                rays: 0,
                counters: None,
                seconds: 0.0,
                phases: raybench_core::Timings::default(),
                color: None,
                interference: None,
            };
            for m in each {
                warm.ids.extend_from_slice(&m.warm.ids);
                warm.t.extend_from_slice(&m.warm.t);
                warm.rays += m.warm.rays;
                warm.seconds += m.warm.seconds;
                if let Some(c) = &m.warm.counters {
                    use raybench_core::Counters as _;
                    warm.counters
                        .get_or_insert_with(raybench_core::RayCounters::default)
                        .merge(c);
                }
                if let Some(c) = &m.warm.color {
                    warm.color.get_or_insert_with(Vec::new).extend_from_slice(c);
                }
            }
            warm
        };
        Measurement {
            warm,
            timing,
            device,
            phases,
        }
    }
}

/// Adds each phase of `from` to the same-named phase of `into` (appended where `into` has
/// none).
fn add_phases(into: &mut raybench_core::Timings, from: &raybench_core::Timings) {
    for (name, secs) in &from.0 {
        match into.0.iter_mut().find(|(n, _)| n == name) {
            Some((_, total)) => *total += secs,
            None => into.push(name.clone(), *secs),
        }
    }
}
