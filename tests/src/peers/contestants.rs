//! Who runs in the peer benchmark: every exact raybench CPU backend of the registry and the
//! peers, each a [`Renderer`] whose prepared structure exposes its batch entry points
//! ([`Renderer::batch_tracer`]).

use crate::obvhs_peer::{ObvhsPeer, ObvhsTree};
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use raybench_registry::TimedRenderer;
use raybench_render::CpuRenderer;
use serde::Serialize;

/// Whose structure a contestant is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A raybench backend bound by the equivalence contract.
    Raybench,
    /// Another library's structure (not bound by the contract: its differences from `bvh`
    /// are counted).
    Peer,
}

/// One contestant: a name, what it is, and how to make its unprepared renderer.
#[derive(Clone, Copy, Debug)]
pub struct Contestant {
    /// The name in the tables, in the JSON and in `--contestants`.
    pub name: &'static str,
    /// Whose structure it is.
    pub kind: Kind,
    /// One line of description.
    pub description: &'static str,
    /// Makes a fresh, unprepared renderer.
    pub make: fn() -> Box<dyn TimedRenderer>,
}

/// Every contestant, in table order: the registry's exact CPU backends except the brute
/// force (`raybench_registry::BACKENDS` is the one list; a new exact backend joins the benchmark by
/// being registered), then [`PEERS`].
#[must_use]
pub fn all() -> Vec<Contestant> {
    raybench_registry::BACKENDS
        .iter()
        .filter(|b| b.exact() && !b.is(raybench_registry::Roles::BRUTE_FORCE))
        .map(|b| Contestant {
            name: b.name,
            kind: Kind::Raybench,
            description: b.description,
            make: b.make,
        })
        .chain(PEERS.iter().copied())
        .collect()
}

/// The contestants called `names`, in table order; a build preset of an exact backend
/// (`packet:ploc`, see `raybench backends`) joins them after the others, in the order
/// named.
///
/// # Errors
/// A name that is neither a contestant nor an exact backend's preset, with the list of
/// known contestants.
pub fn select(names: &[String]) -> Result<Vec<Contestant>, String> {
    let all = all();
    let mut presets = Vec::new();
    for name in names.iter().filter(|n| !all.iter().any(|c| c.name == *n)) {
        match raybench_registry::backend(name) {
            Ok(b) if name.contains(':') && b.exact() => presets.push(Contestant {
                name: b.name,
                kind: Kind::Raybench,
                description: b.description,
                make: b.make,
            }),
            _ => {
                let known: Vec<_> = all.iter().map(|c| c.name).collect();
                return Err(format!(
                    "unknown contestant '{name}' (known: {}, or an exact backend's preset \
                     such as packet:ploc)",
                    known.join(", ")
                ));
            }
        }
    }
    Ok(all
        .into_iter()
        .filter(|c| names.iter().any(|n| n == c.name))
        .chain(presets)
        .collect())
}

/// The registered peer `name` (`bvh-crate`).
fn registered(name: &str) -> Box<dyn TimedRenderer> {
    (raybench_registry::backend(name)
        .unwrap_or_else(|e| panic!("{e}"))
        .make)()
}

/// An obvhs tree of type `T` behind a renderer.
fn obvhs_renderer<T: ObvhsTree>(description: &'static str) -> Box<dyn TimedRenderer> {
    Box::new(
        CpuRenderer::<ObvhsPeer<T>>::with_default_build(T::NAME, description)
            .with_support_check(ObvhsPeer::<T>::supports)
            .without_test_counts(),
    )
}

/// Peers beside the registry's backends.
pub const PEERS: &[Contestant] = &[
    Contestant {
        name: "bvh-crate",
        kind: Kind::Peer,
        description: "svenstaro's bvh crate: its tree, a stack traversal, raybench's triangle test (registered backend bvh-crate)",
        make: || registered("bvh-crate"),
    },
    Contestant {
        name: "obvhs-bvh2",
        kind: Kind::Peer,
        description: OBVHS_BVH2,
        make: || obvhs_renderer::<Bvh2>(OBVHS_BVH2),
    },
    Contestant {
        name: "obvhs-cwbvh",
        kind: Kind::Peer,
        description: OBVHS_CWBVH,
        make: || obvhs_renderer::<CwBvh>(OBVHS_CWBVH),
    },
    #[cfg(feature = "embree")]
    Contestant {
        name: embree::SINGLE_ROBUST,
        kind: Kind::Peer,
        description: "Embree 3, robust mode, rtcIntersect1 / rtcOccluded1 per ray (registered backend embree)",
        make: || embree::single(embree::SINGLE_ROBUST, raybench_peers::EmbreeMode::Robust),
    },
    #[cfg(feature = "embree")]
    Contestant {
        name: embree::SINGLE_DEFAULT,
        kind: Kind::Peer,
        description: "Embree 3, default mode (not watertight), rtcIntersect1 / rtcOccluded1 per ray",
        make: || embree::single(embree::SINGLE_DEFAULT, raybench_peers::EmbreeMode::Default),
    },
    #[cfg(feature = "embree")]
    Contestant {
        name: embree::PACKET_ROBUST,
        kind: Kind::Peer,
        description: "Embree 3, robust mode, rtcIntersect16 / rtcOccluded16 on consecutive rays (registered backend embree-packet)",
        make: || embree::packet(embree::PACKET_ROBUST, raybench_peers::EmbreeMode::Robust),
    },
    #[cfg(feature = "embree")]
    Contestant {
        name: embree::PACKET_DEFAULT,
        kind: Kind::Peer,
        description: "Embree 3, default mode (not watertight), rtcIntersect16 / rtcOccluded16 on consecutive rays",
        make: || embree::packet(embree::PACKET_DEFAULT, raybench_peers::EmbreeMode::Default),
    },
    #[cfg(feature = "tinybvh")]
    Contestant {
        name: "tinybvh4",
        kind: Kind::Peer,
        description: TINYBVH4,
        make: || tinybvh::renderer("tinybvh4", TINYBVH4, raybench_peers::TinyBvhLayout::Bvh4),
    },
    #[cfg(feature = "tinybvh")]
    Contestant {
        name: "tinybvh8",
        kind: Kind::Peer,
        description: TINYBVH8,
        make: || tinybvh::renderer("tinybvh8", TINYBVH8, raybench_peers::TinyBvhLayout::Bvh8),
    },
];

#[cfg(feature = "tinybvh")]
const TINYBVH4: &str = "tinybvh 1.6.8's BVH4_CPU: its own build (binned SAH, collapsed to 4-wide) and single-ray kernels (SSE, own triangle test), through a C++ shim";
#[cfg(feature = "tinybvh")]
const TINYBVH8: &str = "tinybvh 1.6.8's BVH8_CPU: its own build (binned SAH, collapsed to 8-wide) and single-ray kernels (AVX2, own triangle test), through a C++ shim";

/// The tinybvh contestants' renderer.
#[cfg(feature = "tinybvh")]
mod tinybvh {
    use super::TimedRenderer;
    use raybench_peers::{TinyBvhAccel, TinyBvhLayout};

    /// A renderer named `name` over tinybvh's `layout`, with tinybvh's availability (AVX2
    /// and FMA) and support (triangles) checks; tinybvh counts no tests.
    pub(super) fn renderer(
        name: &'static str,
        description: &'static str,
        layout: TinyBvhLayout,
    ) -> Box<dyn TimedRenderer> {
        Box::new(
            raybench_render::CpuRenderer::<TinyBvhAccel>::new(
                name,
                description,
                Box::new(move |g| TinyBvhAccel::build_with(g, layout)),
            )
            .with_availability(raybench_peers::tinybvh_availability)
            .with_support_check(raybench_peers::tinybvh_supports)
            .without_test_counts(),
        )
    }
}

const OBVHS_BVH2: &str = "obvhs 0.4's BVH2 (PLOC, reinsertion, collapsed leaves) and its own traversal, raybench's triangle test";
const OBVHS_CWBVH: &str = "obvhs 0.4's CWBVH (PLOC, reinsertion, compressed wide) and its own traversal, raybench's triangle test";

/// The Embree contestants' names, which the ratio columns refer to.
pub mod embree {
    /// `rtcIntersect1` / `rtcOccluded1`, robust mode.
    pub const SINGLE_ROBUST: &str = "embree1-robust";
    /// `rtcIntersect1` / `rtcOccluded1`, default mode.
    pub const SINGLE_DEFAULT: &str = "embree1-default";
    /// `rtcIntersect16` / `rtcOccluded16`, robust mode.
    pub const PACKET_ROBUST: &str = "embree16-robust";
    /// `rtcIntersect16` / `rtcOccluded16`, default mode.
    pub const PACKET_DEFAULT: &str = "embree16-default";

    #[cfg(feature = "embree")]
    use super::TimedRenderer;
    #[cfg(feature = "embree")]
    use raybench_core::{Accel, Geometry};
    #[cfg(feature = "embree")]
    use raybench_peers::{EmbreeAccel, EmbreeMode, EmbreePacketAccel};
    #[cfg(feature = "embree")]
    use std::sync::Arc;

    /// A renderer named `name` over the structure `build` makes, with Embree's
    /// availability and support checks; Embree counts no tests.
    #[cfg(feature = "embree")]
    fn renderer<A: Accel>(
        name: &'static str,
        build: impl Fn(Arc<Geometry>) -> A + Send + Sync + 'static,
    ) -> Box<dyn TimedRenderer> {
        Box::new(
            raybench_render::CpuRenderer::<A>::new(name, name, Box::new(build))
                .with_availability(raybench_peers::embree_availability)
                .with_support_check(raybench_peers::embree_supports)
                .without_test_counts(),
        )
    }

    /// Single rays in `mode`.
    #[cfg(feature = "embree")]
    pub(super) fn single(name: &'static str, mode: EmbreeMode) -> Box<dyn TimedRenderer> {
        renderer(name, move |g| EmbreeAccel::build_with_mode(g, mode))
    }

    /// 16-ray packets in `mode`.
    #[cfg(feature = "embree")]
    pub(super) fn packet(name: &'static str, mode: EmbreeMode) -> Box<dyn TimedRenderer> {
        renderer(name, move |g| {
            EmbreePacketAccel::build_with(g, raybench_peers::DEFAULT_PACKET_WIDTH, mode)
        })
    }
}
