//! The peer benchmark (`benches/peers.rs`): the workload of `../shared/PEERS.md`, generated
//! once per mesh, traced by every exact raybench CPU backend and every peer in one process.
//!
//! Per mesh ([`MESHES`]: three generated meshes and three shared ones): every contestant's
//! builds in interleaved rounds ([`build_rounds`], all cores, a shuffled order per round,
//! the machine's memory events counted; the best kept and the rounds paired for the ratio
//! to Embree's build and its interval); then one more
//! build per contestant, which it traces with, kept while the memory holds the structures
//! (the contestants built together form a group; one group where memory allows). For each
//! ray set (primary: the scene camera's `N x N` rays in the renderer's tile order;
//! incoherent: seeded random rays in the mesh's box; shadow, ao and diffuse: derived from
//! `bvh`'s primary hits by [`ray_sets::derived`]; or the rays of `--rays-file`) each
//! contestant's untimed pass on all cores counts node visits and primitive tests
//! (contestants that count) and the rays whose answer differs from `bvh`'s; then the closest
//! hits (`intersect_batch`) and the any hits (`occluded_batch`: the any-hit sets' own rays,
//! the others' rays ending at half of `bvh`'s closest hit, where misses keep their `t_max`)
//! are timed on 1 thread and on all cores (a local rayon pool over `chunk`-ray batches) in
//! `repeat` rounds, every contestant of the group once per round in a rotated order, so that
//! a slow phase of the machine lands on all of them rather than on the one whose turn it
//! was; a round the machine interfered with is taken again (the shared rules of
//! `raybench_report::rounds`). The median is kept, and each ratio to Embree is the median of
//! the rounds' ratios with its interval.
//!
//! [`contestants`] says who runs, [`report`] what is written ([`report::Report`], JSON
//! schema `raybench-peers/2`) and printed.

pub mod contestants;
pub mod diff;
pub mod report;

use contestants::Contestant;
use raybench_core::{Hit, Ray, RayCounters, RaySet, Renderer, Scene, ray_sets};
use raybench_registry::interference::{self, MemoryEvents};
use raybench_report::cache_probe;
use raybench_report::rounds::{self, Policy, Repeat, Sample, Tally};
use rayon::ThreadPool;
use rayon::prelude::*;
use report::{
    BuildMemory, ContestantReport, MeshReport, QueryReport, RaySetInfo, Report, Run, SCHEMA,
    SetReport, Skipped, WorkloadInfo,
};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The default meshes: short name and scene spec. Three generated meshes (a closed
/// sphere, a soup of small random triangles, a million-triangle terrain), then the shared
/// meshes users bring: Sponza (Dabrovic's atrium: long thin triangles, many overlapping
/// boxes), the Stanford bunny, and `bunny-field` flattened (144 bunnies and 400 teapots
/// around Sponza, 12.6 million triangles stored flat, so that no level of the tree stays in
/// the caches). The shared meshes need the assets directory; without it they are skipped
/// with the reason, and the run goes on.
pub const MESHES: [(&str, &str); 6] = [
    ("sphere", "icosphere:6"),
    ("soup", "soup:100000"),
    ("terrain", "terrain:708"),
    ("dabrovic-sponza", "dabrovic-sponza"),
    ("bunny", "bunny"),
    ("bunny-field", "flat:bunny-field"),
];

/// The prefix of a mesh spec that asks for the scene flattened (the scene loader's).
pub use raybench_scene::FLAT_PREFIX;

/// The reference every contestant's answers are compared with, and whose closest hits end
/// the any-hit rays.
pub const REFERENCE: &str = "bvh";

/// Any-hit rays end at this fraction of the reference's closest hit.
pub const SHADOW_FRACTION: f32 = 0.5;

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Meshes: short name and scene spec.
    pub meshes: Vec<(String, String)>,
    /// Contestants by name; `None`: all.
    pub contestants: Option<Vec<String>>,
    /// Primary rays: a `primary_size x primary_size` image.
    pub primary_size: u32,
    /// Incoherent rays per mesh.
    pub incoherent_rays: usize,
    /// Seed of the incoherent rays (and of the derived sets' random numbers).
    pub seed: u32,
    /// The ray sets to trace (`--sets`; default: every set, [`RaySet::ALL`]).
    pub sets: Vec<RaySet>,
    /// Ambient-occlusion rays per primary hit of the `ao` set.
    pub ao_rays: u32,
    /// A ray file replayed instead of the ray sets (`--rays-file`, docs/rays-format.md):
    /// one set named `file`, closest hits, and any hits as its flag says.
    pub rays_file: Option<PathBuf>,
    /// Rays per batch call.
    pub chunk: usize,
    /// Timed rounds per figure (the median is kept) and the fewest builds per contestant
    /// (the best is kept).
    pub repeat: usize,
    /// Threads of the "all cores" figures.
    pub threads: usize,
    /// Where the JSON goes.
    pub json: PathBuf,
}

/// What the command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Run the benchmark.
    Run(Options),
    /// Print the usage.
    Help,
    /// List the contestants.
    List,
    /// Time random walks through memory (`raybench_report::cache_probe`) for about this
    /// long each.
    CacheProbe(std::time::Duration),
    /// Set runs' JSON side by side ([`diff`]): the runs before and the runs after (as many,
    /// paired in order), and the reference contestant asked for.
    Diff(Vec<PathBuf>, Vec<PathBuf>, Option<String>),
}

/// The command line's usage.
pub const USAGE: &str = "\
usage: cargo bench -p raybench-tests --bench peers [--features embree] -- [options]

Traces the workload of ../shared/PEERS.md with every exact raybench CPU backend and every
peer: build time, Mrays/s of closest and any hits on 1 thread and on all cores, ratios to
Embree, node visits and primitive tests per ray, differences from `bvh`.

options:
  --quick               256 x 256 primary rays and 65,536 incoherent rays per mesh
  --size N              primary rays: an N x N image (default 1024)
  --rays N              incoherent rays per mesh (default 1048576)
  --sets A,B            ray sets: primary, incoherent, shadow, ao, diffuse (default: all;
                        shadow, ao and diffuse start from the primary rays' hits)
  --ao-rays N           ambient-occlusion rays per primary hit (default 4)
  --rays-file FILE      replay a ray file (raybench rays export) instead of the sets
  --meshes A,B          sphere, soup, terrain, dabrovic-sponza, bunny, bunny-field (default: all),
                        or scene specs; `flat:SCENE` flattens an instanced scene
  --contestants A,B     only these (see --list), or an exact backend's build preset
                        (`packet:ploc`; `raybench backends` lists them); `bvh` is always
                        built as the reference
  --repeat N            timed rounds per figure, every contestant once per round, the
                        median kept (default 5), and the fewest builds, the best kept
                        (meshes that build fast get more, interleaved across contestants)
  --chunk N             rays per intersect_batch / occluded_batch call (default 1024)
  --threads N           threads of the all-cores figures (default: every core)
  --json PATH           where the JSON goes (default: target/raybench-peers.json)
  --list                list the contestants and exit
  --cache-probe         time random walks that fit the L2, fit the last-level cache and
                        miss it, 10 s each, and print how much their samples spread
                        (on a virtual machine whose cache other guests share, the second
                        spreads between the cache's latency and the memory's); then exit
  --diff B1,B2 A1,A2    set runs' JSON side by side (before, after; several pairs are
                        paired in order): per figure, the change of the contestant's
                        speed relative to a reference timed in the same rounds (by default
                        an Embree variant), with an interval and a verdict per pair, and
                        the pairs' geometric mean with a t interval over them; then exit
  --reference NAME      the reference of --diff (a contestant of both runs)
  --help                this text";

/// `target/raybench-peers.json` beside the running benchmark (its executable lives in
/// `target/<profile>/deps`), or `raybench-peers.json` when that cannot be found.
fn default_json() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|exe| {
            exe.ancestors()
                .nth(3)
                .map(|t| t.join("raybench-peers.json"))
        })
        .unwrap_or_else(|| PathBuf::from("raybench-peers.json"))
}

impl Options {
    /// The full workload of `../shared/PEERS.md`.
    #[must_use]
    pub fn full() -> Self {
        Self {
            meshes: MESHES
                .iter()
                .map(|&(n, s)| (n.to_string(), s.to_string()))
                .collect(),
            contestants: None,
            primary_size: 1024,
            incoherent_rays: 1 << 20,
            seed: 1,
            sets: RaySet::ALL.to_vec(),
            ao_rays: ray_sets::DEFAULT_AO_RAYS,
            rays_file: None,
            chunk: 1024,
            repeat: 5,
            threads: std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
            json: default_json(),
        }
    }

    /// Parses the command line (without the program name). `--bench`, which `cargo bench`
    /// passes, is accepted and ignored.
    ///
    /// # Errors
    /// A message naming the bad option and why.
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<Command, String> {
        let mut o = Self::full();
        let mut args = args.into_iter();
        let (mut size, mut rays) = (None, None);
        let (mut runs, mut reference) = (None, None);
        while let Some(arg) = args.next() {
            let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value"));
            let positive = |name: &str, v: String| -> Result<usize, String> {
                v.parse::<usize>()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| format!("{name}: '{v}' is not a positive integer"))
            };
            let list = |v: String| -> Vec<String> {
                v.split(',')
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .map(String::from)
                    .collect()
            };
            match arg.as_str() {
                "--bench" => {}
                "--help" | "-h" => return Ok(Command::Help),
                "--list" => return Ok(Command::List),
                "--cache-probe" => {
                    return Ok(Command::CacheProbe(std::time::Duration::from_secs(10)));
                }
                "--quick" => {
                    o.primary_size = 256;
                    o.incoherent_rays = 65_536;
                }
                "--size" => {
                    let n = positive("--size", value("--size")?)?;
                    size = Some(
                        u32::try_from(n)
                            .ok()
                            .filter(|&n| n <= 16_384)
                            .ok_or_else(|| format!("--size: {n} is above 16384"))?,
                    );
                }
                "--rays" => rays = Some(positive("--rays", value("--rays")?)?),
                "--repeat" => o.repeat = positive("--repeat", value("--repeat")?)?,
                "--chunk" => o.chunk = positive("--chunk", value("--chunk")?)?,
                "--threads" => o.threads = positive("--threads", value("--threads")?)?,
                "--json" => o.json = PathBuf::from(value("--json")?),
                "--diff" => {
                    let paths = |v: String| list(v).into_iter().map(PathBuf::from).collect();
                    let before: Vec<PathBuf> = paths(value("--diff")?);
                    let after: Vec<PathBuf> = paths(value("--diff")?);
                    if before.is_empty() || before.len() != after.len() {
                        return Err(format!(
                            "--diff: {} runs before and {} after; give as many of each, \
                             paired in order",
                            before.len(),
                            after.len()
                        ));
                    }
                    runs = Some((before, after));
                }
                "--reference" => reference = Some(value("--reference")?),
                "--rays-file" => o.rays_file = Some(PathBuf::from(value("--rays-file")?)),
                "--ao-rays" => {
                    let n = positive("--ao-rays", value("--ao-rays")?)?;
                    o.ao_rays = u32::try_from(n)
                        .ok()
                        .filter(|&n| n <= ray_sets::MAX_AO_RAYS)
                        .ok_or_else(|| {
                            format!("--ao-rays: {n} is above {}", ray_sets::MAX_AO_RAYS)
                        })?;
                }
                "--sets" => {
                    o.sets = list(value("--sets")?)
                        .iter()
                        .map(|n| {
                            RaySet::from_name(n)
                                .ok_or_else(|| format!("--sets: unknown ray set '{n}'"))
                        })
                        .collect::<Result<_, _>>()?;
                    if o.sets.is_empty() {
                        return Err("--sets: empty list".into());
                    }
                }
                "--meshes" => {
                    let names = list(value("--meshes")?);
                    if names.is_empty() {
                        return Err("--meshes: empty list".into());
                    }
                    o.meshes = names
                        .into_iter()
                        .map(|n| {
                            let spec = MESHES
                                .iter()
                                .find(|(m, _)| *m == n)
                                .map_or_else(|| n.clone(), |(_, s)| (*s).to_string());
                            (n, spec)
                        })
                        .collect();
                }
                "--contestants" => {
                    let names = list(value("--contestants")?);
                    contestants::select(&names).map_err(|e| format!("--contestants: {e}"))?;
                    o.contestants = Some(names);
                }
                other => return Err(format!("unknown option '{other}' (see --help)")),
            }
        }
        match (runs, reference) {
            (Some((before, after)), reference) => {
                return Ok(Command::Diff(before, after, reference));
            }
            (None, Some(_)) => return Err("--reference is an option of --diff".into()),
            (None, None) => {}
        }
        if let Some(s) = size {
            o.primary_size = s;
        }
        if let Some(r) = rays {
            o.incoherent_rays = r;
        }
        Ok(Command::Run(o))
    }

    /// The contestants to run.
    ///
    /// # Panics
    /// When a name is unknown ([`Options::parse`] checks them).
    #[must_use]
    pub fn selected(&self) -> Vec<Contestant> {
        match &self.contestants {
            None => contestants::all(),
            Some(names) => contestants::select(names).unwrap_or_else(|e| panic!("{e}")),
        }
    }

    /// The thread counts measured: 1 and [`Options::threads`] (once when it is 1).
    #[must_use]
    pub fn thread_counts(&self) -> Vec<usize> {
        if self.threads == 1 {
            vec![1]
        } else {
            vec![1, self.threads]
        }
    }
}

/// One ray set of a mesh with the reference's answers.
pub struct RaySetWork {
    /// The set's name (`primary`, ..., or `file` for `--rays-file`).
    pub name: &'static str,
    /// The rays, for closest hits.
    pub rays: Vec<Ray>,
    /// For any hits: an any-hit set's own rays (`shadow`, `ao`, an any-hit file); else
    /// the rays ending at [`SHADOW_FRACTION`] of the reference's closest hit (misses keep
    /// their `t_max`).
    pub shadow: Vec<Ray>,
    /// The reference's primitive per ray.
    pub closest: Vec<Option<u32>>,
    /// The reference's any-hit answer per shadow ray.
    pub occluded: Vec<bool>,
}

/// A mesh's scene and ray sets: the same for every contestant.
pub struct Workload {
    /// Short name.
    pub name: String,
    /// Scene spec.
    pub spec: String,
    /// The scene.
    pub scene: Arc<Scene>,
    /// The ray sets traced.
    pub sets: Vec<RaySetWork>,
    /// The ray sets asked for that hold no ray here, with why.
    pub skipped_sets: Vec<Skipped>,
}

/// The rays of `set` for `scene`: primary rays in the renderer's tile order
/// ([`ray_sets::primary_tiled`]), seeded incoherent rays ([`ray_sets::incoherent`]), or a
/// set derived from `primary_hits`, the reference's closest hits of the primary rays
/// ([`ray_sets::derived`], seed and `--ao-rays` of `o`; unused for the other sets).
///
/// # Errors
/// A derived set over the ray limit, or hits that are not the primary rays'.
pub fn ray_set(
    scene: &Scene,
    set: RaySet,
    o: &Options,
    primary_hits: &[Option<Hit>],
) -> Result<Vec<Ray>, String> {
    let primary = || {
        ray_sets::primary_tiled(
            &scene.camera,
            o.primary_size,
            o.primary_size,
            raybench_render::TILE_SIZE,
        )
    };
    Ok(match set {
        RaySet::Primary => primary(),
        RaySet::Incoherent => {
            ray_sets::incoherent(scene.geometry.world_bounds(), o.incoherent_rays, o.seed)
        }
        _ => {
            let params = ray_sets::DerivedParams {
                ao_rays: o.ao_rays,
                seed: o.seed,
                ..ray_sets::DerivedParams::default()
            };
            ray_sets::derived(set, scene, &primary(), primary_hits, &params)
                .map_err(|e| e.to_string())?
        }
    })
}

/// The scene of mesh `spec`: loaded from the assets directory, flattened when it starts
/// with [`FLAT_PREFIX`].
///
/// # Errors
/// The loader's or the flattening's error.
pub fn load_mesh(spec: &str) -> Result<Scene, raybench_scene::LoadError> {
    raybench_scene::load(spec, &raybench_scene::assets_dir(None))
}

/// `rays` ending at [`SHADOW_FRACTION`] of `closest`'s `t` (unchanged where it is `None`).
#[must_use]
pub fn shadow_rays(rays: &[Ray], closest: &[Option<Hit>]) -> Vec<Ray> {
    rays.iter()
        .zip(closest)
        .map(|(r, h)| match h {
            Some(h) => Ray::with_interval(r.origin, r.dir, r.t_min, h.t * SHADOW_FRACTION),
            None => *r,
        })
        .collect()
}

/// Answers of one pass: hits or occlusion per ray, and the counters when counted.
struct Pass<T> {
    answers: Vec<T>,
    counters: Option<RayCounters>,
}

/// One untimed pass on the current pool over `chunk`-ray batches: `answers` filled by
/// `trace` (a batch and its counters, when `count`) or by `plain` (a batch, not counting).
fn pass<T: Send>(
    rays: &[Ray],
    mut answers: Vec<T>,
    chunk: usize,
    count: bool,
    trace: impl Fn(&[Ray], &mut [T], &mut RayCounters) + Sync,
    plain: impl Fn(&[Ray], &mut [T]) + Sync,
) -> Pass<T> {
    let counters = if count {
        let parts: Vec<RayCounters> = answers
            .par_chunks_mut(chunk)
            .zip(rays.par_chunks(chunk))
            .map(|(a, r)| {
                let mut c = RayCounters::default();
                trace(r, a, &mut c);
                c
            })
            .collect();
        Some(sum(&parts))
    } else {
        answers
            .par_chunks_mut(chunk)
            .zip(rays.par_chunks(chunk))
            .for_each(|(a, r)| plain(r, a));
        None
    };
    Pass { answers, counters }
}

/// One untimed pass of closest hits on the current pool, counted when `count`.
fn closest_pass(
    tracer: &dyn raybench_core::BatchTracer,
    rays: &[Ray],
    chunk: usize,
    count: bool,
) -> Pass<Option<Hit>> {
    pass(
        rays,
        vec![None; rays.len()],
        chunk,
        count,
        |r, h, c| tracer.trace_batch_counted(r, h, c),
        |r, h| tracer.trace_batch(r, h),
    )
}

/// One untimed pass of any hits on the current pool, counted when `count`.
fn any_pass(
    tracer: &dyn raybench_core::BatchTracer,
    rays: &[Ray],
    chunk: usize,
    count: bool,
) -> Pass<bool> {
    pass(
        rays,
        vec![false; rays.len()],
        chunk,
        count,
        |r, o, c| tracer.occlude_batch_counted(r, o, c),
        |r, o| tracer.occlude_batch(r, o),
    )
}

/// The counters of all chunks, summed in chunk order.
fn sum(parts: &[RayCounters]) -> RayCounters {
    let mut total = RayCounters::default();
    for p in parts {
        raybench_core::Counters::merge(&mut total, p);
    }
    total
}

/// The kept rounds of `n` contestants, `repeat` per contestant ([`rounds::run`]: every
/// contestant once per round in a rotated order, a round the machine interfered with taken
/// again within the redo budget); `pass(i)` runs contestant `i`'s timed pass.
fn timed_rounds(n: usize, repeat: usize, mut pass: impl FnMut(usize)) -> Vec<Tally<()>> {
    let policy = Policy {
        repeat: Repeat::Fixed(u32::try_from(repeat).unwrap_or(u32::MAX)),
        min_sample: 0.0,
        budget: 0.0,
    };
    let tallies = rounds::run(n, &policy, |i| {
        let (seconds, interference) = interference::during(|| {
            let start = Instant::now();
            pass(i);
            start.elapsed().as_secs_f64()
        });
        Ok::<_, std::convert::Infallible>(Sample {
            seconds,
            elapsed: seconds,
            contended: interference.is_some_and(|i| i.contended()),
            extra: (),
        })
    });
    match tallies {
        Ok(t) => t,
        Err(never) => match never {},
    }
}

/// A rayon pool of `threads` workers.
///
/// # Panics
/// When the operating system refuses the threads.
fn pool(threads: usize) -> ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// A prepared renderer of `c` for `scene` and its build time on `pool`, or why it cannot
/// run.
fn build(
    c: &Contestant,
    scene: &Arc<Scene>,
    pool: &ThreadPool,
) -> Result<(Box<dyn Renderer>, f64), String> {
    let mut r = (c.make)();
    r.availability()?;
    r.supports(scene)?;
    let timings = pool
        .install(|| r.prepare(scene))
        .map_err(|e| e.to_string())?;
    Ok((r, timings.get("build").unwrap_or(f64::NAN)))
}

/// Seconds of interleaved builds per mesh after which [`build_rounds`] stops adding
/// rounds (once it has its minimum).
const BUILD_BUDGET_S: f64 = 2.0;

/// The most interleaved build rounds per mesh.
const MAX_BUILD_ROUNDS: usize = 20;

/// A contestant's interleaved builds of one mesh ([`build_rounds`]).
#[derive(Debug)]
struct BuildRounds {
    /// Seconds of each build, in round order.
    seconds: Vec<f64>,
    /// The machine's memory events during its builds; `None` where the system does not
    /// tell.
    memory: Option<MemoryEvents>,
}

/// Per contestant (in order), its builds of `scene` in interleaved rounds on `pool` (each
/// contestant built once per round and dropped, so that a drift of the machine's state
/// during the mesh's builds touches every contestant alike, and two contestants' builds of
/// one round pair up), or why it cannot run. Each round takes the contestants in a freshly
/// shuffled order ([`rounds::shuffled`]), so that none always follows the same one and
/// inherits what it left behind. At least `repeat - 1` rounds (the build that prepares a
/// contestant for tracing adds one more), then more while the rounds so far took under
/// [`BUILD_BUDGET_S`], up to [`MAX_BUILD_ROUNDS`]: small meshes, whose builds take
/// milliseconds and move most from run to run, get many.
///
/// Unlike the traces' rounds, a build the machine interfered with is not taken again: the
/// run-queue test ([`interference::during`]) cannot tell another process from a
/// contestant's own threads, and Embree's and tinybvh's builds run on thread pools of
/// their own that wait on one another (on a quiet 2-vCPU guest, most of tinybvh's builds
/// read as contended). The paired rounds' median and its interval absorb a slow round.
fn build_rounds(
    contestants: &[Contestant],
    scene: &Arc<Scene>,
    pool: &ThreadPool,
    repeat: usize,
) -> Vec<Result<BuildRounds, String>> {
    // Counted from zero where the system tells the events at all.
    let memory = MemoryEvents::now().map(|_| MemoryEvents::default());
    let mut out: Vec<Result<BuildRounds, String>> = contestants
        .iter()
        .map(|_| {
            Ok(BuildRounds {
                seconds: Vec::new(),
                memory,
            })
        })
        .collect();
    let start = Instant::now();
    for round in 0..MAX_BUILD_ROUNDS {
        let enough = round >= repeat.saturating_sub(1);
        if enough && start.elapsed().as_secs_f64() >= BUILD_BUDGET_S {
            break;
        }
        for i in rounds::shuffled(round, contestants.len()) {
            let Ok(b) = &mut out[i] else { continue };
            let before = MemoryEvents::now();
            let built = build(&contestants[i], scene, pool);
            if let (Some(total), Some(before), Some(after)) =
                (&mut b.memory, before, MemoryEvents::now())
            {
                *total += after.since(&before);
            }
            match built {
                Ok((_, s)) => b.seconds.push(s),
                Err(e) => out[i] = Err(e),
            }
        }
    }
    out
}

impl Workload {
    /// Loads mesh `spec` (a generator spec such as `icosphere:6`, any scene raybench
    /// loads, or either behind [`FLAT_PREFIX`] to flatten it) and makes its ray sets, with
    /// the answers of [`REFERENCE`] on `pool`.
    ///
    /// # Errors
    /// When the scene cannot be loaded (its error, naming the spec).
    pub fn generate(
        name: &str,
        spec: &str,
        o: &Options,
        pool: &ThreadPool,
    ) -> Result<Self, String> {
        let scene = load_mesh(spec).map_err(|e| format!("mesh {name} ({spec}): {e}"))?;
        Self::from_scene(name, spec, Arc::new(scene), o, pool)
    }

    /// The ray sets of the loaded mesh `scene`, with the answers of [`REFERENCE`] on
    /// `pool`.
    ///
    /// # Errors
    /// When a ray file cannot be read or a derived set cannot be made.
    pub fn from_scene(
        name: &str,
        spec: &str,
        scene: Arc<Scene>,
        o: &Options,
        pool: &ThreadPool,
    ) -> Result<Self, String> {
        let reference = contestants::all()
            .into_iter()
            .find(|c| c.name == REFERENCE)
            .expect("bvh is registered");
        let (r, _) = build(&reference, &scene, pool)?;
        let tracer = r.batch_tracer().expect("bvh is a CPU structure");
        let mut sources: Vec<(&'static str, Vec<Ray>, bool)> = Vec::new();
        let mut skipped_sets = Vec::new();
        if let Some(path) = &o.rays_file {
            let file = raybench_registry::rays_file::read(path).map_err(|e| e.to_string())?;
            sources.push(("file", file.rays, file.any_hit));
        } else {
            let primary_hits = if o.sets.iter().any(|s| s.is_derived()) {
                let primary = ray_set(&scene, RaySet::Primary, o, &[])?;
                pool.install(|| closest_pass(tracer, &primary, o.chunk, false))
                    .answers
            } else {
                Vec::new()
            };
            for &set in RaySet::ALL.iter().filter(|s| o.sets.contains(s)) {
                let rays = ray_set(&scene, set, o, &primary_hits)
                    .map_err(|e| format!("mesh {name} ({spec}): {e}"))?;
                if rays.is_empty() {
                    // A shadow set without lights, a derived set without primary hits:
                    // no figure to print, so the reason instead.
                    skipped_sets.push(Skipped {
                        name: set.name().to_string(),
                        reason: raybench_registry::measure::no_rays(set, &scene, None),
                    });
                    continue;
                }
                sources.push((set.name(), rays, set.any_hit()));
            }
        }
        let sets = sources
            .into_iter()
            .map(|(name, rays, any_hit)| {
                let hits = pool
                    .install(|| closest_pass(tracer, &rays, o.chunk, false))
                    .answers;
                let shadow = if any_hit {
                    rays.clone()
                } else {
                    shadow_rays(&rays, &hits)
                };
                let occluded = pool
                    .install(|| any_pass(tracer, &shadow, o.chunk, false))
                    .answers;
                RaySetWork {
                    name,
                    closest: hits.iter().map(|h| h.map(|h| h.prim)).collect(),
                    rays,
                    shadow,
                    occluded,
                }
            })
            .collect();
        Ok(Self {
            name: name.to_string(),
            spec: spec.to_string(),
            scene,
            sets,
            skipped_sets,
        })
    }
}

/// Per-ray average of a counter.
fn per_ray(counters: Option<RayCounters>, n: usize, f: impl Fn(RayCounters) -> u64) -> Option<f64> {
    counters.map(|c| f(c) as f64 / n.max(1) as f64)
}

/// A contestant built for tracing: its renderer, the best and the count of its builds, and
/// its [`build_rounds`].
struct Prepared<'a> {
    contestant: &'a Contestant,
    renderer: Box<dyn Renderer>,
    build_s: f64,
    builds: usize,
    rounds: BuildRounds,
}

/// Builds contestant `c` for tracing on `pool`, after `rounds`, its [`build_rounds`] (one
/// more build, which joins them in the best and the count but not
/// in the rounds: it is not paired with the other contestants' builds), or why it cannot
/// trace.
fn prepare<'a>(
    c: &'a Contestant,
    scene: &Arc<Scene>,
    pool: &ThreadPool,
    rounds: BuildRounds,
) -> Result<Prepared<'a>, String> {
    let (renderer, build_s) = build(c, scene, pool)?;
    renderer.batch_tracer().ok_or("not a CPU structure")?;
    Ok(Prepared {
        contestant: c,
        renderer,
        build_s: rounds.seconds.iter().copied().fold(build_s, f64::min),
        builds: rounds.seconds.len() + 1,
        rounds,
    })
}

/// Memory kept free beyond twice the largest structure built so far before another
/// contestant joins a group ([`room_for_another`]): 1 GiB.
const MEMORY_RESERVE: u64 = 1 << 30;

/// Whether another contestant may be built while the group's structures are kept, with
/// `available` bytes free (`None`: unknown, so no) and the largest build so far having
/// taken `largest` bytes: room for twice that (the next contestant's structure is not
/// known in advance) and [`MEMORY_RESERVE`].
fn room_for_another(available: Option<u64>, largest: u64) -> bool {
    available.is_some_and(|a| a >= largest.saturating_mul(2).saturating_add(MEMORY_RESERVE))
}

/// Measures the contestants of `group` on workload `w`: per ray set, each contestant's
/// untimed counted pass on all cores (counters and the rays that differ from `bvh`), then
/// per thread count and query the timed rounds of every contestant of the group
/// ([`timed_rounds`]).
fn measure_group(
    group: &[Prepared<'_>],
    w: &Workload,
    o: &Options,
    pools: &[(usize, ThreadPool)],
) -> Vec<ContestantReport> {
    let all = &pools.last().expect("at least one pool").1;
    let tracers: Vec<&dyn raybench_core::BatchTracer> = group
        .iter()
        .map(|p| p.renderer.batch_tracer().expect("checked by prepare"))
        .collect();
    let mut reports: Vec<ContestantReport> = group
        .iter()
        .map(|p| ContestantReport {
            name: p.contestant.name.to_string(),
            kind: p.contestant.kind,
            build_s: p.build_s,
            builds: p.builds,
            build_rounds_s: p.rounds.seconds.clone(),
            build_memory: p.rounds.memory.map(BuildMemory::from),
            build_vs_embree: None,
            build_ratio: None,
            ray_sets: Vec::new(),
        })
        .collect();
    for s in &w.sets {
        let n = s.rays.len();
        let mut queries: Vec<(QueryReport, QueryReport)> = group
            .iter()
            .zip(&tracers)
            .map(|(p, &tracer)| {
                let count = p.renderer.counts_tests();
                let closest = all.install(|| closest_pass(tracer, &s.rays, o.chunk, count));
                let any = all.install(|| any_pass(tracer, &s.shadow, o.chunk, count));
                let differ_closest = closest
                    .answers
                    .iter()
                    .zip(&s.closest)
                    .filter(|(h, r)| h.map(|h| h.prim) != **r)
                    .count();
                let differ_any = any
                    .answers
                    .iter()
                    .zip(&s.occluded)
                    .filter(|(a, b)| a != b)
                    .count();
                let query = |differ, counters: Option<RayCounters>| QueryReport {
                    runs: Vec::new(),
                    differ,
                    node_visits_per_ray: per_ray(counters, n, |c| c.node_visits),
                    prim_tests_per_ray: per_ray(counters, n, |c| c.prim_tests),
                    ratios: Vec::new(),
                };
                (
                    query(differ_closest, closest.counters),
                    query(differ_any, any.counters),
                )
            })
            .collect();
        for (threads, pool) in pools {
            let mut hits = vec![None; n];
            let closest = timed_rounds(group.len(), o.repeat, |i| {
                pool.install(|| {
                    hits.par_chunks_mut(o.chunk)
                        .zip(s.rays.par_chunks(o.chunk))
                        .for_each(|(h, r)| tracers[i].trace_batch(r, h));
                });
                std::hint::black_box(&hits);
            });
            let mut occluded = vec![false; n];
            let any = timed_rounds(group.len(), o.repeat, |i| {
                pool.install(|| {
                    occluded
                        .par_chunks_mut(o.chunk)
                        .zip(s.shadow.par_chunks(o.chunk))
                        .for_each(|(a, r)| tracers[i].occlude_batch(r, a));
                });
                std::hint::black_box(&occluded);
            });
            for ((q, c), a) in queries.iter_mut().zip(&closest).zip(&any) {
                q.0.runs.push(Run::of(*threads, n, c));
                q.1.runs.push(Run::of(*threads, n, a));
            }
        }
        for (r, (closest, any)) in reports.iter_mut().zip(queries) {
            r.ray_sets.push(SetReport {
                name: s.name,
                closest,
                any,
            });
        }
    }
    reports
}

/// Measures `group` ([`measure_group`]) into `mesh` and empties it (dropping its
/// structures).
fn measure_and_report(
    group: &mut Vec<Prepared<'_>>,
    w: &Workload,
    o: &Options,
    pools: &[(usize, ThreadPool)],
    mesh: &mut MeshReport,
) {
    if group.is_empty() {
        return;
    }
    let start = Instant::now();
    let names: Vec<String> = group
        .iter()
        .map(|p| p.contestant.name.to_string())
        .collect();
    mesh.contestants.extend(measure_group(group, w, o, pools));
    eprintln!("  {} measured in {:.1?}", names.join(", "), start.elapsed());
    mesh.groups.push(names);
    group.clear();
}

/// Embree's version, or why it is absent.
fn embree_description() -> String {
    #[cfg(feature = "embree")]
    {
        raybench_peers::embree_version().unwrap_or_else(|e| format!("absent: {e}"))
    }
    #[cfg(not(feature = "embree"))]
    {
        "absent: built without the cargo feature `embree`".to_string()
    }
}

/// How long the last-level cache's walk is timed before and after a run
/// ([`Report::cache`]).
const CACHE_PROBE_TIME: std::time::Duration = std::time::Duration::from_secs(1);

/// Runs the benchmark, printing progress to stderr and calling `on_mesh` with the report
/// so far after each mesh (the caller prints and saves as it goes, so an interrupted run
/// keeps the meshes it finished).
///
/// # Errors
/// When a mesh cannot be loaded, or as `on_mesh`.
pub fn run(
    o: &Options,
    mut on_mesh: impl FnMut(&Report) -> Result<(), String>,
) -> Result<Report, String> {
    let threads = o.thread_counts();
    let mut report = Report {
        schema: SCHEMA,
        machine: raybench_report::machine::describe(o.threads),
        packet_isa: raybench_packet::Isa::detect().name().to_string(),
        embree: embree_description(),
        workload: WorkloadInfo {
            primary_size: o.primary_size,
            tile: raybench_render::TILE_SIZE,
            incoherent_rays: o.incoherent_rays,
            seed: o.seed,
            chunk: o.chunk,
            repeat: o.repeat,
            threads: threads.clone(),
            shadow_fraction: SHADOW_FRACTION,
        },
        meshes: Vec::new(),
        skipped_meshes: Vec::new(),
        cache: [Some(cache_probe::last_level(CACHE_PROBE_TIME)), None],
    };
    let pools: Vec<(usize, ThreadPool)> = threads.iter().map(|&t| (t, pool(t))).collect();
    let all = &pools.last().expect("at least one pool").1;
    let contestants = o.selected();
    for (name, spec) in &o.meshes {
        let start = Instant::now();
        let scene = match load_mesh(spec) {
            Ok(scene) => Arc::new(scene),
            // A shared mesh without the assets directory, or a scene this machine's memory
            // cannot hold flattened: skipped with the reason, the other meshes still run.
            Err(e) if e.is_missing_asset() || e.is_over_budget() => {
                eprintln!("{name} ({spec}) skipped: {e}");
                report.skipped_meshes.push(Skipped {
                    name: name.clone(),
                    reason: e.to_string(),
                });
                continue;
            }
            Err(e) => return Err(format!("mesh {name} ({spec}): {e}")),
        };
        let w = Workload::from_scene(name, spec, scene, o, all)?;
        eprintln!(
            "{name} ({spec}): {} primitives, ray sets and reference in {:.1?}",
            w.scene.geometry.len(),
            start.elapsed()
        );
        let mut mesh = MeshReport {
            name: name.clone(),
            spec: spec.clone(),
            triangles: w.scene.geometry.len(),
            ray_sets: w
                .sets
                .iter()
                .map(|s| RaySetInfo {
                    name: s.name,
                    rays: s.rays.len(),
                    hits: s.closest.iter().filter(|h| h.is_some()).count(),
                })
                .collect(),
            skipped: Vec::new(),
            skipped_sets: w.skipped_sets.clone(),
            groups: Vec::new(),
            contestants: Vec::new(),
        };
        let start = Instant::now();
        let builds = build_rounds(&contestants, &w.scene, all, o.repeat);
        eprintln!("  builds in {:.1?}", start.elapsed());
        // Contestants are kept built while the memory holds them, and each group is timed
        // in the same rounds.
        let mut group: Vec<Prepared<'_>> = Vec::new();
        let mut largest = 0u64;
        for (c, builds) in contestants.iter().zip(builds) {
            if !group.is_empty() && !room_for_another(raybench_scene::available_memory(), largest) {
                measure_and_report(&mut group, &w, o, &pools, &mut mesh);
            }
            let before = raybench_scene::available_memory();
            match builds.and_then(|b| prepare(c, &w.scene, all, b)) {
                Ok(p) => {
                    let after = raybench_scene::available_memory();
                    if let (Some(before), Some(after)) = (before, after) {
                        largest = largest.max(before.saturating_sub(after));
                    }
                    group.push(p);
                }
                Err(reason) => {
                    eprintln!("  {} skipped: {reason}", c.name);
                    mesh.skipped.push(Skipped {
                        name: c.name.to_string(),
                        reason,
                    });
                }
            }
        }
        measure_and_report(&mut group, &w, o, &pools, &mut mesh);
        mesh.compute_ratios();
        report.meshes.push(mesh);
        on_mesh(&report)?;
    }
    report.cache[1] = Some(cache_probe::last_level(CACHE_PROBE_TIME));
    Ok(report)
}

/// Writes `report` as JSON to `path`, creating its directory: compact, on one line (every
/// round of every figure makes a full run's indented file over a megabyte; the tables are
/// the form to read, `jq .` indents it).
///
/// # Errors
/// The path and the I/O error.
pub fn write_json(report: &Report, path: &std::path::Path) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let text = serde_json::to_string(report).map_err(|e| e.to_string())?;
    std::fs::write(path, text + "\n").map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Another contestant is built beside a group's structures only where the memory is
    /// known and holds twice the largest structure so far and the reserve.
    #[test]
    fn groups_grow_while_the_memory_holds_them() {
        let gib = 1 << 30;
        assert!(room_for_another(Some(3 * gib), gib));
        assert!(!room_for_another(Some(3 * gib - 1), gib));
        assert!(room_for_another(Some(MEMORY_RESERVE), 0));
        assert!(!room_for_another(None, 0));
        assert!(!room_for_another(Some(u64::MAX - 1), u64::MAX));
    }
}
