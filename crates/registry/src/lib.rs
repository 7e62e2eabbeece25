//! # raybench-registry
//!
//! The backend registry (names to [`Renderer`]s, with their roles) and the services every
//! front end shares: the frame comparison used by `raybench compare`, the harness and the
//! cross-backend equivalence tests; measurement ([`measure`]), backend presets
//! ([`presets`]), progress lines ([`progress`]), frame sequences ([`frames`]) and ray files
//! ([`rays_file`]). The command line is the `raybench` crate; the harness that times and
//! reports is `raybench-report`.

pub mod frames;
pub mod interference;
pub mod measure;
pub mod presets;
pub mod progress;
pub mod rays_file;
mod timed;

pub use timed::{OccludedRays, TimedRenderer, TracedRays};

/// The version and the source revision it was built from (`0.1.0 (3f2a9c1)`; `unknown`
/// outside a git checkout, see `build.rs`): what `raybench --version` prints and every
/// report records.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("RAYBENCH_REVISION"),
    ")"
);

/// How this binary was compiled (`rustc 1.x.y (...), opt-level 3, debug assertions off,
/// x86_64-unknown-linux-gnu, RUSTFLAGS none`; see `build.rs`): what every report's
/// reproducibility block records beside the revision.
pub const BUILD: &str = env!("RAYBENCH_BUILD");

use raybench_bvh::{Bvh, ObvhsAccel};
use raybench_core::{Frame, Mode, NO_HIT, RaySet, RenderSettings};
use raybench_grid::{Grid, TwoLevelGrid};
use raybench_naive::NaiveAccel;
use raybench_packet::{Isa, PacketAccel, PacketParams};
use raybench_peers::BvhCrateAccel;
#[cfg(feature = "embree")]
use raybench_peers::{EmbreeAccel, EmbreePacketAccel, embree_availability, embree_supports};
use raybench_render::CpuRenderer;
use raybench_wgpu::{Layout, WgpuRenderer};

/// What a backend is for: the flags the report, `compare`, `info`, the machine description
/// and the tests read, instead of testing backend names. A backend has any number of them
/// ([`Roles::with`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Roles(u16);

impl Roles {
    /// No role: an accelerated backend outside the contract that is neither a peer nor on
    /// another device.
    pub const NONE: Roles = Roles(0);
    /// Bound by the equivalence contract (bit-identical ids and `t` to the oracle):
    /// `compare` exits with status 3 when such a backend disagrees, the report demands
    /// identical frames, and the tests run every exact backend (`raybench_tests::EXACT_BACKENDS`).
    pub const EXACT: Roles = Roles(1);
    /// The oracle: the reference every other backend is compared with (naive). Listed first.
    pub const ORACLE: Roles = Roles(1 << 1);
    /// Tests every primitive for every ray: left out of large default lists and of scaling
    /// points over its time budget.
    pub const BRUTE_FORCE: Roles = Roles(1 << 2);
    /// The baseline structure: the report's reference where the oracle is over its budget,
    /// and the one backend of the experiments that compare two representations of a
    /// surface (`heightfield`, `bezier`).
    pub const BASELINE: Roles = Roles(1 << 3);
    /// A variant of another backend with one parameter pinned (the instruction set): run
    /// only when named, never in a default list.
    pub const PINNED: Roles = Roles(1 << 4);
    /// Runs on another device (the GPU): the machine description names its adapter, and
    /// the tests compare it with the oracle within tolerances.
    pub const DEVICE: Roles = Roles(1 << 5);
    /// Someone else's structure or library (a peer): compared within tolerance, its ties
    /// counted rather than forbidden.
    pub const PEER: Roles = Roles(1 << 6);
    /// A peer the report states every backend's throughput against (Embree).
    pub const YARDSTICK: Roles = Roles(1 << 7);
    /// The representative of SIMD tracing (packets over a wide tree; its pinned variants
    /// do not carry it): the experiments that compare a few representative structures
    /// (`instancing`) take it beside the baseline and the yardstick.
    pub const SIMD: Roles = Roles(1 << 8);
    /// A grid walked cell by cell (3D-DDA): a ray crosses about M^(1/3) cells of a grid
    /// sized to M primitives, so the report's scaling judges its time against that power
    /// law, not against a tree's logarithm.
    pub const GRID: Roles = Roles(1 << 9);

    /// Every role with its name, in the order `raybench backends --json` lists them.
    pub const NAMED: [(Roles, &'static str); 10] = [
        (Roles::EXACT, "exact"),
        (Roles::ORACLE, "oracle"),
        (Roles::BRUTE_FORCE, "brute-force"),
        (Roles::BASELINE, "baseline"),
        (Roles::PINNED, "pinned"),
        (Roles::DEVICE, "device"),
        (Roles::PEER, "peer"),
        (Roles::YARDSTICK, "yardstick"),
        (Roles::SIMD, "simd"),
        (Roles::GRID, "grid"),
    ];

    /// These roles and `other`'s.
    #[must_use]
    pub const fn with(self, other: Roles) -> Roles {
        Roles(self.0 | other.0)
    }

    /// Whether every role of `other` is among these.
    #[must_use]
    pub const fn contains(self, other: Roles) -> bool {
        self.0 & other.0 == other.0
    }

    /// The names of these roles ([`Roles::NAMED`]).
    #[must_use]
    pub fn names(self) -> Vec<&'static str> {
        Roles::NAMED
            .iter()
            .filter(|(r, _)| self.contains(*r))
            .map(|(_, n)| *n)
            .collect()
    }
}

/// A registered backend.
#[derive(Clone, Copy, Debug)]
pub struct Backend {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// What it is for (exact, oracle, brute force, pinned variant, device, peer, ...).
    pub roles: Roles,
    /// What it chose on this machine, for the report's machine description (the packet
    /// backend's instruction set and lanes: `avx2 (8 lanes)`); `None` for most.
    pub detail: Option<fn() -> String>,
    /// Makes a fresh, unprepared renderer.
    pub make: fn() -> Box<dyn TimedRenderer>,
}

impl Backend {
    /// Whether it has every role of `roles`.
    #[must_use]
    pub const fn is(&self, roles: Roles) -> bool {
        self.roles.contains(roles)
    }

    /// Whether it is bound by the equivalence contract ([`Roles::EXACT`]).
    #[must_use]
    pub const fn exact(&self) -> bool {
        self.is(Roles::EXACT)
    }
}

/// The number of backends with every role of `roles` (for [`names_with`]'s array length).
#[must_use]
pub const fn count_with(roles: Roles) -> usize {
    let (mut i, mut n) = (0, 0);
    while i < BACKENDS.len() {
        if BACKENDS[i].is(roles) {
            n += 1;
        }
        i += 1;
    }
    n
}

/// The names of the backends with every role of `roles`, in registry order (so the oracle
/// first), at compile time: `N` must be [`count_with`]`(roles)`.
///
/// # Panics
/// At compile time, when `N` is not that count.
#[must_use]
pub const fn names_with<const N: usize>(roles: Roles) -> [&'static str; N] {
    assert!(N == count_with(roles), "N must be count_with(roles)");
    let mut out = [""; N];
    let (mut i, mut n) = (0, 0);
    while i < BACKENDS.len() {
        if BACKENDS[i].is(roles) {
            out[n] = BACKENDS[i].name;
            n += 1;
        }
        i += 1;
    }
    out
}

/// Whether the backend called `name` has every role of `roles`, at compile time (false for
/// an unknown name).
#[must_use]
pub const fn backend_is(name: &str, roles: Roles) -> bool {
    let mut i = 0;
    while i < BACKENDS.len() {
        if same(BACKENDS[i].name.as_bytes(), name.as_bytes()) {
            return BACKENDS[i].is(roles);
        }
        i += 1;
    }
    false
}

/// Byte equality at compile time.
const fn same(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The roles of the backend called `name`, built ([`BACKENDS`], [`presets::PRESETS`]) or
/// not ([`NOT_BUILT`]).
#[must_use]
pub fn roles_of(name: &str) -> Option<Roles> {
    BACKENDS
        .iter()
        .find(|b| b.name == name)
        .map(|b| b.roles)
        .or_else(|| backend(name).ok().map(|b| b.roles))
        .or_else(|| NOT_BUILT.iter().find(|n| n.name == name).map(|n| n.roles))
}

/// The device backends' adapter when it is a software one that runs on the CPU (Mesa's
/// lavapipe where there is no GPU): its description; `None` for a GPU or no adapter
/// ([`raybench_wgpu::software_adapter`]).
#[must_use]
pub fn software_device() -> Option<String> {
    raybench_wgpu::software_adapter()
}

/// The first backend (in registry order) with every role of `roles`, if any.
#[must_use]
pub fn with_role(roles: Roles) -> Option<&'static Backend> {
    BACKENDS.iter().find(|b| b.is(roles))
}

/// The name of the first backend with every role of `roles`, at compile time (`""` when
/// there is none).
#[must_use]
pub const fn name_with(roles: Roles) -> &'static str {
    let mut i = 0;
    while i < BACKENDS.len() {
        if BACKENDS[i].is(roles) {
            return BACKENDS[i].name;
        }
        i += 1;
    }
    ""
}

const NAIVE: &str = "every ray tests every primitive (the oracle)";
const BVH: &str =
    "own binned-SAH BVH2, 32-byte depth-first nodes, near-child-first stack traversal";
const OBVHS: &str = "obvhs crate: PLOC + reinsertion, compressed wide CWBVH8, obvhs traversal";
const GRID: &str = "uniform grid walked by 3D-DDA (ray marching), mailboxing";
const GRID2: &str = "two-level grid: crowded cells hold their own grid";
const PACKET: &str = "SIMD over a BVH8 collapsed by SAH, leaves of 4-triangle blocks: 64-ray packets for coherent rays, single rays otherwise (four interleaved where the BVH8 exceeds the last-level cache) (AVX2, SSE4.1 or portable, picked at run time; RAYBENCH_ISA overrides)";

/// Every backend, the oracle (naive) first.
///
/// A `static`, not a `const`: a constant is evaluated again in every crate that uses it, and
/// the `make` functions it points to (each backend's renderer, every integrator over its
/// structure) would be compiled again in each of them (the command line, the report, the
/// tests): a fifth of the test build's compiler time, measured. A static is compiled once, here.
pub static BACKENDS: &[Backend] = &[
    Backend {
        name: "naive",
        description: NAIVE,
        roles: Roles::EXACT.with(Roles::ORACLE).with(Roles::BRUTE_FORCE),
        detail: None,
        make: || {
            Box::new(CpuRenderer::<NaiveAccel>::with_default_build(
                "naive", NAIVE,
            ))
        },
    },
    Backend {
        name: "bvh",
        description: BVH,
        roles: Roles::EXACT.with(Roles::BASELINE),
        detail: None,
        make: || Box::new(CpuRenderer::<Bvh>::with_default_build("bvh", BVH)),
    },
    Backend {
        name: "obvhs",
        description: OBVHS,
        roles: Roles::EXACT,
        detail: None,
        make: || {
            Box::new(CpuRenderer::<ObvhsAccel>::with_default_build(
                "obvhs", OBVHS,
            ))
        },
    },
    Backend {
        name: "grid",
        description: GRID,
        roles: Roles::EXACT.with(Roles::GRID),
        detail: None,
        make: || Box::new(CpuRenderer::<Grid>::with_default_build("grid", GRID)),
    },
    Backend {
        name: "grid2",
        description: GRID2,
        roles: Roles::EXACT.with(Roles::GRID),
        detail: None,
        make: || {
            Box::new(CpuRenderer::<TwoLevelGrid>::with_default_build(
                "grid2", GRID2,
            ))
        },
    },
    Backend {
        name: "packet",
        description: PACKET,
        roles: Roles::EXACT.with(Roles::SIMD),
        detail: Some(packet_detail),
        make: || {
            Box::new(CpuRenderer::<PacketAccel>::with_default_build(
                "packet", PACKET,
            ))
        },
    },
    Backend {
        name: "packet-sse4.1",
        description: PACKET_SSE41,
        roles: Roles::EXACT.with(Roles::PINNED),
        detail: None,
        make: || packet_with(Isa::Sse41, "packet-sse4.1", PACKET_SSE41),
    },
    Backend {
        name: "packet-avx512",
        description: PACKET_AVX512,
        roles: Roles::EXACT.with(Roles::PINNED),
        detail: None,
        make: || packet_with(Isa::Avx512, "packet-avx512", PACKET_AVX512),
    },
    Backend {
        name: "packet-portable",
        description: PACKET_PORTABLE,
        roles: Roles::EXACT.with(Roles::PINNED),
        detail: None,
        make: || packet_with(Isa::Portable, "packet-portable", PACKET_PORTABLE),
    },
    Backend {
        name: "bvh-crate",
        description: BVH_CRATE,
        roles: Roles::PEER,
        detail: None,
        make: || {
            Box::new(CpuRenderer::<BvhCrateAccel>::with_default_build(
                "bvh-crate",
                BVH_CRATE,
            ))
        },
    },
    Backend {
        name: "wgpu",
        description: WGPU,
        roles: Roles::DEVICE,
        detail: None,
        make: || Box::new(WgpuRenderer::new("wgpu", WGPU)),
    },
    Backend {
        name: "wgpu-cwbvh",
        description: WGPU_CWBVH,
        roles: Roles::DEVICE,
        detail: None,
        make: || Box::new(WgpuRenderer::new("wgpu-cwbvh", WGPU_CWBVH).with_layout(Layout::Cwbvh)),
    },
    #[cfg(feature = "embree")]
    Backend {
        name: "embree",
        description: EMBREE,
        roles: Roles::PEER.with(Roles::YARDSTICK),
        detail: None,
        make: || {
            Box::new(
                CpuRenderer::<EmbreeAccel>::with_default_build("embree", EMBREE)
                    .with_availability(embree_availability)
                    .with_support_check(embree_supports)
                    .without_test_counts(),
            )
        },
    },
    #[cfg(feature = "embree")]
    Backend {
        name: "embree-packet",
        description: EMBREE_PACKET,
        roles: Roles::PEER.with(Roles::YARDSTICK),
        detail: None,
        make: || {
            Box::new(
                CpuRenderer::<EmbreePacketAccel>::with_default_build(
                    "embree-packet",
                    EMBREE_PACKET,
                )
                .with_availability(embree_availability)
                .with_support_check(embree_supports)
                .without_test_counts(),
            )
        },
    },
];

const WGPU: &str = "GPU: WGSL compute kernels over the CPU-built BVH2 (wgpu; WGPU_BACKEND and WGPU_ADAPTER_NAME pick the adapter; within tolerance, not exact)";

const WGPU_CWBVH: &str = "GPU: the wgpu kernels over a compressed 8-wide BVH (raybench-bvh's BVH2 collapsed, quantised child boxes, Ylitie et al. 2017; within tolerance, not exact)";

const BVH_CRATE: &str = "peer: svenstaro's bvh crate's tree, own stack traversal, raybench's primitive tests (not exact)";
const EMBREE: &str =
    "peer: Intel Embree 3, rtcIntersect1 per ray, Embree's own triangle test (not exact)";
const EMBREE_PACKET: &str = "peer: Intel Embree 3, rtcIntersect16 on 16-ray packets, Embree's own triangle test (not exact)";

const PACKET_SSE41: &str = "packet forced to SSE4.1 (4 lanes, 8-ray packets)";
const PACKET_AVX512: &str = "packet with AVX-512F packets (16 lanes, 64-ray packets; AVX2 for single rays), a measured extra";
const PACKET_PORTABLE: &str = "packet forced to portable code (4 plain f32 lanes, no intrinsics)";

/// The instruction set the packet backend picks on this CPU and its lanes, for the
/// machine description ([`Backend::detail`]).
fn packet_detail() -> String {
    let isa = Isa::detect();
    format!("{} ({} lanes)", isa.name(), isa.lanes())
}

/// The packet backend pinned to `isa`, unavailable where the CPU lacks it.
fn packet_with(isa: Isa, name: &'static str, description: &'static str) -> Box<dyn TimedRenderer> {
    let check = match isa {
        Isa::Sse41 => || {
            Isa::Sse41
                .is_available()
                .then_some(())
                .ok_or_else(|| "this CPU has no SSE4.1".to_string())
        },
        Isa::Avx512 => || {
            Isa::Avx512
                .is_available()
                .then_some(())
                .ok_or_else(|| "this CPU has no AVX-512F".to_string())
        },
        _ => || Ok(()),
    };
    Box::new(
        CpuRenderer::<PacketAccel>::new(
            name,
            description,
            Box::new(move |g| {
                PacketAccel::build_with(
                    g,
                    PacketParams {
                        isa,
                        ..PacketParams::default()
                    },
                )
            }),
        )
        .with_availability(check),
    )
}

/// A backend that exists only with a cargo feature this build was compiled without.
#[derive(Clone, Copy, Debug)]
pub struct NotBuilt {
    /// The name it has when built.
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// The cargo feature of the `raybench` package that builds it.
    pub feature: &'static str,
    /// What the feature needs on the system.
    pub needs: &'static str,
    /// The roles it has when built (so that a report merged by a build without it still
    /// reads them).
    pub roles: Roles,
}

impl NotBuilt {
    /// Why it is unavailable, and how to build it.
    #[must_use]
    pub fn reason(&self) -> String {
        format!(
            "not compiled in: build with the cargo feature `{}` (cargo build --release -p \
             raybench --features {}; needs {})",
            self.feature, self.feature, self.needs
        )
    }
}

/// The backends of [`BACKENDS`] that this build lacks, with the feature that adds them
/// (`raybench backends` lists them as unavailable).
pub const NOT_BUILT: &[NotBuilt] = &[
    #[cfg(not(feature = "embree"))]
    NotBuilt {
        name: "embree",
        description: EMBREE,
        feature: "embree",
        needs: EMBREE_NEEDS,
        roles: Roles::PEER.with(Roles::YARDSTICK),
    },
    #[cfg(not(feature = "embree"))]
    NotBuilt {
        name: "embree-packet",
        description: EMBREE_PACKET,
        feature: "embree",
        needs: EMBREE_NEEDS,
        roles: Roles::PEER.with(Roles::YARDSTICK),
    },
];

/// The system library the Embree backends link.
#[cfg(not(feature = "embree"))]
const EMBREE_NEEDS: &str = "the system library libembree3; Debian: apt install libembree-dev";

/// Backends in order of preference for `render` without `--backend` (fastest first).
pub const PREFERENCE: &[&str] = &["packet", "bvh", "obvhs", "grid2", "grid", "naive"];

/// The backend called `name`, or the preset `BACKEND:PRESET` ([`presets::PRESETS`]).
///
/// # Errors
/// A message listing the known backends (or the backend's known presets).
pub fn backend(name: &str) -> Result<&'static Backend, String> {
    if let Some(preset) = presets::preset_backend(name) {
        return preset;
    }
    BACKENDS.iter().find(|b| b.name == name).ok_or_else(|| {
        if let Some(n) = NOT_BUILT.iter().find(|n| n.name == name) {
            return format!("backend '{name}' is {}", n.reason());
        }
        let names: Vec<_> = BACKENDS.iter().map(|b| b.name).collect();
        format!("unknown backend '{name}' (known: {})", names.join(", "))
    })
}

/// Rough rays per sample of a mode (camera, secondary and shadow rays), for the
/// brute-force budgets.
#[must_use]
pub fn rays_per_sample(mode: Mode) -> f64 {
    match mode {
        Mode::Cast | Mode::Mip | Mode::Composite => 1.0,
        Mode::Whitted => 3.0,
        Mode::Path => 4.0,
    }
}

/// Estimated ray/primitive tests of a brute-force backend (every ray tests every one of
/// `prims` primitives) over `frames` frames of `settings` (primary rays) or `frames`
/// passes over explicit rays: `width x height` incoherent or diffuse rays, twice that many
/// shadow rays, the default `--ao-rays` times as many ambient-occlusion rays.
#[must_use]
pub fn brute_force_tests(
    settings: &RenderSettings,
    rays: RaySet,
    prims: usize,
    frames: u32,
) -> f64 {
    let pixels = f64::from(settings.width) * f64::from(settings.height);
    let per_frame = match rays {
        RaySet::Primary => pixels * f64::from(settings.spp) * rays_per_sample(settings.mode),
        RaySet::Incoherent | RaySet::Diffuse => pixels,
        // One light and one emitter sample per hit, at most one hit per pixel.
        RaySet::Shadow => 2.0 * pixels,
        RaySet::Ao => f64::from(raybench_core::ray_sets::DEFAULT_AO_RAYS) * pixels,
    };
    per_frame * prims as f64 * f64::from(frames)
}

/// Estimated tests ([`brute_force_tests`]) above which `compare` and `info` leave a
/// brute-force backend out of their default lists.
pub const BRUTE_FORCE_BUDGET_TESTS: f64 = 2.0e9;

/// The backends named (a comma list from the command line), or by default every backend
/// but the pinned variants, leaving brute-force ones out (with a message on stderr) when
/// `work` estimated tests exceed [`BRUTE_FORCE_BUDGET_TESTS`]: what `compare` and `info`
/// run.
///
/// # Errors
/// An unknown name.
pub fn chosen_backends(
    names: Option<&[String]>,
    work: f64,
) -> Result<Vec<&'static Backend>, String> {
    if let Some(names) = names {
        return names.iter().map(|n| backend(n.trim())).collect();
    }
    Ok(BACKENDS
        .iter()
        .filter(|b| !b.is(Roles::PINNED))
        .filter(|b| {
            let keep = !b.is(Roles::BRUTE_FORCE) || work <= BRUTE_FORCE_BUDGET_TESTS;
            if !keep {
                eprintln!(
                    "leaving {} out: about {work:.1e} ray/primitive tests (pass --backends {} \
                     to force)",
                    b.name, b.name
                );
            }
            keep
        })
        .collect())
}

/// The fastest available backend.
#[must_use]
pub fn default_backend() -> &'static Backend {
    PREFERENCE
        .iter()
        .filter_map(|n| backend(n).ok())
        .find(|b| (b.make)().availability().is_ok())
        .unwrap_or(&BACKENDS[0])
}

/// How a frame differs from a reference frame of the same size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Fraction of pixels (0..1) whose primitive id equals the reference's.
    pub id_match: f64,
    /// Pixels hit in one frame and missed in the other.
    pub hit_mismatch: u64,
    /// Largest `|t - t_ref|` over pixels where both hit the same primitive (0 when none).
    pub max_abs_dt: f64,
    /// Pixels whose id is equal but whose `t` differs in any bit.
    pub t_mismatch: u64,
    /// Rays where both hit different primitives at the same distance (within
    /// [`TIE_TOLERANCE`] relative): a tie between coincident surfaces, decided by each
    /// backend's own tie rule rather than a wrong hit.
    pub tie_mismatch: u64,
    /// Largest `|t - t_ref| / |t_ref|` where the ids agree (the GPU's tolerance).
    pub max_rel_dt: f64,
}

/// Relative `t` difference under which two different primitives hit by the same ray count
/// as a tie ([`Comparison::tie_mismatch`]).
pub const TIE_TOLERANCE: f64 = 1e-4;

impl Comparison {
    /// True when ids and `t` are bit-identical.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.id_match == 1.0 && self.t_mismatch == 0
    }
}

/// Compares the id and `t` buffers of `frame` with those of `reference`.
///
/// # Panics
/// When the frames differ in size.
#[must_use]
pub fn compare_frames(reference: &Frame, frame: &Frame) -> Comparison {
    compare_hits(&reference.ids, &reference.t, &frame.ids, &frame.t)
}

/// Compares per-ray primitive ids and `t` (as in a frame's buffers: [`NO_HIT`] and
/// infinity for misses) with reference ones.
///
/// # Panics
/// When the lengths differ.
#[must_use]
pub fn compare_hits(ref_ids: &[u32], ref_t: &[f32], ids: &[u32], t: &[f32]) -> Comparison {
    assert_eq!(ref_ids.len(), ids.len(), "hit buffers differ in size");
    let n = ref_ids.len();
    let mut same = 0u64;
    let mut hit_mismatch = 0u64;
    let mut max_abs_dt = 0.0f64;
    let mut t_mismatch = 0u64;
    let mut tie_mismatch = 0u64;
    let mut max_rel_dt = 0.0f64;
    for i in 0..n {
        let (a, b) = (ref_ids[i], ids[i]);
        if a == b {
            same += 1;
            if a != NO_HIT {
                let (ta, tb) = (ref_t[i], t[i]);
                if ta.to_bits() != tb.to_bits() {
                    t_mismatch += 1;
                }
                let dt = (f64::from(ta) - f64::from(tb)).abs();
                max_abs_dt = max_abs_dt.max(dt);
                if dt > 0.0 {
                    max_rel_dt = max_rel_dt.max(dt / f64::from(ta).abs());
                }
            }
        } else if (a == NO_HIT) != (b == NO_HIT) {
            hit_mismatch += 1;
        } else {
            let (ta, tb) = (f64::from(ref_t[i]), f64::from(t[i]));
            if (ta - tb).abs() <= TIE_TOLERANCE * ta.abs().max(tb.abs()) {
                tie_mismatch += 1;
            }
        }
    }
    Comparison {
        id_match: if n == 0 { 1.0 } else { same as f64 / n as f64 },
        hit_mismatch,
        max_abs_dt,
        t_mismatch,
        tie_mismatch,
        max_rel_dt,
    }
}

#[cfg(test)]
mod revision_tests {
    use std::path::Path;
    use std::process::Command;

    /// The exit code and the trimmed output of `git ARGS` in the workspace; `None` when git
    /// cannot run or is ended by a signal.
    fn git(args: &[&str]) -> Option<(i32, String)> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let out = Command::new("git")
            .current_dir(root)
            .args(args)
            .output()
            .ok()?;
        Some((
            out.status.code()?,
            String::from_utf8_lossy(&out.stdout).trim().to_string(),
        ))
    }

    /// `VERSION` names the checkout's commit, marked `-dirty` exactly when the sources
    /// differ from it: a report's revision says whether it is the committed code.
    #[test]
    fn version_names_the_commit_and_marks_a_dirty_tree() {
        if std::env::var_os("RAYBENCH_REVISION").is_some() {
            eprintln!("skipped: RAYBENCH_REVISION names the revision");
            return;
        }
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let top =
            git(&["rev-parse", "--show-toplevel"]).map(|(_, top)| Path::new(&top).canonicalize());
        let (Some(Ok(top)), Ok(root)) = (top, root.canonicalize()) else {
            eprintln!(
                "skipped: not built from a git checkout (VERSION is {})",
                super::VERSION
            );
            return;
        };
        if top != root {
            eprintln!(
                "skipped: the workspace is inside another repository (VERSION is {})",
                super::VERSION
            );
            return;
        }
        let Some((0, hash)) = git(&["rev-parse", "--short", "HEAD"]) else {
            panic!("git rev-parse HEAD failed in a checkout");
        };
        let Some((code @ (0 | 1), _)) = git(&[
            "diff",
            "--quiet",
            "HEAD",
            "--",
            "crates",
            "tests",
            "Cargo.toml",
            "Cargo.lock",
        ]) else {
            panic!("git diff failed in a checkout where git rev-parse worked");
        };
        let want = if code == 0 {
            hash
        } else {
            format!("{hash}-dirty")
        };
        assert!(
            super::VERSION.ends_with(&format!("({want})")),
            "VERSION {} should name {want}",
            super::VERSION
        );
    }
}
