//! # raybench-packet
//!
//! SIMD ray tracing behind raybench's [`Accel`] contract (backend `packet`), bit-identical
//! to the scalar backends:
//!
//! - **One wide tree** (`layout.rs`): the BVH2 of `raybench-bvh` collapsed into a BVH8 by
//!   an SAH-optimal dynamic program (Ylitie, Karras and Laine, HPG 2017), its children's
//!   boxes stored as structure of arrays so that one SIMD test checks eight children, its
//!   leaves stored as contiguous blocks of four triangles with their ids.
//! - **Coherent packets** (Wald, Slusallek, Benthin and Wagner, "Interactive Rendering with
//!   Coherent Ray Tracing", 2001): consecutive rays of a batch that share an octant walk the
//!   BVH8 together, 64 at a time with AVX2 (eight vectors of eight lanes) and AVX-512 (four
//!   of sixteen), 8 with SSE4.1: one interval (frustum) test of the packet against all
//!   eight children, which rejects those no lane enters and accepts those every lane
//!   enters, per-lane slab tests of the others it keeps, nearest child first (for any hits
//!   the layout's slot order), each lane clipped to its own best `t`; leaves test one
//!   triangle against all lanes.
//! - **Single rays** (`intersect`, `occluded`, and batches whose rays share no octant): one
//!   SIMD test of eight children, nearest first (the nearest visited next without the
//!   stack; for any hits the child in the highest slot, see the layout's slot order),
//!   children prefetched, one SIMD test per block of four triangles; a batch's
//!   incoherent rays go one at a time, or, when the BVH8 exceeds the last-level cache,
//!   four at a time interleaved step by step so that their memory waits overlap
//!   (`stream.rs`, [`Interleave`]).
//! - **Instruction sets chosen at run time** ([`Isa::detect`]): AVX2, else SSE4.1, else
//!   portable code (four plain `f32` lanes, the fallback on any target). The same generic
//!   kernels are instantiated once per instruction set inside a `#[target_feature]`
//!   function; no build needs `-C target-cpu=native`.
//!
//! **Exactness.** The SIMD triangle kernels perform, lane by lane, the operations of
//! [`raybench_geometry::Triangle::intersect`] in its order, without approximate reciprocals or
//! fused multiply-adds; lanes where that routine would switch to f64 (an edge function
//! exactly 0) and primitives other than triangles are handed to the scalar routine. Box
//! tests are the core's conservative slab test with the same early-exit rule, so hits and
//! `t` equal the naive backend's bit for bit.
//!
//! `unsafe` is confined to the intrinsics wrapper (`simd.rs`) and the calls of the
//! `#[target_feature]` entry points after detection (this file).

mod layout;
mod packet;
mod simd;
mod single;
mod stream;
mod tri;

use layout::Layout;
use raybench_bvh::{Bvh, BvhParams, ObvhsBuildParams};
use raybench_geometry::{
    Accel, AccelStats, Counters, Geometry, Hit, PrimHit, QualityParams, Ray, StructureQuality,
};
use simd::{Lanes, Portable};
use std::sync::{Arc, OnceLock};

/// An instruction set the kernels can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// AVX-512F: sixteen lanes for packets, AVX2 for single rays (x86-64). A measured
    /// extra: [`Isa::detect`] picks it only when `RAYBENCH_ISA=avx512` asks for it.
    Avx512,
    /// AVX2: eight lanes (x86-64).
    Avx2,
    /// SSE4.1: four lanes (x86-64).
    Sse41,
    /// Portable code: four lanes of plain `f32` (any target).
    Portable,
}

impl Isa {
    /// Every instruction set.
    pub const ALL: [Isa; 4] = [Isa::Avx512, Isa::Avx2, Isa::Sse41, Isa::Portable];

    /// The ones [`Isa::detect`] chooses from by itself, preferred first.
    const AUTOMATIC: [Isa; 3] = [Isa::Avx2, Isa::Sse41, Isa::Portable];

    /// The name used by `RAYBENCH_ISA` and in reports: `avx2`, `sse4.1`, `portable`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Sse41 => "sse4.1",
            Self::Portable => "portable",
        }
    }

    /// SIMD lanes per vector.
    #[must_use]
    pub fn lanes(self) -> usize {
        match self {
            Self::Avx512 => 16,
            Self::Avx2 => 8,
            Self::Sse41 | Self::Portable => 4,
        }
    }

    /// Vectors per coherent packet.
    #[must_use]
    pub fn packet_vectors(self) -> usize {
        match self {
            Self::Avx512 => AVX512_VECTORS,
            Self::Avx2 => AVX2_VECTORS,
            Self::Sse41 | Self::Portable => NARROW_VECTORS,
        }
    }

    /// Whether this CPU can run it.
    #[must_use]
    pub fn is_available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx2")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Self::Sse41 => std::arch::is_x86_feature_detected!("sse4.1"),
            #[cfg(not(target_arch = "x86_64"))]
            Self::Avx512 | Self::Avx2 | Self::Sse41 => false,
            Self::Portable => true,
        }
    }

    /// The instruction set to use, decided once per process: the fastest available, or the
    /// one named by the environment variable `RAYBENCH_ISA` (`avx2`, `sse4.1`, `portable`)
    /// when it is set and available (otherwise a warning on stderr and the fastest).
    #[must_use]
    pub fn detect() -> Isa {
        static CHOSEN: OnceLock<Isa> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let best = Self::AUTOMATIC
                .into_iter()
                .find(|i| i.is_available())
                .unwrap_or(Self::Portable);
            let Ok(wanted) = std::env::var("RAYBENCH_ISA") else {
                return best;
            };
            match Self::ALL.into_iter().find(|i| i.name() == wanted.trim()) {
                Some(isa) if isa.is_available() => isa,
                _ => {
                    eprintln!(
                        "warning: RAYBENCH_ISA={wanted:?} is not an available instruction set \
                         (this CPU has: {}); using {}",
                        Self::ALL
                            .iter()
                            .filter(|i| i.is_available())
                            .map(|i| i.name())
                            .collect::<Vec<_>>()
                            .join(", "),
                        best.name()
                    );
                    best
                }
            }
        })
    }
}

impl std::fmt::Display for Isa {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How [`PacketAccel`] traces batches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PacketParams {
    /// The instruction set; [`Isa::detect`] by default. An unavailable one falls back to
    /// [`Isa::Portable`].
    pub isa: Isa,
    /// Trace coherent runs of a batch as packets (else every ray goes through the BVH8).
    pub packets: bool,
    /// The builder of the BVH2 the BVH8 is collapsed from.
    pub bvh: Bvh2Builder,
    /// How many incoherent rays a batch keeps in flight.
    pub interleave: Interleave,
}

/// The builder of the BVH2 that [`PacketAccel`] collapses into its BVH8. Either tree gives
/// the same hits; the trees, their build times and their speed differ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bvh2Builder {
    /// raybench's binned SAH builder (`raybench-bvh`) with these parameters (the default:
    /// [`BvhParams::medium`]).
    Binned(BvhParams),
    /// obvhs's PLOC (Meister and Bittner 2018) with its reinsertion pass, at obvhs's
    /// `fast_build` preset with leaves of at most `max_leaf` primitives (the collapse
    /// chooses leaves of up to eight from them), copied into raybench's layout with boxes
    /// recomputed from raybench's own ([`Bvh::build_ploc`]).
    Ploc {
        /// Largest leaf of the BVH2.
        max_leaf: u32,
    },
    /// The binned builder's tree with these parameters, then one pass of obvhs's
    /// reinsertion optimiser over the largest fifth of its nodes, at most
    /// [`Bvh2Builder::REINSERTION_CANDIDATES`] of them ([`Bvh::reinserted`]): subtrees
    /// moved to where they lower the surface-area cost, the leaves kept; the binned tree
    /// as it was where the pass saves no more than
    /// [`Bvh2Builder::MIN_REINSERTION_GAIN`] of its cost.
    Reinserted(BvhParams),
}

impl Bvh2Builder {
    /// The PLOC tree of the `packet:ploc` preset: leaves of at most two primitives.
    pub const PLOC: Self = Self::Ploc { max_leaf: 2 };

    /// The tree of the `packet:reinserted` preset: the default binned tree, reinserted.
    pub const REINSERTED: Self = Self::Reinserted(BvhParams::medium());

    /// The most nodes one reinsertion pass of [`Bvh2Builder::Reinserted`] takes as
    /// candidates. The largest nodes, which a pass takes first, hold most of the gain, and
    /// the pass's time grows with its candidates: on Sponza (61,303 nodes) 2,048 of them
    /// keep 84 % to 96 % of the node visits that 8,192 save, for a third of the time (1.6
    /// ms against 4.4 ms on two threads, where the binned build takes 14 ms); see
    /// docs/strategies.md, "Reinserting the binned tree".
    pub const REINSERTION_CANDIDATES: usize = 2048;

    /// The share of the BVH2's surface-area cost that a reinsertion pass of
    /// [`Bvh2Builder::Reinserted`] must save more than for its tree to be kept; otherwise
    /// the binned tree is collapsed as it was, and the pass has cost only the hand-over
    /// and its search. On Sponza the pass saves 7.7 % (and 10 % to 15 % of the node visits
    /// per ray), on the flattened `bunny-field` 1.5 % (the visits per ray unchanged, for
    /// about 0.3 s of pass and copy), on the bunny 0.06 % and on the generated meshes
    /// nothing.
    pub const MIN_REINSERTION_GAIN: f64 = 0.02;

    /// Builds the BVH2 over `geometry`.
    #[must_use]
    pub fn build(self, geometry: Arc<Geometry>) -> Bvh {
        match self {
            Self::Binned(params) => Bvh::build_with(geometry, params),
            Self::Reinserted(params) => {
                let tree = Bvh::build_with(geometry, params);
                let nodes = tree.nodes().len().max(1) as f32;
                let fraction = (Self::REINSERTION_CANDIDATES as f32 / nodes).min(0.2);
                tree.reinserted(&[fraction], Self::MIN_REINSERTION_GAIN)
            }
            Self::Ploc { max_leaf } => {
                let params = ObvhsBuildParams {
                    max_prims_per_leaf: max_leaf.max(1),
                    ..ObvhsBuildParams::fast_build()
                };
                Bvh::build_ploc(geometry, params)
            }
        }
    }
}

/// How many of a batch's incoherent rays (those not traced as packets) are in flight at
/// once: one, or several advanced one traversal step each in turn so that their memory
/// waits overlap. Any choice gives the same hits; only the speed differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interleave {
    /// One when the BVH8 fits the last-level cache, four when it does not (the faster on
    /// each side of that line, by the peer benchmark: see [`stream`]'s documentation).
    #[default]
    Auto,
    /// Each ray alone, through the single-ray loop, whose state stays in registers.
    One,
    /// Two rays.
    Two,
    /// Four rays.
    Four,
}

impl Default for PacketParams {
    fn default() -> Self {
        Self {
            isa: Isa::detect(),
            packets: true,
            bvh: Bvh2Builder::Binned(BvhParams::default()),
            interleave: Interleave::Auto,
        }
    }
}

/// The packet backend: a BVH8 collapsed from a BVH2, walked by packets and single rays.
#[derive(Debug)]
pub struct PacketAccel {
    geometry: Arc<Geometry>,
    layout: Layout,
    params: PacketParams,
    /// Incoherent rays in flight at once ([`stream::ONE`], [`stream::NARROW`] or
    /// [`stream::WIDE`]).
    streams: usize,
}

impl PacketAccel {
    /// Builds with explicit parameters.
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: PacketParams) -> Self {
        let mut params = params;
        if !params.isa.is_available() {
            params.isa = Isa::Portable;
        }
        let bvh = params.bvh.build(Arc::clone(&geometry));
        let layout = Layout::new(&bvh, &geometry);
        let streams = match params.interleave {
            Interleave::Auto => stream::width(layout.memory_bytes()),
            Interleave::One => stream::ONE,
            Interleave::Two => stream::NARROW,
            Interleave::Four => stream::WIDE,
        };
        Self {
            geometry,
            layout,
            params,
            streams,
        }
    }

    /// The parameters in use (with the instruction set actually used).
    #[must_use]
    pub fn params(&self) -> &PacketParams {
        &self.params
    }

    /// Rays per packet: 64 with AVX2 and AVX-512, 8 with four lanes.
    #[must_use]
    pub fn packet_size(&self) -> usize {
        self.params.isa.packet_vectors() * self.params.isa.lanes()
    }
}

/// Vectors per packet with AVX2: 64 rays (measured against 16 and 32: see
/// docs/strategies.md).
const AVX2_VECTORS: usize = 8;

/// Vectors per packet with AVX-512: 64 rays, as with AVX2.
const AVX512_VECTORS: usize = 4;

/// Vectors per packet with four lanes: 8 rays (measured against one vector).
const NARROW_VECTORS: usize = 2;

/// The closest hits of a batch: packets where the rays are coherent, single rays otherwise.
#[inline(always)]
fn batch_closest<L: Lanes, const K: usize, C: Counters>(
    accel: &PacketAccel,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    counters: &mut C,
) {
    let g = &*accel.geometry;
    let size = K * L::W;
    let mut best = vec![None::<(u32, PrimHit)>; rays.len()];
    for (ray, b) in rays.iter().zip(best.iter_mut()) {
        counters.add_tests(g.closest_unbounded(ray, b));
    }
    let mut stack = [(0, 0.0); single::STACK];
    let mut packet_stack: packet::PacketStack<K> = [(0, 0.0, [0; K]); single::STACK];
    // Rays that do not form coherent packets, traced afterwards (see `stream::width`).
    let mut pending = Vec::new();
    for (start, chunk) in (0..).step_by(size).zip(rays.chunks(size)) {
        let end = start + chunk.len();
        match packet::octant(chunk).filter(|_| accel.params.packets) {
            Some(oct) => packet::closest::<L, K, C>(
                &accel.layout,
                g,
                chunk,
                oct,
                &mut best[start..end],
                &mut packet_stack,
                &mut stack,
                counters,
            ),
            None => pending.extend(start..end),
        }
    }
    // A plain `match`, not a closure: a closure in a kernel is compiled as a function of
    // its own, without the kernel's instruction set.
    match accel.streams {
        _ if pending.is_empty() => {}
        stream::WIDE => stream::closest::<L, C, { stream::WIDE }>(
            &accel.layout,
            g,
            rays,
            &pending,
            &mut best,
            counters,
        ),
        stream::NARROW => stream::closest::<L, C, { stream::NARROW }>(
            &accel.layout,
            g,
            rays,
            &pending,
            &mut best,
            counters,
        ),
        _ => {
            for &i in &pending {
                best[i] = single::closest::<L, C>(
                    &accel.layout,
                    g,
                    &rays[i],
                    0,
                    best[i],
                    &mut stack,
                    counters,
                );
            }
        }
    }
    for ((ray, b), hit) in rays.iter().zip(best).zip(hits) {
        *hit = g.complete(ray, b);
    }
}

/// Any-hit results of a batch, as [`batch_closest`].
#[inline(always)]
fn batch_occluded<L: Lanes, const K: usize, C: Counters>(
    accel: &PacketAccel,
    rays: &[Ray],
    occluded: &mut [bool],
    counters: &mut C,
) {
    let g = &*accel.geometry;
    let size = K * L::W;
    let mut stack = [(0, 0.0); single::STACK];
    let mut packet_stack: packet::AnyStack = [(0, 0); single::STACK];
    // Rays that do not form coherent packets, traced afterwards (see `stream::width`).
    let mut pending = Vec::new();
    for (start, (chunk, out)) in (0..)
        .step_by(size)
        .zip(rays.chunks(size).zip(occluded.chunks_mut(size)))
    {
        for (ray, o) in chunk.iter().zip(out.iter_mut()) {
            let (hit, tests) = g.occluded_unbounded(ray);
            counters.add_tests(tests);
            *o = hit;
        }
        match packet::octant(chunk).filter(|_| accel.params.packets) {
            Some(oct) => packet::occluded::<L, K, C>(
                &accel.layout,
                g,
                chunk,
                oct,
                out,
                &mut packet_stack,
                &mut stack,
                counters,
            ),
            None => pending.extend(
                out.iter()
                    .enumerate()
                    .filter(|(_, o)| !**o)
                    .map(|(i, _)| start + i),
            ),
        }
    }
    match accel.streams {
        _ if pending.is_empty() => {}
        stream::WIDE => stream::occluded::<L, C, { stream::WIDE }>(
            &accel.layout,
            g,
            rays,
            &pending,
            occluded,
            counters,
        ),
        stream::NARROW => stream::occluded::<L, C, { stream::NARROW }>(
            &accel.layout,
            g,
            rays,
            &pending,
            occluded,
            counters,
        ),
        _ => {
            for &i in &pending {
                occluded[i] =
                    single::occluded::<L, C>(&accel.layout, g, &rays[i], 0, &mut stack, counters);
            }
        }
    }
}

/// One ray's closest hit through the BVH8.
#[inline(always)]
fn one_closest<L: Lanes, C: Counters>(
    accel: &PacketAccel,
    ray: &Ray,
    counters: &mut C,
) -> Option<Hit> {
    let g = &*accel.geometry;
    let mut best = None;
    counters.add_tests(g.closest_unbounded(ray, &mut best));
    let best = single::closest::<L, C>(
        &accel.layout,
        g,
        ray,
        0,
        best,
        &mut [(0, 0.0); single::STACK],
        counters,
    );
    g.complete(ray, best)
}

/// Whether one ray is blocked, through the BVH8.
#[inline(always)]
fn one_occluded<L: Lanes, C: Counters>(accel: &PacketAccel, ray: &Ray, counters: &mut C) -> bool {
    let g = &*accel.geometry;
    let (hit, tests) = g.occluded_unbounded(ray);
    counters.add_tests(tests);
    hit || single::occluded::<L, C>(
        &accel.layout,
        g,
        ray,
        0,
        &mut [(0, 0.0); single::STACK],
        counters,
    )
}

/// Instantiates the kernels for one instruction set (its lanes and vectors per packet),
/// inside functions with `$attr` (the `#[target_feature]` that lets the intrinsics inline).
macro_rules! entry_points {
    ($(#[$module_attr:meta])* $module:ident, $lanes:ty, $vectors:expr $(, #[$attr:meta])*) => {
        $(#[$module_attr])*
        mod $module {
            use super::*;
            $(#[$attr])*
            pub(super) fn batch_closest<C: Counters>(
                a: &PacketAccel,
                r: &[Ray],
                h: &mut [Option<Hit>],
                c: &mut C,
            ) {
                super::batch_closest::<$lanes, { $vectors }, C>(a, r, h, c);
            }
            $(#[$attr])*
            pub(super) fn batch_occluded<C: Counters>(
                a: &PacketAccel,
                r: &[Ray],
                o: &mut [bool],
                c: &mut C,
            ) {
                super::batch_occluded::<$lanes, { $vectors }, C>(a, r, o, c);
            }
            $(#[$attr])*
            pub(super) fn one_closest<C: Counters>(
                a: &PacketAccel,
                r: &Ray,
                c: &mut C,
            ) -> Option<Hit> {
                super::one_closest::<$lanes, C>(a, r, c)
            }
            $(#[$attr])*
            pub(super) fn one_occluded<C: Counters>(a: &PacketAccel, r: &Ray, c: &mut C) -> bool {
                super::one_occluded::<$lanes, C>(a, r, c)
            }
        }
    };
}

entry_points!(
    #[cfg(target_arch = "x86_64")]
    avx512,
    simd::Avx512,
    AVX512_VECTORS,
    #[target_feature(enable = "avx512f,avx2")]
);
entry_points!(
    #[cfg(target_arch = "x86_64")]
    avx2,
    simd::Avx2,
    AVX2_VECTORS,
    #[target_feature(enable = "avx2")]
);
entry_points!(
    #[cfg(target_arch = "x86_64")]
    sse41,
    simd::Sse41,
    NARROW_VECTORS,
    #[target_feature(enable = "sse4.1")]
);
entry_points!(portable, Portable, NARROW_VECTORS);

/// Calls `$f` of the module for the accelerator's instruction set.
macro_rules! dispatch {
    ($self:ident, $f:ident($($arg:expr),*)) => {
        match $self.params.isa {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `build_with` keeps `Avx512` only when `is_available` detected
            // AVX-512F and AVX2.
            Isa::Avx512 => unsafe { avx512::$f($self, $($arg),*) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `build_with` keeps `Avx2` only when `is_available` detected AVX2.
            Isa::Avx2 => unsafe { avx2::$f($self, $($arg),*) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `build_with` keeps `Sse41` only when `is_available` detected SSE4.1.
            Isa::Sse41 => unsafe { sse41::$f($self, $($arg),*) },
            _ => portable::$f($self, $($arg),*),
        }
    };
}

#[allow(unsafe_code)]
impl Accel for PacketAccel {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, PacketParams::default())
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        dispatch!(self, one_closest(ray, counters))
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        dispatch!(self, one_occluded(ray, counters))
    }

    fn intersect_batch<C: Counters>(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        counters: &mut C,
    ) {
        assert_eq!(rays.len(), hits.len());
        dispatch!(self, batch_closest(rays, hits, counters));
    }

    fn occluded_batch<C: Counters>(&self, rays: &[Ray], occluded: &mut [bool], counters: &mut C) {
        assert_eq!(rays.len(), occluded.len());
        dispatch!(self, batch_occluded(rays, occluded, counters));
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            memory_bytes: self.layout.memory_bytes(),
            counts: vec![
                ("bvh2 nodes", self.layout.bvh2_nodes as u64),
                ("bvh8 nodes", self.layout.wide.len() as u64),
                ("leaves", self.layout.leaves as u64),
                ("child slots filled %", self.layout.fill_percent()),
                ("triangles per leaf x100", self.layout.leaf_prims_x100()),
                ("lanes", self.params.isa.lanes() as u64),
                ("packet rays", self.packet_size() as u64),
                ("interleaved rays", self.streams as u64),
            ],
        }
    }

    /// The BVH8's figures: leaves are runs of blocks of four triangles, and a leaf's
    /// `C_i` cost counts its primitives, not its blocks.
    fn quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        let q = self
            .layout
            .tree_view()
            .quality(&self.geometry, params, self.layout.memory_bytes());
        Some(StructureQuality::Tree(q))
    }
}
