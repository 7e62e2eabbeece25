//! Binned SAH construction (Wald 2007) straight into the flat depth-first node array.
//!
//! - Items are 32-byte records (a box, the primitive id in the spare lane of its minimum).
//! - A node bins its items once for all three axes (bin index per axis from the centroid,
//!   bin boxes as four-lane minimum and maximum vectors), sweeps the bins for the cheapest
//!   split, and takes its children's boxes from the bins. The partition classifies blocks
//!   of items without branches (see [`partition`]) and then gathers the children's
//!   centroid bounds in one pass over each side, so no node bins to find them. Nodes of
//!   two items, the most common, skip the sort of the small-node split (see
//!   [`best_split_small`]).
//! - Parallelism from the top: nodes of at least `parallel_threshold` primitives build their
//!   two subtrees with `rayon::join`, and nodes of at least [`PARALLEL_BINNING`] items bin in
//!   parallel chunks whose bins are then merged (minimum, maximum and counts are exact, so
//!   the result does not depend on the chunking or the thread count).
//! - Nodes are written where they will stay: a subtree of `m` primitives has at most
//!   `2m - 1` nodes, so a parallel node gives its left subtree that many slots and starts the
//!   right one after them. Below the parallel threshold subtrees are written contiguously;
//!   the few gaps the parallel nodes leave are squeezed out once at the end. While building,
//!   an interior node stores the distance to its second child as it will be once the gaps
//!   are gone, which makes every subtree relocatable; the last pass turns distances into
//!   indices.
//!
//! The tree depends only on the primitives and the parameters: the split choice, the
//! partition order and the layout are the same on any number of threads.

use crate::Bvh;
use crate::node::Node;
use crate::params::BvhParams;
use crate::presplit;
use raybench_geometry::{Aabb, Geometry, Vec3};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// Build depth limit: a node this deep becomes a leaf whatever its size, which bounds the
/// traversal stack. Binned SAH on real scenes stays far below it.
pub(crate) const MAX_DEPTH: usize = 60;

/// Largest supported bin count.
const MAX_BINS: usize = 64;
const _: () = assert!(MAX_BINS.is_power_of_two() && MAX_BINS <= 256);

/// Nodes with at least this many items bin in parallel chunks of [`BINNING_CHUNK`] items.
const PARALLEL_BINNING: usize = 1 << 17;

/// Items per parallel binning chunk.
const BINNING_CHUNK: usize = 1 << 14;

/// Four `f32` lanes; the building's boxes use the first three (x, y, z). Written lane by
/// lane so the compiler emits packed SSE instructions.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct V4([f32; 4]);

impl V4 {
    const INFINITY: Self = Self([f32::INFINITY; 4]);
    const NEG_INFINITY: Self = Self([f32::NEG_INFINITY; 4]);

    #[inline]
    fn lanes(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        let (a, b) = (self.0, o.0);
        Self([f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])])
    }

    /// Lane-wise minimum; a NaN in `o` keeps `self` (as `f32::min` does for boxes grown
    /// from the empty box).
    #[inline]
    fn min(self, o: Self) -> Self {
        self.lanes(o, |a, b| if b < a { b } else { a })
    }

    /// Lane-wise maximum; a NaN in `o` keeps `self`.
    #[inline]
    fn max(self, o: Self) -> Self {
        self.lanes(o, |a, b| if b > a { b } else { a })
    }

    #[inline]
    fn vec3(self) -> Vec3 {
        Vec3::new(self.0[0], self.0[1], self.0[2])
    }
}

/// A box during the build, in four-lane vectors (the fourth lane is not part of it).
#[derive(Clone, Copy, Debug)]
struct Box4 {
    lo: V4,
    hi: V4,
}

impl Box4 {
    const EMPTY: Self = Self {
        lo: V4::INFINITY,
        hi: V4::NEG_INFINITY,
    };

    #[inline]
    fn union(self, o: Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    #[inline]
    fn grow(self, p: V4) -> Self {
        Self {
            lo: self.lo.min(p),
            hi: self.hi.max(p),
        }
    }

    #[inline]
    fn aabb(self) -> Aabb {
        Aabb::new(self.lo.vec3(), self.hi.vec3())
    }

    #[inline]
    fn surface_area(self) -> f32 {
        self.aabb().surface_area()
    }

    /// [`Box4::surface_area`] of a box known to be non-empty: the same arithmetic without
    /// the emptiness test.
    #[inline]
    fn area_non_empty(self) -> f32 {
        let e = self.hi.lanes(self.lo, |a, b| a - b).0;
        2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
    }
}

/// One bounded primitive while building: 32 bytes, its box with the primitive id stored in
/// the fourth lane of the minimum (bit-cast after an XOR with [`ID_BITS`]; that lane takes
/// part in no decision).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Item {
    lo: V4,
    hi: V4,
}

/// What the id is XORed with before it is stored as a float: the bits of 1.0, so that ids
/// below 2^23 read as floats in [1, 2). Stored as they are, they read as subnormal floats,
/// and the packed arithmetic that computes centroids, which runs in all four lanes, then
/// took a microcode assist per operation on Intel processors (about half of the build's
/// time on a Xeon).
const ID_BITS: u32 = 0x3f80_0000;

impl Item {
    fn new(bounds: Aabb, id: u32) -> Self {
        let (lo, hi) = (bounds.min, bounds.max);
        Self {
            lo: V4([lo.x, lo.y, lo.z, f32::from_bits(id ^ ID_BITS)]),
            hi: V4([hi.x, hi.y, hi.z, 0.0]),
        }
    }

    #[inline]
    fn id(&self) -> u32 {
        self.lo.0[3].to_bits() ^ ID_BITS
    }

    #[inline]
    fn bounds(&self) -> Box4 {
        Box4 {
            lo: self.lo,
            hi: self.hi,
        }
    }

    /// The centre's coordinate on `axis`, as [`Item::centroid`] computes it.
    #[inline]
    fn centroid_on(&self, axis: usize) -> f32 {
        (self.lo.0[axis] + self.hi.0[axis]) * 0.5
    }

    /// The box's centre, `(min + max) * 0.5` as [`Aabb::center`] computes it.
    #[inline]
    fn centroid(&self) -> V4 {
        self.lo.lanes(self.hi, |a, b| (a + b) * 0.5)
    }
}

/// The bounds of some items and of their centroids.
#[derive(Clone, Copy, Debug)]
struct Extent {
    bounds: Box4,
    centroids: Box4,
}

impl Extent {
    const EMPTY: Self = Self {
        bounds: Box4::EMPTY,
        centroids: Box4::EMPTY,
    };

    #[inline]
    fn add(self, it: &Item) -> Self {
        Self {
            bounds: self.bounds.union(it.bounds()),
            centroids: self.centroids.grow(it.centroid()),
        }
    }

    fn merge(self, o: Self) -> Self {
        Self {
            bounds: self.bounds.union(o.bounds),
            centroids: self.centroids.union(o.centroids),
        }
    }

    fn of(items: &[Item]) -> Self {
        items.iter().fold(Self::EMPTY, Self::add)
    }
}

/// How centroids map to bins along each axis.
#[derive(Clone, Copy, Debug)]
struct Binner {
    /// Smallest centroid per axis.
    cmin: V4,
    /// Bins per unit length per axis; 0 on axes that cannot be split.
    scale: V4,
    /// Bins per axis.
    bins: usize,
}

impl Binner {
    /// The binning over `centroids`, and which axes can be split (positive finite extent).
    fn new(centroids: Box4, bins: usize) -> (Self, [bool; 3]) {
        let extent = centroids.hi.lanes(centroids.lo, |a, b| a - b);
        let mut scale = [0.0; 4];
        let mut valid = [false; 3];
        for axis in 0..3 {
            let e = extent.0[axis];
            if e > 0.0 && e.is_finite() {
                valid[axis] = true;
                scale[axis] = bins as f32 / e;
            }
        }
        let binner = Self {
            cmin: centroids.lo,
            scale: V4(scale),
            bins,
        };
        (binner, valid)
    }

    /// The bins of a centroid on the three axes: per axis, the truncation of the scaled
    /// distance from the smallest centroid, clamped so the largest centroid lands in the
    /// last bin. The clamp happens before the truncation, in all lanes at once (the same
    /// bins as clamping after it, since the bounds are whole numbers; NaN goes to bin 0).
    #[inline]
    fn bins_of(&self, c: V4) -> [usize; 3] {
        let last = (self.bins - 1) as f32;
        let f = c
            .lanes(self.cmin, |c, m| c - m)
            .lanes(self.scale, |d, s| d * s)
            .lanes(V4([last; 4]), |f, last| {
                let f = if f > 0.0 { f } else { 0.0 };
                if f < last { f } else { last }
            });
        // Every lane is now in `0..=last` (below 64), so the conversion to `u8` truncates
        // exactly; unlike one to `i32`, whose saturation at `i32::MAX` compiles to a compare
        // and branch per lane, it compiles to the bare truncating instruction.
        let b = f.0.map(|x| x as u8 as usize);
        [
            b[0] & (MAX_BINS - 1),
            b[1] & (MAX_BINS - 1),
            b[2] & (MAX_BINS - 1),
        ]
    }

    /// Whether coordinate `x` on `axis` falls in a bin below `bin` (at least 1): the
    /// comparison of its [`Binner::bins_of`] bin with `bin` without the conversion, exact because
    /// `bin` is a whole number and the scaled coordinate is not negative.
    #[inline]
    fn below(&self, x: f32, axis: usize, bin: usize) -> bool {
        (x - self.cmin.0[axis]) * self.scale.0[axis] < bin as f32
    }
}

/// Per-axis bins: boxes and item counts.
#[derive(Clone)]
struct Bins {
    boxes: [[Box4; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Box<Self> {
        Box::new(Self {
            boxes: [[Box4::EMPTY; MAX_BINS]; 3],
            counts: [[0; MAX_BINS]; 3],
        })
    }

    /// Empties the first `bins` bins of every axis.
    fn clear(&mut self, bins: usize) {
        for axis in 0..3 {
            self.boxes[axis][..bins].fill(Box4::EMPTY);
            self.counts[axis][..bins].fill(0);
        }
    }

    /// Adds `items` into the bins `binner` assigns them.
    fn add(&mut self, binner: &Binner, items: &[Item]) {
        for it in items {
            self.put(binner, it);
        }
    }

    /// Adds one item.
    #[inline]
    fn put(&mut self, binner: &Binner, it: &Item) {
        let b = binner.bins_of(it.centroid());
        let bounds = it.bounds();
        for (axis, &k) in b.iter().enumerate() {
            let bin = &mut self.boxes[axis][k];
            *bin = bin.union(bounds);
            self.counts[axis][k] += 1;
        }
    }

    /// Adds the first `bins` bins of `o`.
    fn merge(&mut self, o: &Self, bins: usize) {
        for axis in 0..3 {
            for k in 0..bins {
                self.boxes[axis][k] = self.boxes[axis][k].union(o.boxes[axis][k]);
                self.counts[axis][k] += o.counts[axis][k];
            }
        }
    }
}

/// The chosen split: items whose centroid bin on `axis` is below `bin` go left.
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    bin: usize,
    /// SAH cost relative to a leaf's (`C_i` = 1 per primitive).
    cost: f32,
    /// The boxes of the two sides.
    left: Box4,
    right: Box4,
}

/// The cheapest SAH split over the valid axes and bin boundaries of `bins`.
fn best_split(
    bins: &Bins,
    binner: &Binner,
    valid: [bool; 3],
    area: f32,
    params: &BvhParams,
) -> Option<Split> {
    let n = binner.bins;
    let mut best: Option<Split> = None;
    for axis in (0..3).filter(|&a| valid[a]) {
        let (boxes, counts) = (&bins.boxes[axis], &bins.counts[axis]);
        // Sweep from the right for the right-hand areas and counts, then from the left. An
        // empty bin changes neither side: its right-hand area is its neighbour's, and the
        // boundary after it splits like the one before it at the same cost, which is never
        // strictly cheaper, so it is skipped.
        let mut right_area = [0.0f32; MAX_BINS];
        let mut right_count = [0u32; MAX_BINS];
        let (mut acc, mut count, mut acc_area) = (Box4::EMPTY, 0, 0.0);
        for i in (1..n).rev() {
            if counts[i] > 0 {
                acc = acc.union(boxes[i]);
                count += counts[i];
                acc_area = acc.area_non_empty();
            }
            right_area[i] = acc_area;
            right_count[i] = count;
        }
        let (mut left, mut left_count) = (Box4::EMPTY, 0);
        for i in 1..n {
            if counts[i - 1] == 0 {
                continue;
            }
            left = left.union(boxes[i - 1]);
            left_count += counts[i - 1];
            if right_count[i] == 0 {
                break;
            }
            let cost = params.traversal_cost
                + (left.area_non_empty() * left_count as f32
                    + right_area[i] * right_count[i] as f32)
                    / area;
            if cost.is_finite() && best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    bin: i,
                    cost,
                    left: Box4::EMPTY,
                    right: Box4::EMPTY,
                });
            }
        }
    }
    best.map(|b| {
        let boxes = &bins.boxes[b.axis][..n];
        let union = |side: &[Box4]| side.iter().fold(Box4::EMPTY, |a, &b| a.union(b));
        Split {
            left: union(&boxes[..b.bin]),
            right: union(&boxes[b.bin..]),
            ..b
        }
    })
}

/// Nodes of at most this many items find their split without bins (see
/// [`best_split_small`]).
const SMALL: usize = 12;

/// Bits of an item's index in [`best_split_small`]'s sort keys (`SMALL` items fit).
const ITEM_BITS: u32 = 4;
const _: () = assert!(SMALL <= 1 << ITEM_BITS && MAX_BINS << ITEM_BITS <= u16::MAX as usize);

/// [`best_split`] for at most [`SMALL`] items, without bins: per axis, the items sorted by
/// their bin and swept in that order, with a candidate wherever the bin changes. A bin
/// boundary's sides are the items below and above it, so this evaluates the same partitions
/// with the same boxes and costs as the bins would (boundaries next to empty bins repeat a
/// partition at the same cost), and picks the same one; it skips clearing and sweeping
/// mostly empty bins. Every item's bins come from one computation for all three axes; two
/// items have one partition, the same on every axis that separates them, and go without
/// the sort.
fn best_split_small(
    items: &[Item],
    binner: &Binner,
    valid: [bool; 3],
    area: f32,
    params: &BvhParams,
) -> Option<Split> {
    let n = items.len();
    debug_assert!((2..=SMALL).contains(&n));
    // Every item's bins on the three axes at once.
    let mut bins = [[0usize; 3]; SMALL];
    for (b, it) in bins.iter_mut().zip(items) {
        *b = binner.bins_of(it.centroid());
    }
    if n == 2 {
        // One partition only, at the same cost on every axis that separates the two: the
        // first such axis wins, as in the sweep below (later ones are not cheaper).
        let axis = (0..3).find(|&a| valid[a] && bins[0][a] != bins[1][a])?;
        let low = usize::from(bins[1][axis] < bins[0][axis]);
        let (left, right) = (items[low].bounds(), items[1 - low].bounds());
        let cost =
            params.traversal_cost + (left.surface_area() * 1.0 + right.surface_area() * 1.0) / area;
        return cost.is_finite().then_some(Split {
            axis,
            bin: bins[1 - low][axis],
            cost,
            left,
            right,
        });
    }
    let mut boxes = [Box4::EMPTY; SMALL];
    for (b, it) in boxes.iter_mut().zip(items) {
        *b = it.bounds();
    }
    let mut best: Option<Split> = None;
    for axis in (0..3).filter(|&a| valid[a]) {
        // Items by bin, in item order within a bin: `bin << ITEM_BITS | item` sorted as
        // numbers, without the branches of an insertion sort (see [`sort_keys`]).
        let mut unsorted = [u16::MAX; SMALL];
        for (i, b) in bins[..n].iter().enumerate() {
            unsorted[i] = ((b[axis] as u16) << ITEM_BITS) | i as u16;
        }
        let mut keys = [0u16; SMALL];
        match n {
            ..=4 => sort_keys::<4>(&unsorted, n, &mut keys),
            5..=8 => sort_keys::<8>(&unsorted, n, &mut keys),
            _ => sort_keys::<SMALL>(&unsorted, n, &mut keys),
        }
        let item = |k: usize| usize::from(keys[k] & ((1 << ITEM_BITS) - 1));
        // Every box here holds at least one item's box, so none is empty.
        let mut right = [Box4::EMPTY; SMALL];
        let mut right_area = [0.0f32; SMALL];
        let mut acc = Box4::EMPTY;
        for k in (1..n).rev() {
            acc = acc.union(boxes[item(k)]);
            right[k] = acc;
            right_area[k] = acc.area_non_empty();
        }
        let mut left = Box4::EMPTY;
        for k in 1..n {
            left = left.union(boxes[item(k - 1)]);
            if keys[k] >> ITEM_BITS == keys[k - 1] >> ITEM_BITS {
                continue;
            }
            let cost = params.traversal_cost
                + (left.area_non_empty() * k as f32 + right_area[k] * (n - k) as f32) / area;
            if cost.is_finite() && best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    bin: usize::from(keys[k] >> ITEM_BITS),
                    cost,
                    left,
                    right: right[k],
                });
            }
        }
    }
    best
}

/// Sorts the first `n` (at most `M`) of `unsorted`, distinct keys followed by padding
/// larger than all of them, into `keys`: each key's place is the number of smaller keys
/// among the first `M`, counted without branches.
#[inline]
fn sort_keys<const M: usize>(unsorted: &[u16; SMALL], n: usize, keys: &mut [u16; SMALL]) {
    for &key in &unsorted[..n] {
        let place: usize = unsorted[..M]
            .iter()
            .map(|&other| usize::from(other < key))
            .sum();
        keys[place] = key;
    }
}

/// Items per block of the blocked partition.
const PARTITION_BLOCK: usize = 64;

/// In-place partition by the split's side; returns the number of items now at the front
/// (those going left) and the extents of both sides (boxes from the split, centroid bounds
/// gathered here).
///
/// Blocked, as in Edelkamp and Weiß's BlockQuicksort: the sides of a block of items at
/// each end are classified without branches into lists of misplaced positions, and the
/// lists are swapped pairwise, so an unpredictable split (a triangle soup) costs no branch
/// mispredictions per item. What remains in the middle (under two blocks) goes through
/// the plain two-pointer loop. The centroid bounds of the sides are gathered afterwards in
/// one pass over each side (the order of items within a side does not matter to the build:
/// every decision depends on the sets only).
fn partition(items: &mut [Item], binner: &Binner, split: &Split) -> (usize, Extent, Extent) {
    let goes_left = |it: &Item| binner.below(it.centroid_on(split.axis), split.axis, split.bin);
    let (mut lo, mut hi) = (0, items.len());
    let mut misplaced_lo = [0u8; PARTITION_BLOCK];
    let mut misplaced_hi = [0u8; PARTITION_BLOCK];
    let (mut start_lo, mut count_lo, mut start_hi, mut count_hi) = (0, 0, 0, 0);
    while hi - lo >= 2 * PARTITION_BLOCK {
        if count_lo == 0 {
            start_lo = 0;
            for (k, it) in items[lo..lo + PARTITION_BLOCK].iter().enumerate() {
                misplaced_lo[count_lo] = k as u8;
                count_lo += usize::from(!goes_left(it));
            }
        }
        if count_hi == 0 {
            start_hi = 0;
            for (k, it) in items[hi - PARTITION_BLOCK..hi].iter().rev().enumerate() {
                misplaced_hi[count_hi] = k as u8;
                count_hi += usize::from(goes_left(it));
            }
        }
        let m = count_lo.min(count_hi);
        for k in 0..m {
            items.swap(
                lo + usize::from(misplaced_lo[start_lo + k]),
                hi - 1 - usize::from(misplaced_hi[start_hi + k]),
            );
        }
        (count_lo, count_hi) = (count_lo - m, count_hi - m);
        (start_lo, start_hi) = (start_lo + m, start_hi + m);
        if count_lo == 0 {
            lo += PARTITION_BLOCK;
        }
        if count_hi == 0 {
            hi -= PARTITION_BLOCK;
        }
    }
    // Everything before `lo` goes left, everything from `hi` on goes right; a block left
    // half done is classified again here.
    while lo < hi {
        if goes_left(&items[lo]) {
            lo += 1;
        } else {
            hi -= 1;
            items.swap(lo, hi);
        }
    }
    let centroids = |side: &[Item]| side.iter().fold(Box4::EMPTY, |b, it| b.grow(it.centroid()));
    let extent = |bounds, centroids| Extent { bounds, centroids };
    (
        lo,
        extent(split.left, centroids(&items[..lo])),
        extent(split.right, centroids(&items[lo..])),
    )
}

/// A node to build: its items (at `first` in the whole item array), their extent and its
/// depth.
struct Task<'a> {
    items: &'a mut [Item],
    first: usize,
    extent: Extent,
    depth: usize,
}

/// What becomes of a node.
enum Decision {
    Leaf,
    /// Split after the first `mid` items (already partitioned), with the sides' extents.
    Split {
        mid: usize,
        left: Extent,
        right: Extent,
    },
}

impl<'a> Task<'a> {
    /// Decides between a leaf and a split and, for a split, partitions the items.
    /// Binning uses `bins`, in parallel chunks when the node is large.
    fn decide(&mut self, params: &BvhParams, bins: &mut Bins) -> Decision {
        let n = self.items.len();
        if n == 1 || self.depth >= MAX_DEPTH {
            return Decision::Leaf;
        }
        let area = self.extent.bounds.surface_area();
        let split = if area > 0.0 && area.is_finite() {
            let (binner, valid) = Binner::new(self.extent.centroids, params.bins);
            if !valid.contains(&true) {
                None
            } else if n <= SMALL {
                best_split_small(self.items, &binner, valid, area, params).map(|s| (s, binner))
            } else {
                if n >= PARALLEL_BINNING {
                    let merged = self
                        .items
                        .par_chunks(BINNING_CHUNK)
                        .map(|chunk| {
                            let mut b = Bins::new();
                            b.clear(params.bins);
                            b.add(&binner, chunk);
                            b
                        })
                        .reduce_with(|mut a, b| {
                            a.merge(&b, params.bins);
                            a
                        });
                    if let Some(m) = merged {
                        *bins = *m;
                    }
                } else {
                    bins.clear(params.bins);
                    bins.add(&binner, self.items);
                }
                best_split(bins, &binner, valid, area, params).map(|s| (s, binner))
            }
        } else {
            None
        };
        match split {
            Some((split, binner)) if split.cost < n as f32 || n > params.max_leaf_size => {
                let (mid, left, right) = partition(self.items, &binner, &split);
                Decision::Split { mid, left, right }
            }
            Some(_) => Decision::Leaf,
            None if n > params.max_leaf_size => {
                // All centroids coincide (or the box is degenerate): split by count.
                let mid = n / 2;
                Decision::Split {
                    mid,
                    left: Extent::of(&self.items[..mid]),
                    right: Extent::of(&self.items[mid..]),
                }
            }
            None => Decision::Leaf,
        }
    }

    fn leaf(&self) -> Node {
        let b = self.extent.bounds;
        Node {
            min: b.lo.vec3(),
            first_or_right: self.first as u32,
            max: b.hi.vec3(),
            count: self.items.len() as u32,
        }
    }

    /// An interior node whose second child is `right` nodes further (a distance, turned
    /// into an index by [`absolute_indices`]).
    fn interior(&self, right: usize) -> Node {
        let b = self.extent.bounds;
        Node {
            min: b.lo.vec3(),
            first_or_right: right as u32,
            max: b.hi.vec3(),
            count: 0,
        }
    }

    /// The two children's tasks.
    fn children(self, mid: usize, left: Extent, right: Extent) -> (Task<'a>, Task<'a>) {
        let Task {
            items,
            first,
            depth,
            ..
        } = self;
        let (l, r) = items.split_at_mut(mid);
        (
            Task {
                items: l,
                first,
                extent: left,
                depth: depth + 1,
            },
            Task {
                items: r,
                first: first + mid,
                extent: right,
                depth: depth + 1,
            },
        )
    }
}

/// Builds the subtree of `task` on this thread into the front of `nodes`, contiguously;
/// returns its node count.
fn build_serial(
    mut task: Task<'_>,
    params: &BvhParams,
    nodes: &mut [Node],
    bins: &mut Bins,
) -> usize {
    match task.decide(params, bins) {
        Decision::Leaf => {
            nodes[0] = task.leaf();
            1
        }
        Decision::Split { mid, left, right } => {
            let node = task.interior(0);
            let (l, r) = task.children(mid, left, right);
            let left_count = build_serial(l, params, &mut nodes[1..], bins);
            let right_count = build_serial(r, params, &mut nodes[1 + left_count..], bins);
            nodes[0] = Node {
                first_or_right: (1 + left_count) as u32,
                ..node
            };
            1 + left_count + right_count
        }
    }
}

/// A subtree built in parallel: the slots it spans from its root, how many of them hold
/// nodes, and the unused ranges among them (absolute slot indices, ascending).
struct Built {
    span: usize,
    count: usize,
    gaps: Vec<Range<usize>>,
}

/// Builds the subtree of `task` into `nodes` (whose slot 0 is the absolute slot `at`),
/// splitting the work with rayon while nodes hold at least `parallel_threshold` items.
fn build_parallel(mut task: Task<'_>, params: &BvhParams, nodes: &mut [Node], at: usize) -> Built {
    let n = task.items.len();
    let mut bins = Bins::new();
    if n < params.parallel_threshold {
        let count = build_serial(task, params, nodes, &mut bins);
        return Built {
            span: count,
            count,
            gaps: Vec::new(),
        };
    }
    match task.decide(params, &mut bins) {
        Decision::Leaf => {
            nodes[0] = task.leaf();
            Built {
                span: 1,
                count: 1,
                gaps: Vec::new(),
            }
        }
        Decision::Split { mid, left, right } => {
            drop(bins);
            let node = task.interior(0);
            let (l, r) = task.children(mid, left, right);
            // The left subtree has at most 2 mid - 1 nodes; the right one starts after them.
            let (head, rest) = nodes.split_at_mut(1);
            let (left_slots, right_slots) = rest.split_at_mut(2 * mid - 1);
            let (lb, rb) = rayon::join(
                || build_parallel(l, params, left_slots, at + 1),
                || build_parallel(r, params, right_slots, at + 2 * mid),
            );
            head[0] = Node {
                first_or_right: (1 + lb.count) as u32,
                ..node
            };
            let mut gaps = lb.gaps;
            if lb.span < 2 * mid - 1 {
                gaps.push(at + 1 + lb.span..at + 2 * mid);
            }
            gaps.extend(rb.gaps);
            Built {
                span: 2 * mid + rb.span,
                count: 1 + lb.count + rb.count,
                gaps,
            }
        }
    }
}

/// Squeezes the `gaps` (ascending) out of the first `span` slots of `nodes`.
fn close_gaps(nodes: &mut Vec<Node>, span: usize, gaps: &[Range<usize>]) {
    let mut dst = 0;
    let mut src = 0;
    for g in gaps.iter().chain(std::iter::once(&(span..span))) {
        let len = g.start - src;
        if dst != src {
            nodes.copy_within(src..g.start, dst);
        }
        dst += len;
        src = g.end;
    }
    nodes.truncate(dst);
}

/// Turns the interior nodes' distances to their second child into indices.
fn absolute_indices(nodes: &mut [Node]) {
    nodes.par_iter_mut().enumerate().for_each(|(i, node)| {
        if !node.is_leaf() {
            node.first_or_right += i as u32;
        }
    });
}

impl Bvh {
    /// Builds over the bounded primitives of `geometry` with `params`.
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: BvhParams) -> Self {
        let mut params = params;
        params.bins = params.bins.clamp(2, MAX_BINS);
        params.max_leaf_size = params.max_leaf_size.max(1);
        let mut items: Vec<Item> =
            presplit::references(&geometry, geometry.bounded(), params.presplit, Item::new);
        let mut nodes = Vec::new();
        if !items.is_empty() {
            let extent = items
                .par_chunks(BINNING_CHUNK)
                .map(Extent::of)
                .reduce(|| Extent::EMPTY, Extent::merge);
            let slots = 2 * items.len() - 1;
            nodes.par_extend(rayon::iter::repeat_n(Node::default(), slots));
            let task = Task {
                items: &mut items,
                first: 0,
                extent,
                depth: 0,
            };
            let built = build_parallel(task, &params, &mut nodes, 0);
            close_gaps(&mut nodes, built.span, &built.gaps);
            debug_assert_eq!(nodes.len(), built.count);
            absolute_indices(&mut nodes);
            nodes.shrink_to_fit();
        }
        Self {
            geometry,
            nodes,
            prim_ids: items.par_iter().map(Item::id).collect(),
            params,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ids survive the trip through the spare lane, and small ids read as normal floats
    /// there (a subnormal lane slowed every centroid computation down on Intel processors).
    #[test]
    fn ids_round_trip_and_small_ids_are_normal_floats() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        for id in [0, 1, 2, 4095, (1 << 23) - 1, 1 << 23, 1 << 30, u32::MAX - 1] {
            let item = Item::new(b, id);
            assert_eq!(item.id(), id);
            if id < 1 << 23 {
                assert!(item.lo.0[3].is_normal(), "id {id}: {:e}", item.lo.0[3]);
                assert!(item.centroid().0[3].is_normal(), "id {id}");
            }
        }
    }

    /// The split of a small node without bins is the binned split: the same axis, cost,
    /// boxes and sides, for every item count up to [`SMALL`] and bin counts from 2 to
    /// [`MAX_BINS`] (items crowded into few bins, so many share one and many bins are
    /// empty).
    #[test]
    fn small_nodes_split_as_the_bins_would() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let params = BvhParams::default();
        let mut bins = Bins::new();
        for case in 0..3000 {
            let n = 2 + case % (SMALL - 1);
            let bin_count = [2, 3, 16, 64][case % 4];
            let items: Vec<Item> = (0..n)
                .map(|id| {
                    // Corners on a coarse lattice, so that centroids and bins repeat.
                    let lo = Vec3::new(next(), next(), next()) * 6.0;
                    let lo = lo.floor() * 0.25;
                    let size = Vec3::new(next(), next(), next());
                    Item::new(Aabb::new(lo, lo + size), id as u32)
                })
                .collect();
            let extent = Extent::of(&items);
            let area = extent.bounds.surface_area();
            let (binner, valid) = Binner::new(extent.centroids, bin_count);
            bins.clear(bin_count);
            bins.add(&binner, &items);
            let binned = best_split(&bins, &binner, valid, area, &params);
            let small = best_split_small(&items, &binner, valid, area, &params);
            let (Some(b), Some(s)) = (binned, small) else {
                assert!(binned.is_none() && small.is_none(), "case {case}");
                continue;
            };
            let bits = |x: Box4| [x.lo.0, x.hi.0].map(|v| v.map(f32::to_bits));
            assert_eq!(
                (b.axis, b.cost.to_bits()),
                (s.axis, s.cost.to_bits()),
                "case {case}"
            );
            assert_eq!(bits(b.left), bits(s.left), "case {case}");
            assert_eq!(bits(b.right), bits(s.right), "case {case}");
            for it in &items {
                let x = it.centroid_on(b.axis);
                assert_eq!(
                    binner.below(x, b.axis, b.bin),
                    binner.below(x, s.axis, s.bin),
                    "case {case}"
                );
            }
        }
    }
}
