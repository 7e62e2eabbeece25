//! # raybench (library part of the command)
//!
//! The backend registry (names to [`Renderer`]s) and the frame comparison used by
//! `raybench compare` and by the cross-backend equivalence tests. The command line itself is
//! in `main.rs`.

pub mod measure;
pub mod progress;
pub mod report;

/// The version and the source revision it was built from (`0.1.0 (3f2a9c1)`; `unknown`
/// outside a git checkout, see `build.rs`): what `raybench --version` prints and every
/// report records.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("RAYBENCH_REVISION"),
    ")"
);

use raybench_bvh::{Bvh, ObvhsAccel};
use raybench_core::{Frame, Mode, NO_HIT, RaySet, RenderSettings, Renderer};
use raybench_grid::{Grid, TwoLevelGrid};
use raybench_naive::NaiveAccel;
use raybench_packet::{Isa, PacketAccel, PacketParams};
use raybench_peers::BvhCrateAccel;
#[cfg(feature = "embree")]
use raybench_peers::{EmbreeAccel, EmbreePacketAccel, embree_availability, embree_supports};
use raybench_render::CpuRenderer;
use raybench_wgpu::WgpuRenderer;

/// A registered backend.
#[derive(Clone, Copy, Debug)]
pub struct Backend {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// Whether it is a raybench CPU backend bound by the equivalence contract (bit-identical
    /// ids and `t` to naive); `compare` exits with status 3 when such a backend disagrees.
    pub exact: bool,
    /// Whether it tests every primitive for every ray (used to skip it by default on large
    /// workloads).
    pub brute_force: bool,
    /// Whether it is a variant of another backend with one parameter forced (such as the
    /// instruction set): run only when named, never in the default list.
    pub variant: bool,
    /// Makes a fresh, unprepared renderer.
    pub make: fn() -> Box<dyn Renderer>,
}

const NAIVE: &str = "every ray tests every primitive (the oracle)";
const BVH: &str =
    "own binned-SAH BVH2, 32-byte depth-first nodes, near-child-first stack traversal";
const OBVHS: &str = "obvhs crate: PLOC + reinsertion, compressed wide CWBVH8, obvhs traversal";
const GRID: &str = "uniform grid walked by 3D-DDA (ray marching), mailboxing";
const GRID2: &str = "two-level grid: crowded cells hold their own grid";
const PACKET: &str = "SIMD over a BVH8 collapsed by SAH, leaves of 4-triangle blocks: 16-ray packets for coherent rays, interleaved single rays otherwise (AVX2, SSE4.1 or portable, picked at run time; RAYBENCH_ISA overrides)";

/// Every backend, the reference (naive) first.
pub const BACKENDS: &[Backend] = &[
    Backend {
        name: "naive",
        description: NAIVE,
        exact: true,
        brute_force: true,
        variant: false,
        make: || {
            Box::new(CpuRenderer::<NaiveAccel>::with_default_build(
                "naive", NAIVE,
            ))
        },
    },
    Backend {
        name: "bvh",
        description: BVH,
        exact: true,
        brute_force: false,
        variant: false,
        make: || Box::new(CpuRenderer::<Bvh>::with_default_build("bvh", BVH)),
    },
    Backend {
        name: "obvhs",
        description: OBVHS,
        exact: true,
        brute_force: false,
        variant: false,
        make: || {
            Box::new(CpuRenderer::<ObvhsAccel>::with_default_build(
                "obvhs", OBVHS,
            ))
        },
    },
    Backend {
        name: "grid",
        description: GRID,
        exact: true,
        brute_force: false,
        variant: false,
        make: || Box::new(CpuRenderer::<Grid>::with_default_build("grid", GRID)),
    },
    Backend {
        name: "grid2",
        description: GRID2,
        exact: true,
        brute_force: false,
        variant: false,
        make: || {
            Box::new(CpuRenderer::<TwoLevelGrid>::with_default_build(
                "grid2", GRID2,
            ))
        },
    },
    Backend {
        name: "packet",
        description: PACKET,
        exact: true,
        brute_force: false,
        variant: false,
        make: || {
            Box::new(CpuRenderer::<PacketAccel>::with_default_build(
                "packet", PACKET,
            ))
        },
    },
    Backend {
        name: "packet-sse4.1",
        description: PACKET_SSE41,
        exact: true,
        brute_force: false,
        variant: true,
        make: || packet_with(Isa::Sse41, "packet-sse4.1", PACKET_SSE41),
    },
    Backend {
        name: "packet-avx512",
        description: PACKET_AVX512,
        exact: true,
        brute_force: false,
        variant: true,
        make: || packet_with(Isa::Avx512, "packet-avx512", PACKET_AVX512),
    },
    Backend {
        name: "packet-portable",
        description: PACKET_PORTABLE,
        exact: true,
        brute_force: false,
        variant: true,
        make: || packet_with(Isa::Portable, "packet-portable", PACKET_PORTABLE),
    },
    Backend {
        name: "bvh-crate",
        description: BVH_CRATE,
        exact: false,
        brute_force: false,
        variant: false,
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
        exact: false,
        brute_force: false,
        variant: false,
        make: || Box::new(WgpuRenderer::new("wgpu", WGPU)),
    },
    #[cfg(feature = "embree")]
    Backend {
        name: "embree",
        description: EMBREE,
        exact: false,
        brute_force: false,
        variant: false,
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
        exact: false,
        brute_force: false,
        variant: false,
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

const BVH_CRATE: &str = "peer: svenstaro's bvh crate's tree, own stack traversal, raybench's primitive tests (not exact)";
const EMBREE: &str =
    "peer: Intel Embree 3, rtcIntersect1 per ray, Embree's own triangle test (not exact)";
const EMBREE_PACKET: &str = "peer: Intel Embree 3, rtcIntersect16 on 16-ray packets, Embree's own triangle test (not exact)";

const PACKET_SSE41: &str = "packet forced to SSE4.1 (4 lanes, 8-ray packets)";
const PACKET_AVX512: &str = "packet with AVX-512F packets (16 lanes, 32-ray packets; AVX2 for single rays), a measured extra";
const PACKET_PORTABLE: &str = "packet forced to portable code (4 plain f32 lanes, no intrinsics)";

/// The packet backend pinned to `isa`, unavailable where the CPU lacks it.
fn packet_with(isa: Isa, name: &'static str, description: &'static str) -> Box<dyn Renderer> {
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
    },
    #[cfg(not(feature = "embree"))]
    NotBuilt {
        name: "embree-packet",
        description: EMBREE_PACKET,
        feature: "embree",
        needs: EMBREE_NEEDS,
    },
];

/// The system library the Embree backends link.
#[cfg(not(feature = "embree"))]
const EMBREE_NEEDS: &str = "the system library libembree3; Debian: apt install libembree-dev";

/// Backends in order of preference for `render` without `--backend` (fastest first).
pub const PREFERENCE: &[&str] = &["packet", "bvh", "obvhs", "grid2", "grid", "naive"];

/// The backend called `name`.
///
/// # Errors
/// A message listing the known backends.
pub fn backend(name: &str) -> Result<&'static Backend, String> {
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
/// passes over `width x height` explicit rays (incoherent).
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
        RaySet::Incoherent => pixels,
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
        .filter(|b| !b.variant)
        .filter(|b| {
            let keep = !b.brute_force || work <= BRUTE_FORCE_BUDGET_TESTS;
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
mod tests {
    use super::*;

    fn names(list: &[&Backend]) -> Vec<&'static str> {
        list.iter().map(|b| b.name).collect()
    }

    #[test]
    fn brute_force_backends_leave_large_default_lists() {
        // `info terrain:708 --rays incoherent --width 64 --height 64`: 4096 rays against a
        // million triangles, minutes of naive.
        let s = RenderSettings {
            width: 64,
            height: 64,
            ..RenderSettings::default()
        };
        let terrain = brute_force_tests(&s, RaySet::Incoherent, 2 * 707 * 707, 1);
        assert!(!names(&chosen_backends(None, terrain).unwrap()).contains(&"naive"));
        // Named, it runs anyway.
        let forced = chosen_backends(Some(&["naive".to_string()]), terrain).unwrap();
        assert_eq!(names(&forced), ["naive"]);
        // A small scene keeps it, and it comes first (the reference).
        let small = brute_force_tests(&s, RaySet::Primary, 100, 4);
        assert_eq!(names(&chosen_backends(None, small).unwrap())[0], "naive");
        // Secondary rays count: path tracing estimates four rays per sample.
        let path = RenderSettings {
            mode: Mode::Path,
            ..s
        };
        assert_eq!(
            brute_force_tests(&path, RaySet::Primary, 10, 1),
            4.0 * brute_force_tests(&s, RaySet::Primary, 10, 1)
        );
    }

    #[test]
    fn backends_missing_from_the_build_name_their_feature() {
        for n in NOT_BUILT {
            assert!(BACKENDS.iter().all(|b| b.name != n.name));
            let e = backend(n.name).unwrap_err();
            assert!(
                e.contains("not compiled in") && e.contains(n.feature),
                "{e}"
            );
        }
        assert_eq!(
            NOT_BUILT.iter().any(|n| n.name == "embree"),
            !cfg!(feature = "embree")
        );
    }
}
