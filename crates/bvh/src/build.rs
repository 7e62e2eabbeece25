//! Binned SAH construction (Wald 2007), parallel over subtrees with rayon, then flattened
//! depth-first.

use crate::Bvh;
use crate::node::Node;
use crate::params::BvhParams;
use raybench_core::{Aabb, Geometry, Vec3};
use std::sync::Arc;

/// Build depth limit: a node this deep becomes a leaf whatever its size, which bounds the
/// traversal stack. Binned SAH on real scenes stays far below it.
pub(crate) const MAX_DEPTH: usize = 60;

/// One bounded primitive while building.
#[derive(Clone, Copy, Debug)]
struct Item {
    bounds: Aabb,
    centroid: Vec3,
    id: u32,
}

/// The unflattened tree.
enum BuildNode {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[BuildNode; 2]>,
    },
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

/// Largest supported bin count.
const MAX_BINS: usize = 64;

/// Where to split: an axis and a bin boundary, with the binning that decides sides.
#[derive(Clone, Copy)]
struct Split {
    axis: usize,
    bin: usize,
    cmin: f32,
    scale: f32,
    bins: usize,
}

impl Split {
    #[inline]
    fn bin_of(&self, c: Vec3) -> usize {
        // Truncation of a non-negative finite number; clamped so the largest centroid lands
        // in the last bin.
        let b = ((c[self.axis] - self.cmin) * self.scale) as usize;
        b.min(self.bins - 1)
    }

    #[inline]
    fn goes_left(&self, c: Vec3) -> bool {
        self.bin_of(c) < self.bin
    }
}

impl Bvh {
    /// Builds over the bounded primitives of `geometry` with `params`.
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: BvhParams) -> Self {
        let mut params = params;
        params.bins = params.bins.clamp(2, MAX_BINS);
        params.max_leaf_size = params.max_leaf_size.max(1);
        let mut items: Vec<Item> = geometry
            .bounded()
            .iter()
            .map(|&id| {
                let bounds = geometry.shape(id).bounds().unwrap_or(Aabb::EMPTY);
                Item {
                    bounds,
                    centroid: bounds.center(),
                    id,
                }
            })
            .collect();
        let mut nodes = Vec::new();
        if !items.is_empty() {
            let root = build_rec(&mut items, 0, &params, 0);
            nodes.reserve(2 * items.len());
            flatten(&root, &mut nodes);
        }
        Self {
            geometry,
            nodes,
            prim_ids: items.iter().map(|it| it.id).collect(),
            params,
        }
    }
}

fn bounds_of(items: &[Item]) -> (Aabb, Aabb) {
    let mut bounds = Aabb::EMPTY;
    let mut centroids = Aabb::EMPTY;
    for it in items {
        bounds = bounds.union(it.bounds);
        centroids = centroids.grow(it.centroid);
    }
    (bounds, centroids)
}

/// The cheapest SAH split over all axes and bin boundaries, and its cost relative to a
/// leaf's (`C_i` = 1 per primitive).
fn find_split(
    items: &[Item],
    bounds: Aabb,
    centroids: Aabb,
    params: &BvhParams,
) -> Option<(Split, f32)> {
    let area = bounds.surface_area();
    if !(area > 0.0 && area.is_finite()) {
        return None;
    }
    let bins = params.bins;
    let mut best: Option<(Split, f32)> = None;
    let extent = centroids.extent();
    for axis in 0..3 {
        if !(extent[axis] > 0.0 && extent[axis].is_finite()) {
            continue;
        }
        let split = Split {
            axis,
            bin: 0,
            cmin: centroids.min[axis],
            scale: bins as f32 / extent[axis],
            bins,
        };
        let mut bin = [EMPTY_BIN; MAX_BINS];
        for it in items {
            let b = &mut bin[split.bin_of(it.centroid)];
            b.bounds = b.bounds.union(it.bounds);
            b.count += 1;
        }
        // Sweep from the right to get the right-hand areas and counts, then from the left.
        let mut right_area = [0.0f32; MAX_BINS];
        let mut right_count = [0usize; MAX_BINS];
        let mut acc = EMPTY_BIN;
        for i in (1..bins).rev() {
            acc.bounds = acc.bounds.union(bin[i].bounds);
            acc.count += bin[i].count;
            right_area[i] = acc.bounds.surface_area();
            right_count[i] = acc.count;
        }
        let mut left = EMPTY_BIN;
        for i in 1..bins {
            left.bounds = left.bounds.union(bin[i - 1].bounds);
            left.count += bin[i - 1].count;
            if left.count == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = params.traversal_cost
                + (left.bounds.surface_area() * left.count as f32
                    + right_area[i] * right_count[i] as f32)
                    / area;
            if cost.is_finite() && best.is_none_or(|(_, c)| cost < c) {
                best = Some((Split { bin: i, ..split }, cost));
            }
        }
    }
    best
}

fn leaf(bounds: Aabb, first: usize, count: usize) -> BuildNode {
    BuildNode::Leaf {
        bounds,
        first: first as u32,
        count: count as u32,
    }
}

fn build_rec(items: &mut [Item], first: usize, params: &BvhParams, depth: usize) -> BuildNode {
    let n = items.len();
    let (bounds, centroids) = bounds_of(items);
    if n == 1 || depth >= MAX_DEPTH {
        return leaf(bounds, first, n);
    }
    let mid = match find_split(items, bounds, centroids, params) {
        Some((split, cost)) if cost < n as f32 || n > params.max_leaf_size => {
            partition(items, |it| split.goes_left(it.centroid))
        }
        Some(_) => return leaf(bounds, first, n),
        None if n > params.max_leaf_size => {
            // All centroids coincide (or the box is degenerate): split by count.
            n / 2
        }
        None => return leaf(bounds, first, n),
    };
    let (left, right) = items.split_at_mut(mid);
    let (l, r) = if n >= params.parallel_threshold {
        rayon::join(
            || build_rec(left, first, params, depth + 1),
            || build_rec(right, first + mid, params, depth + 1),
        )
    } else {
        (
            build_rec(left, first, params, depth + 1),
            build_rec(right, first + mid, params, depth + 1),
        )
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([l, r]),
    }
}

/// In-place partition; returns the number of items for which `left` holds, now at the
/// front.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    let mut j = items.len();
    while i < j {
        if left(&items[i]) {
            i += 1;
        } else {
            j -= 1;
            items.swap(i, j);
        }
    }
    i
}

fn flatten(node: &BuildNode, out: &mut Vec<Node>) {
    match node {
        BuildNode::Leaf {
            bounds,
            first,
            count,
        } => out.push(Node {
            min: bounds.min,
            first_or_right: *first,
            max: bounds.max,
            count: *count,
        }),
        BuildNode::Interior { bounds, children } => {
            let me = out.len();
            out.push(Node {
                min: bounds.min,
                first_or_right: 0,
                max: bounds.max,
                count: 0,
            });
            flatten(&children[0], out);
            out[me].first_or_right = out.len() as u32;
            flatten(&children[1], out);
        }
    }
}
