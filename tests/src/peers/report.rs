//! The peer benchmark's results: the JSON schema (`raybench-peers/2`) and the tables printed
//! from it.
//!
//! ```text
//! {
//!   "schema": "raybench-peers/2",
//!   "machine": { cpu, cores, threads, isa, gpu, os, version },   // as raybench report's
//!   "packet_isa": "avx2",            // what raybench_packet::Isa::detect chose
//!   "embree": "Embree 3.13.5, native packets 4/8/16" | "absent: ...",
//!   "workload": { primary_size, tile, incoherent_rays, seed, chunk, repeat, threads: [1, N],
//!                 shadow_fraction },
//!   "meshes": [ {
//!     "name": "sphere", "spec": "icosphere:6", "triangles": 81920,
//!     "ray_sets": [ { "name": "primary", "rays": 1048576, "hits": 640000 } ],
//!     "skipped": [ { "name": "packet-avx512", "reason": "this CPU has no AVX-512F" } ],
//!     "skipped_sets": [ { "name": "shadow", "reason": "no shadow rays: the scene has no light ..." } ],
//!     "groups": [ ["bvh", "packet", ...] ],   // contestants timed in the same rounds
//!     "contestants": [ {
//!       "name": "bvh", "kind": "raybench" | "peer",
//!       "build_s": 0.012,            // best of `builds`, all cores
//!       "builds": 21,                // interleaved rounds and the one traced with
//!       "build_rounds_s": [0.013, 0.012, ...],  // the interleaved rounds, in round order
//!       "build_memory": { "thp_fault_alloc": 0, "compact_stall": 0 },  // or null
//!       "build_vs_embree": 1.9,      // build_s / embree1-default's build_s (lower is faster)
//!       "build_ratio": { "reference": "embree1-default",   // or null
//!                        "value": 1.95,                // median of the rounds' ratios
//!                        "interval": [1.85, 2.1], "confidence": 0.96 },  // or null
//!       "ray_sets": [ {
//!         "name": "primary",
//!         "closest": {               // intersect_batch; "any": occluded_batch on shadow rays
//!           "runs": [ { "threads": 1, "median_s": 0.25, "best_s": 0.24,
//!                       "samples_s": [0.25, 0.24, 0.26], // kept rounds, in round order
//!                       "mrays": 4.1,                    // at the median
//!                       "redone": 0, "contended": 0 } ],
//!           "differ": 0,             // rays whose hit/miss or primitive differs from bvh's
//!           "node_visits_per_ray": 37.0, "prim_tests_per_ray": 2.2,       // or null
//!           "ratios": [ { "reference": "embree16-robust", "threads": 1,
//!                         "value": 0.37,              // median of the rounds' ratios
//!                         "interval": [0.35, 0.39], "confidence": 0.75,  // or null
//!                         "verdict": "behind" } ]     // ahead, behind, within noise,
//!         },                                          // noise unknown
//!         "any": { ... }
//!       } ]
//!     } ]
//!   } ],
//!   "skipped_meshes": [ { "name": "dabrovic-sponza", "reason": "missing asset ..." } ]
//! }
//! ```

use super::contestants::Kind;
use super::contestants::embree::{PACKET_DEFAULT, PACKET_ROBUST, SINGLE_DEFAULT, SINGLE_ROBUST};
use raybench_core::RaySet;
use raybench_registry::interference::MemoryEvents;
use raybench_report::results::CacheWalk;
use raybench_report::results::Machine;
use raybench_report::rounds::Tally;
use raybench_report::stats::{self, Change};
use serde::Serialize;
use std::fmt::Write as _;

/// The schema name written into every file.
pub const SCHEMA: &str = "raybench-peers/2";

/// A whole run.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// [`SCHEMA`].
    pub schema: &'static str,
    /// The machine, as `raybench report` describes it.
    pub machine: Machine,
    /// The instruction set `packet` chose (`raybench_packet::Isa::detect`).
    pub packet_isa: String,
    /// Embree's version and native packet widths, or why it is absent.
    pub embree: String,
    /// What was traced.
    pub workload: WorkloadInfo,
    /// One entry per mesh.
    pub meshes: Vec<MeshReport>,
    /// Meshes that could not be loaded here (the shared meshes without the assets
    /// directory, a flattened scene over the memory budget), with why.
    pub skipped_meshes: Vec<Skipped>,
    /// A random walk through a quarter of the last-level cache, timed for a second before
    /// the run and after it (`null` until the run ends;
    /// `raybench_report::cache_probe::last_level`): where other machines share that cache,
    /// the median step moves away from the fastest, and the small meshes' Mrays/s with it.
    pub cache: [Option<CacheWalk>; 2],
}

/// The workload's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct WorkloadInfo {
    /// Primary rays: a `primary_size x primary_size` image of the scene's camera.
    pub primary_size: u32,
    /// Edge of the tiles the primary rays are ordered in (4 x 4 pixel blocks inside).
    pub tile: u32,
    /// Incoherent rays per mesh.
    pub incoherent_rays: usize,
    /// Seed of the incoherent rays.
    pub seed: u32,
    /// Rays per `intersect_batch` / `occluded_batch` call.
    pub chunk: usize,
    /// Timed rounds per figure (every contestant timed once per round, the median kept),
    /// and the fewest builds per contestant (`ContestantReport::builds` says how many each
    /// had).
    pub repeat: usize,
    /// Thread counts measured.
    pub threads: Vec<usize>,
    /// Any-hit rays end at this fraction of `bvh`'s closest hit (misses keep `t_max`).
    pub shadow_fraction: f32,
}

/// One mesh.
#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    /// Short name (`sphere`).
    pub name: String,
    /// Scene spec (`icosphere:6`).
    pub spec: String,
    /// Primitive count.
    pub triangles: usize,
    /// The ray sets.
    pub ray_sets: Vec<RaySetInfo>,
    /// Contestants that could not run, with why.
    pub skipped: Vec<Skipped>,
    /// Ray sets that hold no ray on this mesh (a shadow set without lights), with why.
    pub skipped_sets: Vec<Skipped>,
    /// The contestants timed in the same rounds, in table order: one group where the
    /// machine's memory holds every contestant's structure at once, more where it does not
    /// (figures of different groups were not taken side by side).
    pub groups: Vec<Vec<String>>,
    /// Contestants' figures, in table order.
    pub contestants: Vec<ContestantReport>,
}

/// A ray set of a mesh.
#[derive(Clone, Debug, Serialize)]
pub struct RaySetInfo {
    /// `primary`, `incoherent`, `shadow`, `ao`, `diffuse`, or `file` (`--rays-file`).
    pub name: &'static str,
    /// Ray count.
    pub rays: usize,
    /// Rays that hit something (per `bvh`).
    pub hits: usize,
}

/// A contestant that did not run on a mesh, or a mesh that could not be loaded.
#[derive(Clone, Debug, Serialize)]
pub struct Skipped {
    /// Contestant or mesh.
    pub name: String,
    /// Why.
    pub reason: String,
}

/// One contestant on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ContestantReport {
    /// Contestant.
    pub name: String,
    /// Whose structure.
    pub kind: Kind,
    /// Best build time, seconds, all cores.
    pub build_s: f64,
    /// Builds `build_s` is the best of: the interleaved rounds and the one traced with
    /// (`build_rounds` in the parent module).
    pub builds: usize,
    /// The times of the interleaved build rounds, seconds, in round order (the build
    /// traced with is not among them: it was not paired with the others' builds).
    pub build_rounds_s: Vec<f64>,
    /// The machine's memory events during the interleaved builds; `None` where the system
    /// does not tell.
    pub build_memory: Option<BuildMemory>,
    /// `build_s` over Embree's (`embree1-default`); `None` without Embree.
    pub build_vs_embree: Option<f64>,
    /// The build against Embree's (`embree1-default`), the rounds paired; `None` without
    /// Embree.
    pub build_ratio: Option<BuildRatio>,
    /// One entry per ray set.
    pub ray_sets: Vec<SetReport>,
}

/// Memory events of the whole machine (Linux `/proc/vmstat`) during a contestant's builds
/// (`raybench_registry::interference::MemoryEvents`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BuildMemory {
    /// Page faults served with a newly allocated transparent huge page.
    pub thp_fault_alloc: u64,
    /// Allocations that waited for the kernel to compact memory.
    pub compact_stall: u64,
}

impl From<MemoryEvents> for BuildMemory {
    fn from(m: MemoryEvents) -> Self {
        Self {
            thp_fault_alloc: m.thp_fault_alloc,
            compact_stall: m.compact_stall,
        }
    }
}

/// One contestant on one ray set.
#[derive(Clone, Debug, Serialize)]
pub struct SetReport {
    /// `primary`, `incoherent`, `shadow`, `ao`, `diffuse`, or `file` (`--rays-file`).
    pub name: &'static str,
    /// Closest hits (`intersect_batch`).
    pub closest: QueryReport,
    /// Any hit (`occluded_batch`): an any-hit set's own rays, else the rays ending at
    /// [`crate::peers::SHADOW_FRACTION`] of `bvh`'s closest hit.
    pub any: QueryReport,
}

/// One query of one ray set.
#[derive(Clone, Debug, Serialize)]
pub struct QueryReport {
    /// Best run per thread count.
    pub runs: Vec<Run>,
    /// Rays whose answer differs from `bvh`'s (hit/miss or primitive; occluded or not).
    pub differ: usize,
    /// Node or cell visits per ray, when the contestant counts.
    pub node_visits_per_ray: Option<f64>,
    /// Primitive tests per ray, when the contestant counts.
    pub prim_tests_per_ray: Option<f64>,
    /// Throughput over the Embree references of [`references`], per thread count.
    pub ratios: Vec<Ratio>,
}

/// A timed figure: the kept rounds of one query on one thread count.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// Worker threads.
    pub threads: usize,
    /// Median of the kept rounds, seconds.
    pub median_s: f64,
    /// Fastest kept round, seconds.
    pub best_s: f64,
    /// Seconds of every kept round, in round order (round `k` of every contestant of a
    /// group was taken in the same round, so [`Ratio`]s pair them by index).
    pub samples_s: Vec<f64>,
    /// Million rays per second at the median.
    pub mrays: f64,
    /// Rounds taken again because the machine interfered (another process waited for the
    /// CPUs: `raybench_registry::interference`).
    pub redone: u32,
    /// Kept rounds the machine interfered with (the redo budget spent, or the machine busy
    /// throughout).
    pub contended: u32,
}

impl Run {
    /// The figure of `rays` rays on `threads` threads from the kept rounds of `tally` (at
    /// least one).
    #[must_use]
    pub fn of<X>(threads: usize, rays: usize, tally: &Tally<X>) -> Self {
        let median_s = stats::median(&tally.seconds).unwrap_or(f64::NAN);
        Self {
            threads,
            median_s,
            best_s: tally.seconds.iter().copied().fold(f64::INFINITY, f64::min),
            samples_s: tally.seconds.clone(),
            mrays: rays as f64 / median_s / 1e6,
            redone: tally.redone,
            contended: tally.contended,
        }
    }
}

/// A throughput ratio to a reference contestant timed in the same rounds (above 1: faster
/// than the reference).
#[derive(Clone, Debug, Serialize)]
pub struct Ratio {
    /// The reference contestant.
    pub reference: &'static str,
    /// Worker threads of both figures.
    pub threads: usize,
    /// The median over the rounds of the reference's time over the contestant's
    /// ([`stats::paired_ratio`]: a slow phase of the machine lands on both sides of a
    /// round and cancels out).
    pub value: f64,
    /// The distribution-free interval of `value`, `[lo, hi]`; `None` with one round.
    pub interval: Option<[f64; 2]>,
    /// The probability that `interval` holds the true ratio (below 0.95 where few rounds
    /// allow no more: 0.75 for three, 0.94 for five).
    pub confidence: Option<f64>,
    /// What the interval says.
    pub verdict: Verdict,
}

/// A build time over a reference's, the interleaved rounds paired (above 1: slower than the
/// reference).
#[derive(Clone, Debug, Serialize)]
pub struct BuildRatio {
    /// The reference contestant.
    pub reference: &'static str,
    /// The median over the rounds of the contestant's build time over the reference's
    /// ([`stats::paired_ratio`]; `NaN` without rounds).
    pub value: f64,
    /// The distribution-free interval of `value`, `[lo, hi]`; `None` with one round.
    pub interval: Option<[f64; 2]>,
    /// The probability that `interval` holds the true ratio.
    pub confidence: Option<f64>,
}

impl BuildRatio {
    /// The rounds `own_s` against the reference `reference`'s rounds `base_s`.
    #[must_use]
    pub fn of(reference: &'static str, own_s: &[f64], base_s: &[f64]) -> Self {
        let (value, interval) = stats::paired_ratio(own_s, base_s);
        Self {
            reference,
            value,
            interval: interval.map(|i| [i.lo, i.hi]),
            confidence: interval.map(|i| i.confidence),
        }
    }

    /// The interval as a cell, `[lo-hi]`; `-` without one.
    #[must_use]
    pub fn interval_cell(&self) -> String {
        self.interval
            .map_or_else(|| "-".into(), |[lo, hi]| format!("[{lo:.2}-{hi:.2}]"))
    }
}

/// What a [`Ratio`]'s interval says of the contestant against the reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Verdict {
    /// Faster: the interval lies above 1 and the ratio is at least `1 + MIN_EFFECT`
    /// ([`stats::MIN_EFFECT`]).
    #[serde(rename = "ahead")]
    Ahead,
    /// Slower, likewise.
    #[serde(rename = "behind")]
    Behind,
    /// The interval holds 1, or the difference is under [`stats::MIN_EFFECT`].
    #[serde(rename = "within noise")]
    WithinNoise,
    /// One round: the noise is unknown.
    #[serde(rename = "noise unknown")]
    NoiseUnknown,
}

impl Ratio {
    /// `own` against `base` (the reference `reference`'s figure on the same thread count,
    /// timed in the same rounds).
    #[must_use]
    pub fn of(reference: &'static str, own: &Run, base: &Run) -> Self {
        let (value, interval) = stats::paired_ratio(&base.samples_s, &own.samples_s);
        let (time, time_interval) = stats::paired_ratio(&own.samples_s, &base.samples_s);
        let verdict = match stats::judge(time, time_interval, stats::MIN_EFFECT) {
            Change::Faster => Verdict::Ahead,
            Change::Slower => Verdict::Behind,
            Change::Same => Verdict::WithinNoise,
            Change::Unknown => Verdict::NoiseUnknown,
        };
        Self {
            reference,
            threads: own.threads,
            value,
            interval: interval.map(|i| [i.lo, i.hi]),
            confidence: interval.map(|i| i.confidence),
            verdict,
        }
    }

    /// The table's cell: the ratio, behind `~` when it is within the noise.
    #[must_use]
    pub fn cell(&self) -> String {
        match self.verdict {
            Verdict::WithinNoise => format!("~{:.2}", self.value),
            _ => format!("{:.2}", self.value),
        }
    }
}

/// Which query of a ray set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit.
    Closest,
    /// Any hit.
    Any,
}

/// The Embree contestants a query's throughput is compared with, with their column
/// headings: primary closest hits against the 16-wide packets, the closest hits of every
/// other set (incoherent, diffuse, a ray file's) against single rays in both modes, any
/// hits against `rtcOccluded1` in robust mode (the any-hit targets). `set` is a ray
/// set's name.
#[must_use]
pub fn references(set: &str, query: Query) -> &'static [(&'static str, &'static str)] {
    match (set, query) {
        (_, Query::Closest) if set == RaySet::Primary.name() => &[
            (PACKET_ROBUST, "vs E16 robust"),
            (PACKET_DEFAULT, "vs E16 default"),
        ],
        (_, Query::Closest) => &[
            (SINGLE_ROBUST, "vs E1 robust"),
            (SINGLE_DEFAULT, "vs E1 default"),
        ],
        (_, Query::Any) => &[(SINGLE_ROBUST, "vs O1 robust")],
    }
}

/// Embree's build, the reference of `build_vs_embree`.
pub const BUILD_REFERENCE: &str = SINGLE_DEFAULT;

/// Every Embree variant.
const EMBREE: [&str; 4] = [SINGLE_ROBUST, SINGLE_DEFAULT, PACKET_ROBUST, PACKET_DEFAULT];

/// Embree's variants in robust mode: watertight, as raybench's exact backends are.
const EMBREE_ROBUST: [&str; 2] = [SINGLE_ROBUST, PACKET_ROBUST];

/// The build goal of `bvh`: at most this multiple of Embree's fastest build.
pub const BVH_BUILD_GOAL: f64 = 1.2;

/// The build goal of `packet`, likewise.
pub const PACKET_BUILD_GOAL: f64 = 1.5;

/// On mesh `m`, ray set `set`: the ratio of the fastest exact raybench backend (by median
/// on `threads`) to the fastest of the Embree `variants`, their rounds paired; `None` where
/// either is missing.
fn best_against_embree(
    m: &MeshReport,
    set: &str,
    query: Query,
    threads: usize,
    variants: &[&'static str],
) -> Option<Ratio> {
    let fastest = |pick: &dyn Fn(&ContestantReport) -> bool| {
        m.contestants
            .iter()
            .filter(|c| pick(c))
            .filter_map(|c| Some((c, c.query(set, query)?.run(threads)?)))
            .max_by(|a, b| a.1.mrays.total_cmp(&b.1.mrays))
    };
    let (_, own) = fastest(&|c| c.kind == Kind::Raybench)?;
    let (reference, base) = fastest(&|c| variants.contains(&c.name.as_str()))?;
    let name = variants.iter().copied().find(|e| *e == reference.name)?;
    Some(Ratio::of(name, own, base))
}

impl QueryReport {
    /// Mrays/s on `threads`, if measured.
    #[must_use]
    pub fn mrays(&self, threads: usize) -> Option<f64> {
        self.run(threads).map(|r| r.mrays)
    }

    /// The figure on `threads`, if measured.
    #[must_use]
    pub fn run(&self, threads: usize) -> Option<&Run> {
        self.runs.iter().find(|r| r.threads == threads)
    }
}

impl ContestantReport {
    /// The query `query` of ray set `set`.
    #[must_use]
    pub fn query(&self, set: &str, query: Query) -> Option<&QueryReport> {
        self.ray_sets
            .iter()
            .find(|s| s.name == set)
            .map(|s| match query {
                Query::Closest => &s.closest,
                Query::Any => &s.any,
            })
    }
}

impl MeshReport {
    /// Fills every contestant's ratios to the Embree references and its build ratio, from
    /// the figures of the references measured on this mesh.
    pub fn compute_ratios(&mut self) {
        let snapshot = self.contestants.clone();
        let find = |name: &str| snapshot.iter().find(|c| c.name == name);
        let build_ref = find(BUILD_REFERENCE);
        for c in &mut self.contestants {
            c.build_vs_embree = build_ref.map(|b| c.build_s / b.build_s);
            c.build_ratio = build_ref
                .map(|b| BuildRatio::of(BUILD_REFERENCE, &c.build_rounds_s, &b.build_rounds_s));
            for s in &mut c.ray_sets {
                let name = s.name;
                for (query, q) in [(Query::Closest, &mut s.closest), (Query::Any, &mut s.any)] {
                    q.ratios.clear();
                    for &(reference, _) in references(name, query) {
                        let Some(r) = find(reference).and_then(|r| r.query(name, query)) else {
                            continue;
                        };
                        for run in &q.runs {
                            if let Some(base) = r.run(run.threads) {
                                q.ratios.push(Ratio::of(reference, run, base));
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The cells of every thread count joined as `"a / b"`, `-` where absent.
fn per_threads(threads: &[usize], cell: impl Fn(usize) -> Option<String>) -> String {
    threads
        .iter()
        .map(|&t| cell(t).unwrap_or_else(|| "-".to_string()))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The build of `own` against `reference`'s: the best build over the best, and the interval
/// of the median of the interleaved rounds' ratios (where there are two rounds or more).
fn build_cell(own: &ContestantReport, reference: &ContestantReport) -> String {
    let best = format!("{:.2}", own.build_s / reference.build_s);
    let rounds = BuildRatio::of("", &own.build_rounds_s, &reference.build_rounds_s);
    match rounds.interval {
        Some(_) => format!("{best} {}", rounds.interval_cell()),
        None => best,
    }
}

/// Mrays/s with two decimals.
fn mrays_cell(v: f64) -> String {
    format!("{v:.2}")
}

/// How the figures were taken and what a ratio cell says, for `repeat` rounds.
fn timing_rule(repeat: usize) -> String {
    let rounds = format!(
        "{repeat} round{} per figure, every contestant once per round in a rotated order \
         (a round the machine interfered with taken again), the median kept",
        if repeat == 1 { "" } else { "s" }
    );
    // The confidence of the round ratios' interval depends on the count alone.
    let samples: Vec<f64> = (0..repeat).map(|k| k as f64).collect();
    match stats::median_interval(&samples) {
        Some(i) => format!(
            "{rounds}; a ratio is the median of the rounds' ratios, shown as ~R where its \
             {:.0} % interval holds 1 or the difference is under {:.0} %",
            100.0 * i.confidence,
            100.0 * stats::MIN_EFFECT
        ),
        None => format!("{rounds}; one round: the ratios' noise is unknown"),
    }
}

impl Report {
    /// The tables: [`Report::header`], then [`Report::mesh_tables`] of every mesh.
    #[must_use]
    pub fn tables(&self) -> String {
        let mut out = self.header();
        for m in &self.meshes {
            out.push_str(&self.mesh_tables(m));
        }
        out.push_str(&self.skipped_meshes_text());
        out.push_str(&self.cache_text());
        out.push_str(&self.summary());
        out
    }

    /// The goals' table: per mesh and ray set, the best exact raybench backend against the
    /// best Embree variant on one thread (closest / any hits), and the builds of `bvh` and
    /// `packet` against Embree's fastest; empty without Embree's figures.
    #[must_use]
    pub fn summary(&self) -> String {
        let mut out = String::new();
        if !self.has_embree() {
            return out;
        }
        let threads = self.workload.threads.first().copied().unwrap_or(1);
        let sets: Vec<&str> = {
            let mut names: Vec<&str> = Vec::new();
            for s in self.meshes.iter().flat_map(|m| &m.ray_sets) {
                if !names.contains(&s.name) {
                    names.push(s.name);
                }
            }
            names
        };
        let _ = writeln!(
            out,
            "\n## Against Embree\n\nThe best exact raybench backend over the best Embree \
             variant, by median Mrays/s on {threads} thread{}, rounds paired (~: within the \
             noise); builds: the best build over Embree's fastest best build, lower is \
             faster (goals: `bvh` at most {BVH_BUILD_GOAL}, `packet` at most \
             {PACKET_BUILD_GOAL}), and in brackets the interval of the median of the ratios \
             of the builds' interleaved rounds, paired by round (its confidence, by the \
             rounds' count, is in the JSON).\n",
            if threads == 1 { "" } else { "s" }
        );
        out.push_str(&self.summary_table(&sets, threads, &EMBREE, true));
        let _ = writeln!(
            out,
            "\nThe same against Embree's robust mode only (watertight, as raybench's exact \
             backends are; its default mode is not):\n"
        );
        out.push_str(&self.summary_table(&sets, threads, &EMBREE_ROBUST, false));
        out
    }

    /// [`Report::summary`]'s table against the Embree `variants`, with the builds' column
    /// when `builds`.
    fn summary_table(
        &self,
        sets: &[&str],
        threads: usize,
        variants: &[&'static str],
        builds: bool,
    ) -> String {
        let mut out = String::new();
        let mut head = String::from("| mesh |");
        let mut rule = String::from("|---|");
        for s in sets {
            let _ = write!(head, " {s} closest / any |");
            rule.push_str("---:|");
        }
        if builds {
            head.push_str(" build bvh / packet |");
            rule.push_str("---:|");
        }
        let _ = writeln!(out, "{head}\n{rule}");
        for m in &self.meshes {
            let _ = write!(out, "| {} |", m.name);
            for s in sets {
                let cell = |query| {
                    best_against_embree(m, s, query, threads, variants)
                        .map_or_else(|| "-".into(), |r| r.cell())
                };
                let _ = write!(out, " {} / {} |", cell(Query::Closest), cell(Query::Any));
            }
            if builds {
                let fastest = m
                    .contestants
                    .iter()
                    .filter(|c| variants.contains(&c.name.as_str()))
                    .min_by(|a, b| a.build_s.total_cmp(&b.build_s));
                let build = |name: &str| {
                    let own = m.contestants.iter().find(|c| c.name == name);
                    match (own, fastest) {
                        (Some(c), Some(e)) => build_cell(c, e),
                        _ => "-".into(),
                    }
                };
                let _ = write!(out, " {} / {} |", build("bvh"), build("packet"));
            }
            out.push('\n');
        }
        out
    }

    /// The last-level cache's walk after the run, one line (empty until the run ends).
    #[must_use]
    pub fn cache_text(&self) -> String {
        self.cache[1].map_or_else(String::new, |after| {
            format!(
                "\nLast-level cache after the run: a random walk through {} took {}\n",
                after.size(),
                after.describe()
            )
        })
    }

    /// The meshes that could not be loaded, one line each with why (empty when none).
    #[must_use]
    pub fn skipped_meshes_text(&self) -> String {
        let mut out = String::new();
        if !self.skipped_meshes.is_empty() {
            let _ = writeln!(out, "\nSkipped meshes:");
            for s in &self.skipped_meshes {
                let _ = writeln!(out, "- {}: {}", s.name, s.reason);
            }
        }
        out
    }

    /// Whether Embree's figures are in the report.
    fn has_embree(&self) -> bool {
        self.meshes
            .iter()
            .any(|m| m.contestants.iter().any(|c| c.name == BUILD_REFERENCE))
    }

    /// The machine, Embree's version and the workload.
    #[must_use]
    pub fn header(&self) -> String {
        let mut out = String::new();
        let w = &self.workload;
        let threads = &w.threads;
        let t_label = threads
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(" / ");
        let _ = writeln!(out, "# raybench peers ({})", self.schema);
        let _ = writeln!(
            out,
            "CPU: {} ({} logical cores)",
            self.machine.cpu, self.machine.cores
        );
        let _ = writeln!(out, "ISA: {}", self.machine.isa);
        let _ = writeln!(out, "OS: {}; {}", self.machine.os, self.machine.version);
        let _ = writeln!(out, "Embree: {}", self.embree);
        let _ = writeln!(
            out,
            "Workload: primary {0} x {0} in {1} x {1} tiles, {2} incoherent rays (seed {3}), \
             {4}-ray batches; any hit on rays ending at {5} of bvh's closest hit; figures at \
             {t_label} threads",
            w.primary_size, w.tile, w.incoherent_rays, w.seed, w.chunk, w.shadow_fraction
        );
        let _ = writeln!(out, "Timing: {}", timing_rule(w.repeat));
        if let Some(before) = &self.cache[0] {
            let _ = writeln!(
                out,
                "Last-level cache before the run: a random walk through {} took {}",
                before.size(),
                before.describe()
            );
        }
        if !self.has_embree() && !self.embree.starts_with("Embree") {
            let _ = writeln!(
                out,
                "No Embree figures ({}): ratio columns are absent.",
                self.embree
            );
        }
        out
    }

    /// Mesh `m`'s build table and one table per ray set (Mrays/s and ratios at each
    /// thread count, counters, differences from `bvh`).
    #[must_use]
    pub fn mesh_tables(&self, m: &MeshReport) -> String {
        let mut out = String::new();
        let threads = &self.workload.threads;
        let t_label = threads
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(" / ");
        let embree = m.contestants.iter().any(|c| c.name == BUILD_REFERENCE);
        {
            let _ = writeln!(
                out,
                "\n## {} ({}, {} triangles)\n",
                m.name, m.spec, m.triangles
            );
            for s in &m.skipped {
                let _ = writeln!(out, "skipped {}: {}", s.name, s.reason);
            }
            for s in &m.skipped_sets {
                let _ = writeln!(out, "skipped ray set {}: {}", s.name, s.reason);
            }
            if m.groups.len() > 1 {
                let groups: Vec<String> = m.groups.iter().map(|g| g.join(", ")).collect();
                let _ = writeln!(
                    out,
                    "timed in separate rounds (the memory holds no more structures at once): {}",
                    groups.join(" | ")
                );
            }
            let memory = m.contestants.iter().any(|c| c.build_memory.is_some());
            let _ = writeln!(
                out,
                "| contestant | build ms ({} threads) | builds |{}{}",
                threads.last().copied().unwrap_or(1),
                if embree {
                    " vs Embree build | rounds' ratio [interval] |"
                } else {
                    ""
                },
                if memory {
                    " huge-page faults / compaction stalls |"
                } else {
                    ""
                }
            );
            let _ = writeln!(
                out,
                "|---|---:|---:|{}{}",
                if embree { "---:|---:|" } else { "" },
                if memory { "---:|" } else { "" }
            );
            for c in &m.contestants {
                let _ = write!(
                    out,
                    "| {} | {:.1} | {} |",
                    c.name,
                    1e3 * c.build_s,
                    c.builds
                );
                if embree {
                    let _ = write!(
                        out,
                        " {} | {} |",
                        c.build_vs_embree
                            .map_or_else(|| "-".into(), |v| format!("{v:.2}")),
                        c.build_ratio.as_ref().map_or_else(
                            || "-".into(),
                            |r| format!("{:.2} {}", r.value, r.interval_cell())
                        )
                    );
                }
                if memory {
                    let _ = write!(
                        out,
                        " {} |",
                        c.build_memory.map_or_else(
                            || "-".into(),
                            |m| format!("{} / {}", m.thp_fault_alloc, m.compact_stall)
                        )
                    );
                }
                out.push('\n');
            }
            for set in &m.ray_sets {
                let _ = writeln!(
                    out,
                    "\n{} {}: {} rays, {} hit; Mrays/s and ratios at {t_label} threads\n",
                    m.name, set.name, set.rays, set.hits
                );
                let mut head = String::from("| contestant | closest |");
                let mut rule = String::from("|---|---:|");
                let closest_refs = if embree {
                    references(set.name, Query::Closest)
                } else {
                    &[]
                };
                let any_refs = if embree {
                    references(set.name, Query::Any)
                } else {
                    &[]
                };
                for (_, h) in closest_refs {
                    let _ = write!(head, " {h} |");
                    rule.push_str("---:|");
                }
                head.push_str(" any |");
                rule.push_str("---:|");
                for (_, h) in any_refs {
                    let _ = write!(head, " {h} |");
                    rule.push_str("---:|");
                }
                head.push_str(
                    " visits/ray closest, any | tests/ray closest, any | differ closest, any |",
                );
                rule.push_str("---:|---:|---:|");
                let _ = writeln!(out, "{head}\n{rule}");
                for c in &m.contestants {
                    let (Some(cl), Some(an)) = (
                        c.query(set.name, Query::Closest),
                        c.query(set.name, Query::Any),
                    ) else {
                        continue;
                    };
                    let _ = write!(
                        out,
                        "| {} | {} |",
                        c.name,
                        per_threads(threads, |t| cl.mrays(t).map(mrays_cell))
                    );
                    let ratio = |q: &QueryReport, reference: &str, t: usize| {
                        q.ratios
                            .iter()
                            .find(|r| r.reference == reference && r.threads == t)
                            .map(Ratio::cell)
                    };
                    for (r, _) in closest_refs {
                        let _ = write!(out, " {} |", per_threads(threads, |t| ratio(cl, r, t)));
                    }
                    let _ = write!(
                        out,
                        " {} |",
                        per_threads(threads, |t| an.mrays(t).map(mrays_cell))
                    );
                    for (r, _) in any_refs {
                        let _ = write!(out, " {} |", per_threads(threads, |t| ratio(an, r, t)));
                    }
                    let count =
                        |v: Option<f64>| v.map_or_else(|| "-".into(), |v| format!("{v:.1}"));
                    let _ = writeln!(
                        out,
                        " {}, {} | {}, {} | {}, {} |",
                        count(cl.node_visits_per_ray),
                        count(an.node_visits_per_ray),
                        count(cl.prim_tests_per_ray),
                        count(an.prim_tests_per_ray),
                        cl.differ,
                        an.differ
                    );
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(samples_s: &[f64]) -> Run {
        let tally = Tally::<()> {
            seconds: samples_s.to_vec(),
            ..Tally::default()
        };
        Run::of(1, 1_000_000, &tally)
    }

    /// A ratio pairs the rounds: a slow round of both sides cancels out, a contestant
    /// faster in every round of five is ahead, one whose rounds straddle the reference's is
    /// within the noise, and one round says nothing of the noise.
    #[test]
    fn ratios_pair_the_rounds_and_judge_by_their_interval() {
        let reference = run(&[1.0, 1.0, 2.0, 1.0, 1.0]);
        let ahead = Ratio::of("r", &run(&[0.8, 0.8, 1.6, 0.81, 0.79]), &reference);
        assert_eq!(ahead.verdict, Verdict::Ahead);
        assert_eq!(ahead.value, 1.0 / 0.8);
        let [lo, hi] = ahead.interval.unwrap();
        assert!(lo > 1.2 && hi < 1.3, "{ahead:?}");
        assert_eq!(ahead.confidence, Some(0.9375));
        assert_eq!(ahead.cell(), "1.25");
        let behind = Ratio::of("r", &reference, &run(&[0.8, 0.8, 1.6, 0.81, 0.79]));
        assert_eq!(behind.verdict, Verdict::Behind);
        let tie = Ratio::of("r", &run(&[0.97, 1.04, 1.9, 0.99, 1.02]), &reference);
        assert_eq!(tie.verdict, Verdict::WithinNoise);
        assert!(tie.cell().starts_with('~'), "{}", tie.cell());
        let once = Ratio::of("r", &run(&[0.5]), &run(&[1.0]));
        assert_eq!((once.verdict, once.interval), (Verdict::NoiseUnknown, None));
        assert_eq!(once.cell(), "2.00");
        // The figure is the median round: 1 Mrays in 1 s.
        assert_eq!((reference.mrays, reference.best_s), (1.0, 1.0));
    }

    /// A build ratio pairs the interleaved rounds: the median of the rounds' ratios with
    /// its interval, a slow round of both sides cancelling out; the cell gives the best
    /// over the best beside that interval, and the best alone with one round.
    #[test]
    fn build_ratios_pair_the_rounds() {
        let contestant = |build_s: f64, rounds: &[f64]| ContestantReport {
            name: "c".into(),
            kind: Kind::Raybench,
            build_s,
            builds: rounds.len() + 1,
            build_rounds_s: rounds.to_vec(),
            build_memory: None,
            build_vs_embree: None,
            build_ratio: None,
            ray_sets: Vec::new(),
        };
        let embree = contestant(1.0, &[1.0, 2.0, 1.1, 1.0, 1.05]);
        let own = contestant(1.4, &[1.5, 3.0, 1.65, 1.45, 1.6]);
        let r = BuildRatio::of("e", &own.build_rounds_s, &embree.build_rounds_s);
        assert_eq!(r.value, 1.5);
        let [lo, hi] = r.interval.unwrap();
        assert!(lo >= 1.45 && hi <= 1.55 && lo < hi, "{r:?}");
        assert_eq!(r.confidence, Some(0.9375));
        assert_eq!(r.interval_cell(), format!("[{lo:.2}-{hi:.2}]"));
        assert_eq!(build_cell(&own, &embree), format!("1.40 [{lo:.2}-{hi:.2}]"));
        let once = contestant(1.4, &[1.5]);
        assert_eq!(build_cell(&once, &contestant(1.0, &[1.0])), "1.40");
        let none = BuildRatio::of("e", &[], &[]);
        assert!(none.value.is_nan() && none.interval.is_none());
        assert_eq!(none.interval_cell(), "-");
    }

    #[test]
    fn the_timing_rule_states_the_rounds_and_the_confidence() {
        let five = timing_rule(5);
        assert!(five.starts_with("5 rounds per figure"), "{five}");
        assert!(five.contains("94 % interval"), "{five}");
        assert!(timing_rule(1).ends_with("one round: the ratios' noise is unknown"));
    }
}
