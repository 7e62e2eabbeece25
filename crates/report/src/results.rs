//! `results.json`: what a report run measured, in a form other tools can read and
//! `raybench merge` can join (schema: `docs/results.md`).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The schema identifier written into every file; readers refuse others.
pub const SCHEMA: &str = "raybench-results/1";

/// Everything one report (or a merge of shards) measured.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Results {
    /// [`SCHEMA`].
    pub schema: String,
    /// The raybench version that wrote the file.
    pub raybench_version: String,
    /// One entry per shard that contributed (one for an unsharded run).
    pub shards: Vec<Shard>,
    /// One entry per (scene, workload, backend).
    pub runs: Vec<Run>,
    /// The scaling experiments' points.
    pub scaling: Vec<ScalingPoint>,
    /// Straight-line fits of the scaling points on log-log axes.
    pub fits: Vec<Fit>,
    /// The scenes and experiments of the matrix that did not run (or ran in part), and why.
    /// Absent from files written before it was added: read as empty.
    #[serde(default)]
    pub skipped: Vec<Skipped>,
    /// The `motion` experiment's frames (refit against rebuild). Absent from files written
    /// before it was added, and when it did not run: read as empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub motion: Vec<MotionFrame>,
    /// The frame pipeline's fixed cost per camera ray, measured on a scene without
    /// primitives, per backend. Absent from files written before it was added, and when the
    /// matrix did not run ray casting's camera rays: read as empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub empty_scene: Vec<EmptyScene>,
}

/// One backend on a scene without primitives (`report/experiments/empty_scene.rs`): every
/// camera ray misses, so the frame's time is the pipeline's fixed cost (ray generation,
/// shading a miss, the image) and the batch's the traversal's fixed cost per ray.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EmptyScene {
    /// Index into [`Results::shards`].
    pub shard: usize,
    /// Backend name.
    pub backend: String,
    /// Worker threads the frames and batches ran on (the matrix's).
    pub threads: usize,
    /// Image width (camera rays per row).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Camera rays per frame (and per batch).
    pub rays: u64,
    /// The whole frame's timed repetitions (ray casting, camera rays).
    pub frame: Timing,
    /// The same camera rays made beforehand and traced as a batch; `None` where it was not
    /// measured.
    pub trace: Option<Timing>,
}

impl EmptyScene {
    /// Nanoseconds per camera ray of the whole frame, over its median.
    #[must_use]
    pub fn frame_ns_per_ray(&self) -> f64 {
        self.frame.median / self.rays.max(1) as f64 * 1e9
    }

    /// Nanoseconds per camera ray of the batch trace, over its median.
    #[must_use]
    pub fn trace_ns_per_ray(&self) -> Option<f64> {
        let rays = self.rays.max(1) as f64;
        self.trace.as_ref().map(|t| t.median / rays * 1e9)
    }
}

/// One frame of a moving scene in the `motion` experiment, for one backend: the update
/// and trace times and the SAH cost of a structure refitted from frame 0 and of one rebuilt
/// every frame (`report/experiments/motion.rs`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MotionFrame {
    /// Index into [`Results::shards`].
    pub shard: usize,
    /// The moving scene.
    pub scene: String,
    /// Backend name.
    pub backend: String,
    /// The frame (0: both structures are the first build).
    pub frame: u32,
    /// Image side of the traced frames (camera rays).
    pub size: u32,
    /// Seconds of the refit (bottom level, phase `refit`); `None` at frame 0.
    pub refit_seconds: Option<f64>,
    /// Seconds of the rebuild (phase `build`; the first build at frame 0).
    pub rebuild_seconds: f64,
    /// Seconds of a two-level form's top-level rebuild (phase `top`, on the refitted
    /// structure), when it has one.
    pub top_seconds: Option<f64>,
    /// Median seconds to trace the camera rays through the refitted structure.
    pub trace_refitted_seconds: f64,
    /// Median seconds to trace them through the rebuilt structure.
    pub trace_rebuilt_seconds: f64,
    /// SAH cost (`C_t = C_i = 1`) of the refitted structure over the flat primitives.
    pub sah_refitted: Option<f64>,
    /// SAH cost of the rebuilt one.
    pub sah_rebuilt: Option<f64>,
}

/// A scene or scaling experiment of the matrix that did not run, or ran in part.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Skipped {
    /// Index into [`Results::shards`].
    pub shard: usize,
    /// `scene` or `experiment`.
    pub kind: String,
    /// The scene or experiment name.
    pub name: String,
    /// `skipped` (nothing of it ran) or `partial` (some points of an experiment ran).
    pub status: String,
    /// Why (a missing asset: which file, and where it was looked for).
    pub reason: String,
}

/// One shard of the matrix: where and how it ran.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based shard number.
    pub index: u32,
    /// Number of shards the matrix was split into.
    pub count: u32,
    /// The machine it ran on.
    pub machine: Machine,
    /// When it started (UTC, RFC 3339).
    pub started: String,
    /// Wall-clock seconds it took.
    pub wall_seconds: f64,
    /// The command line.
    pub command: String,
    /// Whether it was a `--quick` run.
    pub quick: bool,
    /// The machine's load averages (1, 5, 15 minutes) when the shard started and when it
    /// ended; `null` where the system does not tell, and in files written before they were
    /// recorded.
    #[serde(default)]
    pub load: Option<[[f64; 3]; 2]>,
    /// Whether the verdict ranks backends on another device by their device time
    /// (`--device-time`) rather than by wall time, as every other backend is.
    #[serde(default)]
    pub ranked_by_device: bool,
    /// The share of the machine's CPU time other processes took while the shard ran (busy
    /// time not its own over all CPUs' time; hypervisor steal included), and of it the
    /// hypervisor's steal; `null` where `/proc` does not tell and in older files.
    #[serde(default)]
    pub others: Option<[f64; 2]>,
    /// A random walk through a quarter of the last-level cache, timed for a quarter of a
    /// second when the shard started and when it ended ([`crate::cache_probe::last_level`]):
    /// where other machines share that cache, its median step moves away from its fastest;
    /// `null` in older files.
    #[serde(default)]
    pub cache: Option<[CacheWalk; 2]>,
    /// Whether the worker threads were pinned to cores (`--pin`).
    #[serde(default)]
    pub pinned: bool,
    /// How the timed repetitions were chosen: `auto` or the fixed count (`--repeat`);
    /// empty in files written before it was recorded.
    #[serde(default)]
    pub repeat: String,
    /// Seconds a timed repetition lasted at least (`--min-sample`); 0 in files written
    /// before it was recorded.
    #[serde(default)]
    pub min_sample: f64,
    /// The plan this shard is part of (`merge` checks that its shards share it); `null` in
    /// files written before it was recorded.
    #[serde(default)]
    pub plan: Option<Plan>,
}

/// A random walk through memory, one dependent load per step, timed in samples
/// ([`crate::cache_probe`]), summarised.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CacheWalk {
    /// Bytes walked through.
    pub bytes: u64,
    /// Samples taken (100,000 steps each).
    pub samples: u32,
    /// Nanoseconds per step of the fastest sample.
    pub fastest_ns: f64,
    /// Of the median sample.
    pub median_ns: f64,
    /// Of the 90th percentile.
    pub p90_ns: f64,
    /// Of the slowest sample.
    pub slowest_ns: f64,
}

/// The whole report a shard is part of: what `merge` checks its shards share, and which
/// units a missing shard would have run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The options that decide the work and its timings, as one line: every option of
    /// `report` but `--shard`, `--out` and `--baseline`.
    pub settings: String,
    /// The binary that ran it: its version and a hash of its executable.
    pub binary: String,
    /// Every unit of the whole plan in order (`matrix spheres`, `primitives primitives`):
    /// shard `I/N` runs those at 0-based positions `p` with `p mod N = I - 1`
    /// ([`Plan::holds`]).
    pub units: Vec<String>,
}

impl Plan {
    /// Whether shard `index` of `count` runs the unit at 0-based position `position`.
    #[must_use]
    pub fn holds(position: usize, index: u32, count: u32) -> bool {
        (position as u64 % u64::from(count)) + 1 == u64::from(index)
    }

    /// The units shard `index` of `count` runs.
    #[must_use]
    pub fn units_of(&self, index: u32, count: u32) -> Vec<&str> {
        self.units
            .iter()
            .enumerate()
            .filter(|(p, _)| Self::holds(*p, index, count))
            .map(|(_, u)| u.as_str())
            .collect()
    }
}

impl Shard {
    /// Whether `other` records the same run of the same shard.
    #[must_use]
    pub fn same_run(&self, other: &Shard) -> bool {
        (
            self.index,
            self.count,
            &self.started,
            &self.command,
            &self.machine,
        ) == (
            other.index,
            other.count,
            &other.started,
            &other.command,
            &other.machine,
        )
    }
}

/// The machine a shard ran on.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Machine {
    /// The node's host name (a cluster's node name); empty in files written before it was
    /// recorded.
    #[serde(default)]
    pub host: String,
    /// CPU model name.
    pub cpu: String,
    /// Logical cores available to the process.
    pub cores: usize,
    /// Worker threads used for rendering.
    pub threads: usize,
    /// Instruction set the `packet` backend uses, and the SIMD extensions detected.
    pub isa: String,
    /// GPU adapter used by GPU backends, or why there is none.
    pub gpu: String,
    /// Operating system and kernel.
    pub os: String,
    /// The raybench version and, when known, the source revision.
    pub version: String,
    /// How the binary was compiled: the compiler's version, optimisation level, debug
    /// assertions, target and `RUSTFLAGS` ([`raybench_registry::BUILD`]); empty in files
    /// written before it was recorded.
    #[serde(default)]
    pub build: String,
    /// The CPU frequency policy: the governor and the frequency range where the OS exposes
    /// them (`cpufreq`), else what `/proc/cpuinfo` reports and why the policy is unknown;
    /// empty in files written before it was recorded.
    #[serde(default)]
    pub frequency: String,
    /// Simultaneous multithreading: whether the OS runs sibling threads on one core, and how
    /// many logical CPUs share a core; empty in files written before it was recorded.
    #[serde(default)]
    pub smt: String,
    /// The data caches of CPU 0 as the OS reports them; `null` where it does not tell and
    /// in files written before they were recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caches: Option<Caches>,
}

/// The sizes of a CPU's data caches in bytes (a level's data or unified cache); `None` for
/// a level the OS does not report.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
pub struct Caches {
    /// The level-1 data cache.
    pub l1d: Option<u64>,
    /// The level-2 cache.
    pub l2: Option<u64>,
    /// The level-3 cache (shared by several cores on most CPUs).
    pub l3: Option<u64>,
}

impl Caches {
    /// Each known level with its label (`L1d`, `L2`, `L3`) and size, smallest level first.
    #[must_use]
    pub fn levels(&self) -> Vec<(&'static str, u64)> {
        [("L1d", self.l1d), ("L2", self.l2), ("L3", self.l3)]
            .into_iter()
            .filter_map(|(name, size)| Some((name, size?)))
            .collect()
    }

    /// The known levels as text: `L1d 48 KiB, L2 2 MiB, L3 480 MiB` (one decimal where the
    /// size is not a whole number of the unit).
    #[must_use]
    pub fn describe(&self) -> String {
        self.levels()
            .into_iter()
            .map(|(name, size)| {
                let (v, unit) = if size >= 1 << 20 {
                    (size as f64 / f64::from(1 << 20), "MiB")
                } else {
                    (size as f64 / 1024.0, "KiB")
                };
                let v = format!("{v:.1}");
                format!("{name} {} {unit}", v.trim_end_matches(".0"))
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The timed repetitions of one workload: their median with its confidence interval, the
/// extremes, and what the machine did meanwhile.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Timing {
    /// Median seconds.
    pub median: f64,
    /// Fastest repetition.
    pub min: f64,
    /// Slowest repetition.
    pub max: f64,
    /// Every repetition kept, in order.
    pub samples: Vec<f64>,
    /// The median's distribution-free confidence interval `[lo, hi]`
    /// ([`crate::stats::median_interval`]); `null` for a single repetition (noise unknown)
    /// and in files written before intervals were recorded.
    #[serde(default)]
    pub interval: Option<[f64; 2]>,
    /// The probability that [`Timing::interval`] holds the true median (0.95 or more from
    /// six repetitions; less with fewer, as stated).
    #[serde(default)]
    pub confidence: Option<f64>,
    /// Repetitions kept although the machine interfered with them (the redo budget was
    /// spent): see [`raybench_registry::interference`].
    #[serde(default)]
    pub contended: u32,
    /// Repetitions discarded because the machine interfered, and run again.
    #[serde(default)]
    pub redone: u32,
    /// Runs of the workload within one repetition (a repetition lasts at least the run's
    /// minimum sample; its seconds are per run): 1 in files written before samples had a
    /// minimum length.
    #[serde(default = "one")]
    pub per_sample: u32,
}

fn one() -> u32 {
    1
}

/// The half-width of a median's interval, relative to the median, above which a timing is
/// flagged as noisy in the report: 5 %.
pub const NOISY_HALF_WIDTH: f64 = 0.05;

/// What a timing says about its own noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Noise {
    /// A single repetition: nothing.
    Unknown,
    /// The interval's half-width relative to the median, at most [`NOISY_HALF_WIDTH`].
    Narrow(f64),
    /// Wider than that.
    Wide(f64),
}

impl Timing {
    /// The noise the median's interval shows; for files without intervals, the interval
    /// computed from the samples.
    #[must_use]
    pub fn noise(&self) -> Noise {
        let interval = self
            .interval
            .or_else(|| crate::stats::median_interval(&self.samples).map(|i| [i.lo, i.hi]));
        match interval {
            None => Noise::Unknown,
            Some([lo, hi]) => {
                let half = if self.median > 0.0 {
                    0.5 * (hi - lo) / self.median
                } else {
                    0.0
                };
                if half > NOISY_HALF_WIDTH {
                    Noise::Wide(half)
                } else {
                    Noise::Narrow(half)
                }
            }
        }
    }

    /// Whether the median's interval is wider than [`NOISY_HALF_WIDTH`].
    #[must_use]
    pub fn noisy(&self) -> bool {
        matches!(self.noise(), Noise::Wide(_))
    }

    /// The timing of `samples` (at least one), none contended.
    #[must_use]
    pub fn of(samples: Vec<f64>) -> Self {
        let min = samples.iter().copied().fold(f64::INFINITY, f64::min);
        let max = samples.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let interval = crate::stats::median_interval(&samples);
        Self {
            median: crate::stats::median(&samples).unwrap_or(0.0),
            min,
            max,
            interval: interval.map(|i| [i.lo, i.hi]),
            confidence: interval.map(|i| i.confidence),
            samples,
            contended: 0,
            redone: 0,
            per_sample: 1,
        }
    }
}

/// How a backend's result compares with the reference backend's on the same workload.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Equality {
    /// Fraction of pixels or rays with the reference's primitive id.
    pub id_match: f64,
    /// Rays hit by one and missed by the other.
    pub hit_mismatch: u64,
    /// Rays with the same id but a `t` differing in any bit.
    pub t_mismatch: u64,
    /// Rays where both hit different primitives at the same distance (relative difference
    /// at most `1e-4`): ties between coincident surfaces.
    pub tie_mismatch: u64,
    /// Largest `|t - t_ref|` where both hit the same primitive.
    pub max_abs_dt: f64,
    /// Ids, `t` and (for frames) colours bit-identical.
    pub identical: bool,
    /// PSNR of the sRGB colour image in dB; `null` when the images are identical (infinite)
    /// or the workload has no image.
    pub psnr_db: Option<f64>,
    /// Mean FLIP error (0 = indistinguishable, 1 = completely different); `null` without an
    /// image.
    pub flip_mean: Option<f64>,
    /// Whether the backend passes the report's threshold (see `docs/results.md`).
    pub pass: bool,
}

/// Files written for one run, relative to the report folder.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Images {
    /// The colour image (written for the reference and for backends whose image differs).
    pub color: Option<String>,
    /// Heat map of id mismatches against the reference.
    pub ids_diff: Option<String>,
    /// FLIP error map against the reference.
    pub flip: Option<String>,
    /// Heat map of node or cell visits per pixel of the first camera's rays
    /// ([`crate::images::visits_heat_map`]), for ray casting's camera rays on a backend with
    /// a per-ray cost distribution ([`Run::ray_costs`]). Absent otherwise and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visits: Option<String>,
}

/// One backend on one workload of one scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Run {
    /// Index into [`Results::shards`].
    pub shard: usize,
    /// Scene name.
    pub scene: String,
    /// Primitives in the scene.
    pub primitives: u64,
    /// Integrator (`cast`, `whitted`, `path`, `mip`, `composite`).
    pub mode: String,
    /// `primary` (frames), `incoherent` (explicit random rays), or a set derived from the
    /// primary hits: `shadow`, `ao` (any hit) or `diffuse`.
    pub ray_set: String,
    /// Image width (or rays = width x height for incoherent sets; the derived sets start
    /// from width x height primary rays).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Backend name.
    pub backend: String,
    /// Whether the backend is bound by the equivalence contract.
    pub exact: bool,
    /// The backend the equality figures compare with.
    pub reference: String,
    /// `ok`, `unavailable` (not on this machine) or `unsupported` (not this scene).
    pub status: String,
    /// Why it did not run.
    pub reason: Option<String>,
    /// Seconds to build the acceleration structure.
    pub build_seconds: Option<f64>,
    /// Bytes held by the structure.
    pub memory_bytes: Option<u64>,
    /// Named sizes of the structure (nodes, leaves, cells, ...).
    pub structure: BTreeMap<String, u64>,
    /// Render (or trace) time of the timed repetitions: the wall-clock time of the whole
    /// call, for every backend.
    pub seconds: Option<Timing>,
    /// For a backend on another device: the device's execution time of the same
    /// repetitions (phase `gpu`: timestamp queries where the adapter has them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device_seconds: Option<Timing>,
    /// For a backend on another device: the adapter it ran on (name, type, driver).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<String>,
    /// Whether that adapter is a software one (a CPU emulating a GPU, such as lavapipe):
    /// its figures are then no GPU's, and the report says so wherever they appear.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub software_device: bool,
    /// Whether a Whitted run's scene was lit by the headlight Whitted ray tracing uses where
    /// a scene has no point or directional light ([`raybench_core::integrator::headlight`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub headlight: bool,
    /// Rays traced per repetition (all rays: camera, secondary, shadow).
    pub rays: Option<u64>,
    /// Rays per second over the median time, in millions.
    pub mrays_per_s: Option<f64>,
    /// Ray/primitive tests per ray.
    pub tests_per_ray: Option<f64>,
    /// Node or cell visits per ray.
    pub visits_per_ray: Option<f64>,
    /// How the work spreads over the rays: each ray's own tests and visits, as percentiles
    /// ([`RayCosts`]). Recorded for ray casting's workloads on CPU backends that count node or
    /// cell visits, where the rays traced one at a time do exactly the work of the run's
    /// counted pass; absent otherwise and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ray_costs: Option<RayCosts>,
    /// The share of the rays with a hit, as this backend answered them: for frames the
    /// camera rays (pixels) that hit a surface, for closest-hit sets the rays that hit, for
    /// any-hit sets the rays blocked. Absent in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hit_fraction: Option<f64>,
    /// Shadow rays of the set not traced because their light lies behind the surface they
    /// would leave, which blocks it ([`raybench_core::ray_sets::Derived::facing_away`]):
    /// blocked, and left out of `rays` and `hit_fraction`. Absent for other sets and in
    /// older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub facing_away: Option<u64>,
    /// Ray casting's camera rays (`cast`, `primary`) traced once more as a batch made
    /// beforehand (no ray generation, shading or image): the trace throughput, where the run's
    /// own `seconds` and `mrays_per_s` time the whole frame. Absent for other workloads and in
    /// older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<Trace>,
    /// The scene is a coverage scene ([`raybench_scene::Purpose::Coverage`]: small, checking
    /// modes and kinds): timed, but the verdict names no winner on it. False for performance
    /// scenes, scene files, generated scenes and in older files.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub coverage: bool,
    /// Comparison with the reference.
    pub equality: Option<Equality>,
    /// Files.
    pub images: Images,
    /// Seconds per phase, for backends on another device (the GPU): `prepare.build`,
    /// `prepare.upload`, `warm-up` (the first call, which compiles the kernels it uses),
    /// and the medians of the timed repetitions' `upload`, `gpu` (execution),
    /// `readback` and `render` (the whole call, the time `seconds` and `mrays_per_s`
    /// use). Empty for CPU backends.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub phases: BTreeMap<String, f64>,
    /// Each camera, for a scene with several (empty otherwise): the run's own figures are
    /// then over every camera (`seconds` the time to render all of them once, `mrays_per_s`
    /// their rays over that time, the equality over all their pixels) and these are each
    /// camera's own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cameras: Vec<CameraRun>,
    /// The prepared structure's quality figures (the same for every workload of the backend
    /// on the scene: computed once after the build). Absent for backends without a
    /// structure and in files written before it was added.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quality: Option<Quality>,
}

/// The distribution of one per-ray count over a run's rays: the minimum, the nearest-rank
/// percentiles 50, 90 and 99 ([`crate::stats::nearest_rank`]) and the maximum.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Distribution {
    /// The smallest count.
    pub min: u64,
    /// The median (nearest rank).
    pub p50: u64,
    /// The 90th percentile (nearest rank).
    pub p90: u64,
    /// The 99th percentile (nearest rank).
    pub p99: u64,
    /// The largest count.
    pub max: u64,
}

impl Distribution {
    /// The distribution of `counts`; `None` for none.
    #[must_use]
    pub fn of(counts: &[u64]) -> Option<Self> {
        let mut v = counts.to_vec();
        v.sort_unstable();
        let at = |p| crate::stats::nearest_rank(&v, p);
        Some(Self {
            min: *v.first()?,
            p50: at(50)?,
            p90: at(90)?,
            p99: at(99)?,
            max: *v.last()?,
        })
    }
}

/// Each ray's own work on a run's rays ([`Run::ray_costs`]): every ray traced alone, with a
/// fresh count, in an untimed pass after the timed ones. The distributions are over every
/// camera's rays; their means are the run's `tests_per_ray` and `visits_per_ray`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct RayCosts {
    /// Rays the distributions are over.
    pub rays: u64,
    /// Ray/primitive tests per ray.
    pub tests: Distribution,
    /// Node or cell visits per ray.
    pub visits: Distribution,
}

/// A workload's rays traced as a batch ([`Run::trace`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Trace {
    /// The timed repetitions (every camera's batch once per repetition).
    pub seconds: Timing,
    /// Rays per repetition.
    pub rays: u64,
    /// Rays per second over the median, in millions.
    pub mrays_per_s: f64,
}

impl Run {
    /// The run as the verdict judges it: where its camera rays were also traced as a batch
    /// ([`Run::trace`]), the batch's time and throughput in place of the frame's, so that
    /// every ray set is judged on tracing alone.
    #[must_use]
    pub fn traced(&self) -> std::borrow::Cow<'_, Run> {
        match &self.trace {
            Some(t) => std::borrow::Cow::Owned(Run {
                seconds: Some(t.seconds.clone()),
                rays: Some(t.rays),
                mrays_per_s: Some(t.mrays_per_s),
                // The device's time belongs to the frame.
                device_seconds: None,
                ..self.clone()
            }),
            None => std::borrow::Cow::Borrowed(self),
        }
    }
}

/// One camera of a [`Run`] over a scene with several cameras.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CameraRun {
    /// The camera's name in the scene (`raybench info` lists them).
    pub name: String,
    /// This camera's timed repetitions.
    pub seconds: Timing,
    /// Rays traced per repetition.
    pub rays: u64,
    /// Rays per second over the median time, in millions.
    pub mrays_per_s: f64,
    /// Ids, `t` and colours bit-identical to the reference backend's from the same camera
    /// (`null` for the reference itself).
    pub identical: Option<bool>,
}

/// A structure's quality figures ([`raybench_core::StructureQuality`]), by kind.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Quality {
    /// A tree of boxes.
    Tree {
        /// `C_t`, the cost of an interior node in `sah` and `epo`.
        c_t: f64,
        /// `C_i`, the cost of a primitive test in `sah` and `epo`.
        c_i: f64,
        /// The SAH cost.
        sah: f64,
        /// The EPO estimate (mean over the sampled points).
        epo: f64,
        /// Its standard error.
        epo_std_error: f64,
        /// Points sampled for it.
        epo_samples: u32,
        /// Bounded primitives left out of the sampling (neither triangles nor spheres).
        epo_excluded_primitives: u64,
        /// Interior nodes.
        interior_nodes: u64,
        /// Leaves.
        leaves: u64,
        /// Leaves with 1, 2, 3, 4, 5-8, 9-16 and more than 16 primitives.
        leaf_sizes: [u64; 7],
        /// Nodes on the longest root-to-leaf path.
        max_depth: u32,
        /// Mean depth of the leaves (the root at depth 1).
        mean_leaf_depth: f64,
        /// Primitive references over all leaves.
        references: u64,
        /// Structure bytes per bounded primitive.
        bytes_per_primitive: f64,
        /// Mean leaves entered per ray up to its closest hit
        /// ([`raybench_core::TreeView::leaf_counts`]), where rays were given (experiment
        /// `presets`); absent elsewhere and in older files.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        leaves_per_ray: Option<f64>,
        /// Their standard deviation over the rays: the leaf-count variability.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        leaf_count_std_dev: Option<f64>,
    },
    /// A uniform or two-level grid.
    Grid {
        /// Cells whose lists rays test.
        cells: u64,
        /// Cells with a non-empty list.
        non_empty_cells: u64,
        /// Primitive references over all lists.
        references: u64,
        /// Bounded primitives.
        primitives: u64,
        /// The longest list.
        max_list: u64,
        /// Non-empty lists of 1, 2, 3, 4, 5-8, 9-16 and more than 16 references.
        list_lengths: [u64; 7],
        /// Structure bytes per bounded primitive.
        bytes_per_primitive: f64,
    },
    /// A structure whose nodes cannot be read (Embree).
    NotReadable {
        /// Why.
        reason: String,
    },
}

/// Column headers of [`Quality::tree_columns`].
pub const TREE_COLUMNS: [&str; 7] = [
    "SAH",
    "EPO ± error",
    "leaves",
    "interior",
    "depth max/mean",
    "bytes/prim",
    "primitives per leaf",
];

/// Column headers of [`Quality::grid_columns`].
pub const GRID_COLUMNS: [&str; 7] = [
    "cells",
    "fill",
    "refs/prim",
    "list mean",
    "list max",
    "bytes/prim",
    "list lengths",
];

impl Quality {
    /// A tree's figures as table cells (headers [`TREE_COLUMNS`]), for `raybench info` and
    /// `REPORT.md`.
    #[must_use]
    pub fn tree_columns(&self) -> Option<[String; 7]> {
        let Self::Tree {
            sah,
            epo,
            epo_std_error,
            leaves,
            interior_nodes,
            leaf_sizes,
            max_depth,
            mean_leaf_depth,
            bytes_per_primitive,
            ..
        } = self
        else {
            return None;
        };
        Some([
            format!("{sah:.2}"),
            self.measured_epo().map_or_else(
                || "not measured".to_string(),
                |_| format!("{epo:.2} ± {epo_std_error:.2}"),
            ),
            leaves.to_string(),
            interior_nodes.to_string(),
            format!("{max_depth}/{mean_leaf_depth:.1}"),
            format!("{bytes_per_primitive:.1}"),
            raybench_core::SizeHistogram(*leaf_sizes).describe(),
        ])
    }

    /// A grid's figures as table cells (headers [`GRID_COLUMNS`]).
    #[must_use]
    pub fn grid_columns(&self) -> Option<[String; 7]> {
        let Self::Grid {
            cells,
            non_empty_cells,
            references,
            primitives,
            max_list,
            list_lengths,
            bytes_per_primitive,
        } = *self
        else {
            return None;
        };
        let g = raybench_core::GridQuality {
            cells,
            non_empty_cells,
            references,
            primitives,
            max_list,
            list_lengths: raybench_core::SizeHistogram(list_lengths),
            bytes_per_primitive,
        };
        Some([
            cells.to_string(),
            format!("{:.1}%", 100.0 * g.fill()),
            format!("{:.2}", g.references_per_primitive()),
            format!("{:.2}", g.mean_list()),
            max_list.to_string(),
            format!("{bytes_per_primitive:.1}"),
            g.list_lengths.describe(),
        ])
    }

    /// A tree's SAH cost; `None` for other structures.
    #[must_use]
    pub fn sah(&self) -> Option<f64> {
        match self {
            Self::Tree { sah, .. } => Some(*sah),
            _ => None,
        }
    }

    /// A tree's EPO when it was measured: `None` when no point was sampled (the scene holds
    /// only kinds the EPO leaves out, so its 0 says nothing) and for other structures.
    #[must_use]
    pub fn measured_epo(&self) -> Option<f64> {
        match self {
            Self::Tree {
                epo, epo_samples, ..
            } if *epo_samples > 0 => Some(*epo),
            _ => None,
        }
    }
}

impl From<&raybench_core::StructureQuality> for Quality {
    fn from(q: &raybench_core::StructureQuality) -> Self {
        use raybench_core::StructureQuality as Q;
        match q {
            Q::Tree(t) => Self::Tree {
                c_t: t.costs.traversal,
                c_i: t.costs.intersection,
                sah: t.sah,
                epo: t.epo.mean,
                epo_std_error: t.epo.std_error,
                epo_samples: t.epo.samples,
                epo_excluded_primitives: t.epo.excluded_primitives,
                interior_nodes: t.interior_nodes,
                leaves: t.leaves,
                leaf_sizes: t.leaf_sizes.0,
                max_depth: t.max_depth,
                mean_leaf_depth: t.mean_leaf_depth,
                references: t.references,
                bytes_per_primitive: t.bytes_per_primitive,
                leaves_per_ray: t.leaf_counts.map(|c| c.mean),
                leaf_count_std_dev: t.leaf_counts.map(|c| c.std_dev),
            },
            Q::Grid(g) => Self::Grid {
                cells: g.cells,
                non_empty_cells: g.non_empty_cells,
                references: g.references,
                primitives: g.primitives,
                max_list: g.max_list,
                list_lengths: g.list_lengths.0,
                bytes_per_primitive: g.bytes_per_primitive,
            },
            Q::NotReadable(reason) => Self::NotReadable {
                reason: (*reason).to_string(),
            },
        }
    }
}

impl Run {
    /// Seconds per ray of each timed repetition (empty without timings or rays): what
    /// backends that trace the same rays are compared on (Mrays/s is the inverse of their
    /// median).
    #[must_use]
    pub fn seconds_per_ray(&self) -> Vec<f64> {
        self.seconds_per_ray_by(false)
    }

    /// [`Run::seconds_per_ray`], over the device time where `device` is set and the run
    /// has one.
    #[must_use]
    pub fn seconds_per_ray_by(&self, device: bool) -> Vec<f64> {
        let timing = match &self.device_seconds {
            Some(t) if device => Some(t),
            _ => self.seconds.as_ref(),
        };
        match (timing, self.rays) {
            (Some(t), Some(rays)) if rays > 0 => {
                t.samples.iter().map(|s| s / rays as f64).collect()
            }
            _ => Vec::new(),
        }
    }

    /// The backend's name as the report shows it: `wgpu (software adapter)` for one on a
    /// software adapter.
    #[must_use]
    pub fn label(&self) -> String {
        if self.software_device {
            format!("{} (software adapter)", self.backend)
        } else {
            self.backend.clone()
        }
    }

    /// What the run measured: scene, workload and backend (`spheres cast-primary 256x256
    /// 1 spp, backend bvh`); unique within a report.
    #[must_use]
    pub fn key(&self) -> String {
        format!(
            "{} {}-{} {}x{} {} spp, backend {}",
            self.scene, self.mode, self.ray_set, self.width, self.height, self.spp, self.backend
        )
    }
}

/// One point of a scaling experiment.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ScalingPoint {
    /// Index into [`Results::shards`].
    pub shard: usize,
    /// `primitives` (x = M), `pixels` (x = N^2), `spp` (x = K), `heightfield` (x = N^2
    /// cells; series `direct` or `tessellated`), `bezier` (x = primitives: 32 patches, or
    /// `2 N^2 32` triangles; series `direct` or `tessellated`) or `presets` (x = rays;
    /// series `SCENE RAYS`, such as `bunny primary`; backend `BACKEND:PRESET`).
    pub experiment: String,
    /// The scene or generator varied (`soup`, `spheres`, `bunny`, `cornell-box`).
    pub series: String,
    /// Backend name.
    pub backend: String,
    /// The varied quantity.
    pub x: f64,
    /// Median render seconds.
    pub seconds: f64,
    /// The timed repetitions behind [`ScalingPoint::seconds`]: median, interval, minimum
    /// and counts, as a run's `seconds`; absent in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
    /// Rays traced.
    pub rays: u64,
    /// Ray/primitive tests per ray.
    pub tests_per_ray: Option<f64>,
    /// Seconds to load or generate the scene (experiment `heightfield`: tessellating, or
    /// building the min-max levels).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_seconds: Option<f64>,
    /// Seconds to build the backend's structure (experiments `heightfield` and `presets`:
    /// there the median of the run's repetitions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build_seconds: Option<f64>,
    /// Bytes of primitives plus structure (experiments `heightfield` and `presets`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory_bytes: Option<u64>,
    /// The image against the direct rendering (experiment `bezier`, tessellated points).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub difference: Option<ImageDifference>,
    /// Primitives stored (experiment `instancing`: each distinct mesh once plus the flat
    /// ones for series `SCENE instanced`, every primitive for `SCENE flattened`; `x` is the
    /// flattened scene's primitive count).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stored_primitives: Option<u64>,
    /// Node or cell visits per ray (absent where the backend does not count them and in
    /// older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visits_per_ray: Option<f64>,
    /// The structure's quality figures (experiment `presets`: each preset's tree, for the
    /// fixed-kernel analysis); absent elsewhere and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quality: Option<Quality>,
    /// The share of the point's camera rays that hit (the warm-up's answers); absent in
    /// older files and for points without rays.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hit_fraction: Option<f64>,
}

impl ScalingPoint {
    /// What the point measured (`scaling primitives soup x=1000, backend bvh`); unique
    /// within a report.
    #[must_use]
    pub fn key(&self) -> String {
        format!(
            "scaling {} {} x={}, backend {}",
            self.experiment, self.series, self.x, self.backend
        )
    }
}

/// How far a rendering is from a reference rendering of the same view.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct ImageDifference {
    /// Mean FLIP error of the colour images.
    pub mean_flip: f64,
    /// Fraction of pixels whose object differs (a Bezier patch against its triangles; a hit
    /// against a miss).
    pub patch_mismatch: f64,
    /// Fraction of pixels hit in both whose depth differs by more than 1%.
    pub depth_mismatch: f64,
}

/// A least-squares line through `(log10 x, log10 y)`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Fit {
    /// The experiment.
    pub experiment: String,
    /// The series.
    pub series: String,
    /// The backend.
    pub backend: String,
    /// `seconds` or `tests_per_ray`.
    pub quantity: String,
    /// The slope: the exponent `a` in `y ~ x^a`.
    pub slope: f64,
    /// The line's intercept on log-log axes: `log10 y = intercept + slope * log10 x`.
    /// Absent from files written before it was added (a merge fits them anew).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intercept: Option<f64>,
    /// Points fitted.
    pub points: usize,
    /// The logarithmic model `y = a + b log10 x` fitted to the same points (least squares on
    /// relative residuals): `b`, the growth of `y` per decade of `x`. Absent with fewer
    /// than three points and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub per_decade: Option<f64>,
    /// The power law's Akaike criterion less the logarithm's, over relative residuals (both
    /// models have two parameters: `n ln(RSS_power / RSS_log)`): below -2 the points favour
    /// the power law, above 2 the logarithm, between them neither ([`Fit::favoured`]).
    /// Absent with fewer than three points and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delta_aic: Option<f64>,
}

/// The model a [`Fit`]'s points favour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Favoured {
    /// `y ~ x^slope` fits better by more than 2 in the Akaike criterion.
    PowerLaw,
    /// `y = a + b log10 x` fits better by more than 2.
    Logarithm,
    /// Within 2 of each other: the points do not tell the models apart.
    Neither,
}

/// The difference in the Akaike criterion that counts as a preference (Burnham and
/// Anderson's rule of thumb: below 2, the models are about equally supported).
pub const AIC_MARGIN: f64 = 2.0;

/// The largest spread (percentage points) of a series' hit fractions still called constant.
pub const CONSTANT_HITS_PP: f64 = 1.0;

/// The hit fraction (0 to 1) at each `x` of a scaling series, ascending in `x`
/// ([`Results::hit_fractions`]). A series whose hit fraction changes with `x` confounds its
/// fit: a ray that hits costs more than one that misses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HitFractions(pub Vec<(f64, f64)>);

impl HitFractions {
    /// The spread (largest minus smallest fraction) in percentage points; 0 with no points.
    #[must_use]
    pub fn spread_pp(&self) -> f64 {
        let (lo, hi) = self.range().unwrap_or((0.0, 0.0));
        (hi - lo) * 100.0
    }

    /// The smallest and largest fraction, or `None` with no points.
    #[must_use]
    pub fn range(&self) -> Option<(f64, f64)> {
        let mut it = self.0.iter().map(|&(_, h)| h);
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), h| (lo.min(h), hi.max(h))))
    }

    /// Whether the fraction stays within [`CONSTANT_HITS_PP`] over the series; `None` with
    /// fewer than two points, where constancy means nothing.
    #[must_use]
    pub fn constant(&self) -> Option<bool> {
        (self.0.len() >= 2).then(|| self.spread_pp() <= CONSTANT_HITS_PP)
    }
}

impl Fit {
    /// Which model the points favour, where they were compared.
    #[must_use]
    pub fn favoured(&self) -> Option<Favoured> {
        self.delta_aic.map(|d| {
            if d < -AIC_MARGIN {
                Favoured::PowerLaw
            } else if d > AIC_MARGIN {
                Favoured::Logarithm
            } else {
                Favoured::Neither
            }
        })
    }
}

/// The logarithmic model `y = a + b log10 x` by weighted least squares (weights `1 / y^2`,
/// so that relative residuals count, as in the power law's log-log fit), and both models'
/// relative residual sums: `(b, a, RSS_power, RSS_log)` for the power law `(slope,
/// intercept)`; `None` with fewer than three positive points or one distinct `x`.
#[must_use]
pub fn log_model(points: &[(f64, f64)], power: (f64, f64)) -> Option<(f64, f64, f64, f64)> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let w: Vec<f64> = pts.iter().map(|(_, y)| 1.0 / (y * y)).collect();
    let sw: f64 = w.iter().sum();
    let mx = pts
        .iter()
        .zip(&w)
        .map(|((x, _), w)| w * x.log10())
        .sum::<f64>()
        / sw;
    let my = pts.iter().zip(&w).map(|((_, y), w)| w * y).sum::<f64>() / sw;
    let sxx: f64 = pts
        .iter()
        .zip(&w)
        .map(|((x, _), w)| w * (x.log10() - mx).powi(2))
        .sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = pts
        .iter()
        .zip(&w)
        .map(|((x, y), w)| w * (x.log10() - mx) * (y - my))
        .sum();
    let b = sxy / sxx;
    let a = my - b * mx;
    let rel = |f: &dyn Fn(f64) -> f64| -> f64 {
        pts.iter().map(|(x, y)| ((y - f(*x)) / y).powi(2)).sum()
    };
    let rss_power = rel(&|x| 10f64.powf(power.1 + power.0 * x.log10()));
    let rss_log = rel(&|x| a + b * x.log10());
    Some((b, a, rss_power, rss_log))
}

/// The slope and intercept of the least-squares line through `(log10 x, log10 y)` for
/// positive pairs; `None` with fewer than two distinct `x`.
#[must_use]
pub fn log_log_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| {
        let slope = sxy / sxx;
        (slope, my - slope * mx)
    })
}

impl Results {
    /// Recomputes [`Results::fits`] from the scaling points.
    pub fn fit(&mut self) {
        let mut groups: BTreeMap<(String, String, String), Vec<&ScalingPoint>> = BTreeMap::new();
        for p in &self.scaling {
            groups
                .entry((p.experiment.clone(), p.series.clone(), p.backend.clone()))
                .or_default()
                .push(p);
        }
        self.fits.clear();
        for ((experiment, series, backend), pts) in groups {
            let time: Vec<(f64, f64)> = pts.iter().map(|p| (p.x, p.seconds)).collect();
            let tests: Vec<(f64, f64)> = pts
                .iter()
                .filter_map(|p| p.tests_per_ray.map(|t| (p.x, t)))
                .collect();
            for (quantity, data) in [("seconds", time), ("tests_per_ray", tests)] {
                if let Some((slope, intercept)) = log_log_fit(&data) {
                    let log = log_model(&data, (slope, intercept));
                    // Residuals of exactly 0 (a perfect fit) would make the ratio 0 or
                    // infinite: a floor far below any timing's noise.
                    let delta_aic = log.map(|(_, _, power, log)| {
                        let floor = 1e-12;
                        data.len() as f64 * ((power + floor) / (log + floor)).ln()
                    });
                    self.fits.push(Fit {
                        experiment: experiment.clone(),
                        series: series.clone(),
                        backend: backend.clone(),
                        quantity: quantity.into(),
                        slope,
                        intercept: Some(intercept),
                        points: data.len(),
                        per_decade: log.map(|l| l.0),
                        delta_aic,
                    });
                }
            }
        }
    }

    /// The fit of `quantity` for one series and backend.
    #[must_use]
    pub fn fit_of(
        &self,
        experiment: &str,
        series: &str,
        backend: &str,
        quantity: &str,
    ) -> Option<&Fit> {
        self.fits.iter().find(|f| {
            f.experiment == experiment
                && f.series == series
                && f.backend == backend
                && f.quantity == quantity
        })
    }

    /// The hit fraction at each `x` of one series of a scaling experiment, ascending in `x`:
    /// the first point of each `x` that recorded one (every exact backend shares the
    /// answers); empty where no point did (files written before they were).
    #[must_use]
    pub fn hit_fractions(&self, experiment: &str, series: &str) -> HitFractions {
        let mut points: Vec<(f64, f64)> = self
            .scaling
            .iter()
            .filter(|p| p.experiment == experiment && p.series == series)
            .filter_map(|p| Some((p.x, p.hit_fraction?)))
            .collect();
        // Stable: the first point of each `x` stays first, and `dedup_by` keeps it.
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        points.dedup_by(|b, a| a.0 == b.0);
        HitFractions(points)
    }

    /// The slope of `quantity` for one series and backend.
    #[must_use]
    pub fn slope(
        &self,
        experiment: &str,
        series: &str,
        backend: &str,
        quantity: &str,
    ) -> Option<f64> {
        self.fit_of(experiment, series, backend, quantity)
            .map(|f| f.slope)
    }

    /// Reads a `results.json`.
    ///
    /// # Errors
    /// When the file cannot be read, is not JSON of this schema, or has another schema.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        use anyhow::Context;
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("{} is not JSON", path.display()))?;
        let schema = value
            .get("schema")
            .and_then(serde_json::Value::as_str)
            .unwrap_or("none");
        if schema != SCHEMA {
            anyhow::bail!(
                "{} has schema {schema:?}, this raybench reads {SCHEMA:?}",
                path.display()
            );
        }
        serde_json::from_value(value)
            .with_context(|| format!("{} is not a valid {SCHEMA} file", path.display()))
    }

    /// Why `other` cannot be merged with `self` because they share data: the same shard
    /// (same number, start time, command and machine), or a run or scaling point measured
    /// in both; `None` when they are disjoint.
    #[must_use]
    pub fn overlap(&self, other: &Results) -> Option<String> {
        if let Some(s) = self
            .shards
            .iter()
            .find(|s| other.shards.iter().any(|o| s.same_run(o)))
        {
            return Some(format!(
                "shard {}/{} started {}",
                s.index, s.count, s.started
            ));
        }
        if let Some(r) = self
            .runs
            .iter()
            .find(|r| other.runs.iter().any(|o| r.key() == o.key()))
        {
            return Some(format!("both measure {}", r.key()));
        }
        self.scaling
            .iter()
            .find(|p| other.scaling.iter().any(|o| p.key() == o.key()))
            .map(|p| format!("both measure {}", p.key()))
    }

    /// Appends another result set, renumbering its shard references.
    pub fn absorb(&mut self, other: Results) {
        let offset = self.shards.len();
        self.shards.extend(other.shards);
        self.runs.extend(other.runs.into_iter().map(|mut r| {
            r.shard += offset;
            r
        }));
        self.scaling.extend(other.scaling.into_iter().map(|mut p| {
            p.shard += offset;
            p
        }));
        self.skipped.extend(other.skipped.into_iter().map(|mut s| {
            s.shard += offset;
            s
        }));
        self.motion.extend(other.motion.into_iter().map(|mut m| {
            m.shard += offset;
            m
        }));
        self.empty_scene
            .extend(other.empty_scene.into_iter().map(|mut e| {
                e.shard += offset;
                e
            }));
        self.fit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A distribution sorts the counts first (they come in ray order), and reads its
    /// percentiles by nearest rank: 7 counts, p50 the 4th, p90 and p99 the 7th.
    #[test]
    fn a_distribution_of_counts_in_ray_order() {
        let d = Distribution::of(&[9, 0, 4, 1, 30, 4, 2]).unwrap();
        assert_eq!(
            d,
            Distribution {
                min: 0,
                p50: 4,
                p90: 30,
                p99: 30,
                max: 30
            }
        );
        let d = Distribution::of(&(1..=100).rev().collect::<Vec<u64>>()).unwrap();
        assert_eq!((d.min, d.p50, d.p90, d.p99, d.max), (1, 50, 90, 99, 100));
        assert_eq!(Distribution::of(&[]), None);
    }

    /// Points on a power law favour it, points on a logarithm favour that, and a flat line
    /// (both models fit it exactly) favours neither.
    #[test]
    fn the_better_model_is_named_by_its_residuals() {
        let fit_of = |points: Vec<(f64, f64)>| {
            let mut r = Results::default();
            for (x, y) in points {
                r.scaling.push(ScalingPoint {
                    hit_fraction: None,
                    shard: 0,
                    experiment: "primitives".into(),
                    series: "soup".into(),
                    backend: "tree".into(),
                    x,
                    seconds: y,
                    timing: None,
                    rays: 1,
                    tests_per_ray: None,
                    load_seconds: None,
                    build_seconds: None,
                    memory_bytes: None,
                    difference: None,
                    stored_primitives: None,
                    visits_per_ray: None,
                    quality: None,
                });
            }
            r.fit();
            r.fits[0].clone()
        };
        let sizes: [f64; 5] = [1e3, 1e4, 1e5, 1e6, 1e7];
        let power = fit_of(
            sizes
                .iter()
                .map(|&m| (m, 1e-3 * m.powf(1.0 / 3.0)))
                .collect(),
        );
        assert!((power.slope - 1.0 / 3.0).abs() < 1e-9);
        assert_eq!(power.favoured(), Some(Favoured::PowerLaw), "{power:?}");
        let log = fit_of(sizes.iter().map(|&m| (m, 1.0 + 0.5 * m.log10())).collect());
        assert_eq!(log.favoured(), Some(Favoured::Logarithm), "{log:?}");
        assert!((log.per_decade.unwrap() - 0.5).abs() < 1e-9);
        let flat = fit_of(sizes.iter().map(|&m| (m, 2.0)).collect());
        assert_eq!(flat.favoured(), Some(Favoured::Neither), "{flat:?}");
        // Two points: no comparison.
        let two = fit_of(vec![(1e3, 1.0), (1e4, 2.0)]);
        assert_eq!((two.per_decade, two.favoured()), (None, None));
    }

    #[test]
    fn slopes_of_power_laws() {
        let linear: Vec<(f64, f64)> = (1..6)
            .map(|i| (10f64.powi(i), 3.0 * 10f64.powi(i)))
            .collect();
        let (slope, intercept) = log_log_fit(&linear).unwrap();
        assert!((slope - 1.0).abs() < 1e-12);
        assert!((intercept - 3f64.log10()).abs() < 1e-12);
        let flat: Vec<(f64, f64)> = (1..6).map(|i| (10f64.powi(i), 2.0)).collect();
        let (slope, intercept) = log_log_fit(&flat).unwrap();
        assert!(slope.abs() < 1e-12 && (intercept - 2f64.log10()).abs() < 1e-12);
        let half: Vec<(f64, f64)> = (1..6).map(|i| (4f64.powi(i), 2f64.powi(i))).collect();
        let (slope, intercept) = log_log_fit(&half).unwrap();
        assert!((slope - 0.5).abs() < 1e-12 && intercept.abs() < 1e-12);
        assert_eq!(log_log_fit(&[(1.0, 1.0)]), None);
        assert_eq!(log_log_fit(&[(1.0, 1.0), (1.0, 2.0)]), None);
        assert_eq!(
            log_log_fit(&[(0.0, 1.0), (-1.0, 2.0), (f64::NAN, 1.0)]),
            None
        );
    }

    /// A fit written before `intercept` existed reads without one, and a merge (which fits
    /// anew) gives it one.
    #[test]
    fn fits_without_an_intercept_still_read() {
        let old = r#"{"experiment": "spp", "series": "cornell-box", "backend": "tree",
            "quantity": "seconds", "slope": 1.0, "points": 2}"#;
        let f: Fit = serde_json::from_str(old).unwrap();
        assert_eq!(f.intercept, None);
        let json = serde_json::to_string(&f).unwrap();
        assert!(!json.contains("intercept"), "{json}");
        let mut r = Results::default();
        for (x, s) in [(1.0, 0.5), (4.0, 2.0)] {
            r.scaling.push(ScalingPoint {
                hit_fraction: None,
                shard: 0,
                experiment: "spp".into(),
                series: "cornell-box".into(),
                backend: "tree".into(),
                x,
                seconds: s,
                timing: None,
                rays: 1,
                tests_per_ray: None,
                load_seconds: None,
                build_seconds: None,
                memory_bytes: None,
                difference: None,
                stored_primitives: None,
                visits_per_ray: None,
                quality: None,
            });
        }
        r.fits.push(f);
        r.absorb(Results::default());
        let f = r.fit_of("spp", "cornell-box", "tree", "seconds").unwrap();
        assert!((f.slope - 1.0).abs() < 1e-12);
        // 0.5 x: log10 y = log10 0.5 + log10 x.
        assert!((f.intercept.unwrap() - 0.5f64.log10()).abs() < 1e-12);
    }

    #[test]
    fn timing_median_interval_and_noise() {
        let t = Timing::of(vec![3.0, 1.0, 2.0]);
        assert_eq!((t.median, t.min, t.max), (2.0, 1.0, 3.0));
        assert_eq!((t.interval, t.confidence), (Some([1.0, 3.0]), Some(0.75)));
        assert_eq!(t.noise(), Noise::Wide(0.5));
        let one = Timing::of(vec![1.0]);
        assert_eq!((one.interval, one.noise()), (None, Noise::Unknown));
        assert!(!one.noisy());
        let quiet = Timing::of(vec![1.0, 1.01, 0.99, 1.0, 1.02, 0.98]);
        assert!(matches!(quiet.noise(), Noise::Narrow(h) if (h - 0.02).abs() < 1e-9));
        // A file written before intervals: computed from its samples.
        let old: Timing = serde_json::from_str(
            r#"{"median": 2.0, "min": 1.0, "max": 3.0, "samples": [1.0, 2.0, 3.0]}"#,
        )
        .unwrap();
        assert_eq!((old.interval, old.contended, old.redone), (None, 0, 0));
        assert_eq!(old.noise(), Noise::Wide(0.5));
    }
}
