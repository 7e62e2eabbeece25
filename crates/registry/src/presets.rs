//! The builder presets: every backend whose structure has named build parameters, each
//! preset registered as a backend of its own called `BACKEND:PRESET` (`bvh:fast`,
//! `obvhs:very_slow_build`, `embree:high`), so that `compare`, `info`, `render` and
//! `report` take it wherever they take a backend name ([`crate::backend`] resolves it).
//! This file is part of the registry (with `lib.rs`, the one place that names concrete
//! backends).
//!
//! A preset's [`Backend`] has its backend's roles without the registry-wide ones (oracle,
//! baseline, yardstick) and with [`Roles::PINNED`]: a variant with one parameter pinned,
//! run only when named. Every backend's default preset ([`Preset::default`]) builds what
//! its entry in [`crate::BACKENDS`] builds.

use crate::{Backend, Roles, TimedRenderer};
use raybench_bvh::{Bvh, BvhParams, ObvhsAccel, ObvhsBuildParams};

use raybench_grid::{Grid, GridParams};
use raybench_packet::{Bvh2Builder, PacketAccel, PacketParams};
#[cfg(feature = "embree")]
use raybench_peers::{
    EmbreeAccel, EmbreeMode, EmbreeQuality, embree_availability, embree_supports,
};
use raybench_render::CpuRenderer;

/// One named build preset of a backend.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    /// The backend it builds (a name in [`crate::BACKENDS`]).
    pub backend: &'static str,
    /// The preset's name (what follows the `:`).
    pub preset: &'static str,
    /// Whether it is what the backend builds by default.
    pub default: bool,
    /// The backend entry `BACKEND:PRESET` that builds with it.
    pub entry: Backend,
}

/// A preset of backend `$backend` called `$preset` (string literals), with its roles,
/// description, and the builder of its structure from an `Arc<Geometry>`.
macro_rules! preset {
    ($backend:literal, $preset:literal, $default:expr, $roles:expr, $accel:ty,
     $description:literal, $build:expr) => {
        Preset {
            backend: $backend,
            preset: $preset,
            default: $default,
            entry: Backend {
                name: concat!($backend, ":", $preset),
                description: $description,
                roles: $roles,
                detail: None,
                make: || {
                    Box::new(CpuRenderer::<$accel>::new(
                        concat!($backend, ":", $preset),
                        $description,
                        Box::new($build),
                    )) as Box<dyn TimedRenderer>
                },
            },
        }
    };
}

/// The roles of a preset of one of raybench's exact backends.
const EXACT_PRESET: Roles = Roles::EXACT.with(Roles::PINNED);

/// The Embree backend's presets: its builder at one build quality, robust scene mode, as
/// the backend `embree` (medium is its default).
#[cfg(feature = "embree")]
macro_rules! embree_preset {
    ($preset:literal, $default:expr, $quality:expr, $description:literal) => {
        Preset {
            backend: "embree",
            preset: $preset,
            default: $default,
            entry: Backend {
                name: concat!("embree:", $preset),
                description: $description,
                roles: Roles::PEER.with(Roles::PINNED),
                detail: None,
                make: || {
                    Box::new(
                        CpuRenderer::<EmbreeAccel>::new(
                            concat!("embree:", $preset),
                            $description,
                            Box::new(|g| EmbreeAccel::build_with(g, EmbreeMode::Robust, $quality)),
                        )
                        .with_availability(embree_availability)
                        .with_support_check(embree_supports)
                        .without_test_counts(),
                    )
                },
            },
        }
    };
}

/// Every preset, grouped by backend in registry order, each backend's fastest build
/// first (for `bvh`: its binned builds, then its PLOC topologies, each group fastest first).
/// A `static` for the reason [`crate::BACKENDS`] is one.
pub static PRESETS: &[Preset] = &[
    preset!(
        "bvh",
        "fast",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh built with BvhParams::fast (8 bins, leaves of up to 8)",
        |g| Bvh::build_with(g, BvhParams::fast())
    ),
    preset!(
        "bvh",
        "medium",
        true,
        EXACT_PRESET,
        Bvh,
        "bvh built with BvhParams::medium (16 bins, leaves of up to 4; the default)",
        |g| Bvh::build_with(g, BvhParams::medium())
    ),
    preset!(
        "bvh",
        "quality",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh built with BvhParams::quality (32 bins, leaves of up to 2)",
        |g| Bvh::build_with(g, BvhParams::quality())
    ),
    preset!(
        "bvh",
        "presplit",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh built with BvhParams::medium over triangles pre-split for up to 30 % more references (a triangle in several leaves, each with the box of its part there)",
        |g| Bvh::build_with(g, presplit())
    ),
    preset!(
        "bvh",
        "ploc_fastest_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::fastest_build (minimum search, no reinsertion): the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::fastest_build())
    ),
    preset!(
        "bvh",
        "ploc_very_fast_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::very_fast_build: the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::very_fast_build())
    ),
    preset!(
        "bvh",
        "ploc_fast_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::fast_build: the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::fast_build())
    ),
    preset!(
        "bvh",
        "ploc_medium_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::medium_build: the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::medium_build())
    ),
    preset!(
        "bvh",
        "ploc_slow_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::slow_build: the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::slow_build())
    ),
    preset!(
        "bvh",
        "ploc_very_slow_build",
        false,
        EXACT_PRESET,
        Bvh,
        "bvh's layout and traversal over obvhs's PLOC tree at BvhBuildParams::very_slow_build (full reinsertion): the builder varied, the kernel fixed",
        |g| Bvh::build_ploc(g, ObvhsBuildParams::very_slow_build())
    ),
    preset!(
        "obvhs",
        "fastest_build",
        false,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::fastest_build (PLOC, minimum search, no reinsertion)",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::fastest_build())
    ),
    preset!(
        "obvhs",
        "very_fast_build",
        false,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::very_fast_build",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::very_fast_build())
    ),
    preset!(
        "obvhs",
        "fast_build",
        false,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::fast_build",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::fast_build())
    ),
    preset!(
        "obvhs",
        "medium_build",
        true,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::medium_build (the default)",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::medium_build())
    ),
    preset!(
        "obvhs",
        "slow_build",
        false,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::slow_build (its pre-splitting needs triangles and is off: raybench hands obvhs boxes)",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::slow_build())
    ),
    preset!(
        "obvhs",
        "very_slow_build",
        false,
        EXACT_PRESET,
        ObvhsAccel,
        "obvhs with BvhBuildParams::very_slow_build (full reinsertion; no pre-splitting, as slow_build)",
        |g| ObvhsAccel::build_with(g, ObvhsBuildParams::very_slow_build())
    ),
    preset!(
        "grid",
        "fast_build",
        false,
        EXACT_PRESET,
        Grid,
        "grid with GridParams::fast_build (the default resolution without the triangle/box test)",
        |g| Grid::build_with(g, GridParams::fast_build())
    ),
    preset!(
        "grid",
        "coarse",
        false,
        EXACT_PRESET,
        Grid,
        "grid with GridParams::coarse (lambda 0.8, about half a cell per primitive)",
        |g| Grid::build_with(g, GridParams::coarse())
    ),
    preset!(
        "grid",
        "medium",
        true,
        EXACT_PRESET,
        Grid,
        "grid with GridParams::medium (lambda 1.25; the default)",
        |g| Grid::build_with(g, GridParams::medium())
    ),
    preset!(
        "grid",
        "fine",
        false,
        EXACT_PRESET,
        Grid,
        "grid with GridParams::fine (lambda 2, eight cells per primitive)",
        |g| Grid::build_with(g, GridParams::fine())
    ),
    preset!(
        "packet",
        "fast",
        false,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from a BVH2 built with BvhParams::fast",
        |g| PacketAccel::build_with(g, packet_over(BvhParams::fast()))
    ),
    preset!(
        "packet",
        "medium",
        true,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from a BVH2 built with BvhParams::medium (the default)",
        |g| PacketAccel::build_with(g, packet_over(BvhParams::medium()))
    ),
    preset!(
        "packet",
        "quality",
        false,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from a BVH2 built with BvhParams::quality",
        |g| PacketAccel::build_with(g, packet_over(BvhParams::quality()))
    ),
    preset!(
        "packet",
        "presplit",
        false,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from a BVH2 built with BvhParams::medium over triangles pre-split for up to 30 % more references",
        |g| PacketAccel::build_with(g, packet_over(presplit()))
    ),
    preset!(
        "packet",
        "ploc",
        false,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from obvhs's PLOC BVH2 with reinsertion (its fast_build, leaves of up to two): fewer node visits on Sponza than the binned tree",
        |g| PacketAccel::build_with(
            g,
            PacketParams {
                bvh: Bvh2Builder::PLOC,
                ..PacketParams::default()
            }
        )
    ),
    preset!(
        "packet",
        "reinserted",
        false,
        EXACT_PRESET,
        PacketAccel,
        "packet's BVH8 collapsed from the medium binned BVH2 after one pass of obvhs's reinsertion optimiser over its largest fifth of nodes (at most 2,048): fewer node visits on Sponza (a build about 1.1x as long); where the pass saves under 2 % of the SAH (the generated meshes, the bunny, bunny-field) the binned tree is kept",
        |g| PacketAccel::build_with(
            g,
            PacketParams {
                bvh: Bvh2Builder::REINSERTED,
                ..PacketParams::default()
            }
        )
    ),
    #[cfg(feature = "embree")]
    embree_preset!(
        "low",
        false,
        EmbreeQuality::Low,
        "peer: Embree 3, rtcIntersect1, RTC_BUILD_QUALITY_LOW (its fastest, lower-quality build)"
    ),
    #[cfg(feature = "embree")]
    embree_preset!(
        "medium",
        true,
        EmbreeQuality::Medium,
        "peer: Embree 3, rtcIntersect1, RTC_BUILD_QUALITY_MEDIUM (its default)"
    ),
    #[cfg(feature = "embree")]
    embree_preset!(
        "high",
        false,
        EmbreeQuality::High,
        "peer: Embree 3, rtcIntersect1, RTC_BUILD_QUALITY_HIGH (spatial splits for triangles)"
    ),
];

/// The packet backend's parameters over a BVH2 built with `bvh` (instruction set detected,
/// packets on).
fn packet_over(bvh: BvhParams) -> PacketParams {
    PacketParams {
        bvh: Bvh2Builder::Binned(bvh),
        ..PacketParams::default()
    }
}

/// The `medium` preset over triangles pre-split with [`BvhParams::PRESPLIT`].
fn presplit() -> BvhParams {
    BvhParams {
        presplit: BvhParams::PRESPLIT,
        ..BvhParams::medium()
    }
}

/// The presets of backend `name`, in order.
pub fn presets_of(name: &str) -> impl Iterator<Item = &'static Preset> + '_ {
    PRESETS.iter().filter(move |p| p.backend == name)
}

/// The backend named `spec` when it has the form `BACKEND:PRESET`; `None` when it has no
/// `:`.
///
/// # Errors
/// One line naming what is wrong: an unknown backend (as [`crate::backend`]), a backend
/// without presets (listing those with), or an unknown preset (listing the backend's).
pub fn preset_backend(spec: &str) -> Option<Result<&'static Backend, String>> {
    let (name, preset) = spec.split_once(':')?;
    Some(
        if let Some(p) = presets_of(name).find(|p| p.preset == preset) {
            Ok(&p.entry)
        } else if let Err(e) = crate::backend(name) {
            Err(e)
        } else if presets_of(name).next().is_none() {
            let mut with: Vec<&str> = PRESETS.iter().map(|p| p.backend).collect();
            with.dedup();
            Err(format!(
                "backend '{name}' has no build presets (backends with presets: {})",
                with.join(", ")
            ))
        } else {
            let known: Vec<&str> = presets_of(name).map(|p| p.preset).collect();
            Err(format!(
                "unknown preset '{preset}' of backend '{name}' (known: {})",
                known.join(", ")
            ))
        },
    )
}
