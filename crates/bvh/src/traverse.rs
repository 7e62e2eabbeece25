//! Closest-hit and any-hit traversal of the flattened BVH2.

use crate::Bvh;
use crate::Node;
use crate::build::MAX_DEPTH;
use raybench_geometry::traverse::{self, AnyHit, Closest};
use raybench_geometry::{
    Accel, AccelStats, Counters, Geometry, Hit, NodeStack, QualityParams, Ray, SlabRay,
    StructureQuality,
};
use std::sync::Arc;

/// Traversal stack: one entry per level plus the far children pushed on the way down.
const STACK_SIZE: usize = 2 * MAX_DEPTH + 4;

impl Accel for Bvh {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, crate::BvhParams::default())
    }

    const REFITS: bool = true;

    /// Boxes recomputed bottom up in one reverse pass over the depth-first nodes
    /// (`refit.rs`).
    fn refit(&mut self, geometry: Arc<Geometry>) -> bool {
        self.refit_to(geometry)
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        traverse::closest(&self.geometry, ray, counters, |q| self.walk_closest(q))
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        traverse::occluded(&self.geometry, ray, counters, |q| self.walk_any(q))
    }

    fn stats(&self) -> AccelStats {
        let leaves = self.nodes.iter().filter(|n| n.is_leaf()).count() as u64;
        AccelStats {
            memory_bytes: self.nodes.len() * std::mem::size_of::<crate::Node>()
                + self.prim_ids.len() * std::mem::size_of::<u32>(),
            counts: vec![
                ("nodes", self.nodes.len() as u64),
                ("leaves", leaves),
                ("depth", self.depth() as u64),
            ],
        }
    }

    fn quality(&self, params: &QualityParams) -> Option<StructureQuality> {
        let q = self
            .tree_view()
            .quality(&self.geometry, params, self.stats().memory_bytes);
        Some(StructureQuality::Tree(q))
    }
}

impl Bvh {
    /// The closest-hit walk: depth first, the nearer child first, nodes entered beyond the
    /// best hit so far skipped (rule 3).
    fn walk_closest<C: Counters>(&self, q: &mut Closest<'_, C>) {
        if self.nodes.is_empty() {
            return;
        }
        // Per-ray slab setup hoisted out of the loop: 1.1x to 1.2x on bunny rays.
        let slab = SlabRay::new(q.ray());
        let entry_of =
            |node: &Node, limit: f32| slab.entry(node.min.into(), node.max.into(), limit);
        let mut storage = [(0u32, 0.0f32); STACK_SIZE];
        let mut stack = NodeStack::new(&mut storage);
        let mut limit = q.limit();
        if let Some(t) = entry_of(&self.nodes[0], limit) {
            stack.push(0, t);
        }
        while let Some((index, _)) = stack.pop_within(limit) {
            q.add_visits(1);
            let node = &self.nodes[index as usize];
            if node.is_leaf() {
                let first = node.first_or_right as usize;
                for &id in &self.prim_ids[first..first + node.count as usize] {
                    q.test(id);
                }
                limit = q.limit();
                continue;
            }
            let (l, r) = (index + 1, node.first_or_right);
            let tl = entry_of(&self.nodes[l as usize], limit);
            let tr = entry_of(&self.nodes[r as usize], limit);
            // Near-child-first: push the far child first so the near one is popped next.
            match (tl, tr) {
                (Some(a), Some(b)) => {
                    let (near, far) = if a <= b {
                        ((l, a), (r, b))
                    } else {
                        ((r, b), (l, a))
                    };
                    stack.push(far.0, far.1);
                    stack.push(near.0, near.1);
                }
                (Some(a), None) => stack.push(l, a),
                (None, Some(b)) => stack.push(r, b),
                (None, None) => {}
            }
        }
    }

    /// The any-hit walk: depth first in any order, stopping at the first hit.
    fn walk_any<C: Counters>(&self, q: &mut AnyHit<'_, C>) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let ray = q.ray();
        let slab = SlabRay::new(ray);
        let hits_box = |node: &Node| {
            slab.entry(node.min.into(), node.max.into(), ray.t_max)
                .is_some()
        };
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        if hits_box(&self.nodes[0]) {
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            q.add_visits(1);
            let node = &self.nodes[stack[sp] as usize];
            if node.is_leaf() {
                let first = node.first_or_right as usize;
                for &id in &self.prim_ids[first..first + node.count as usize] {
                    if q.test(id) {
                        return true;
                    }
                }
                continue;
            }
            for child in [node.first_or_right, stack[sp] + 1] {
                if self.nodes[child as usize]
                    .aabb()
                    .intersect(ray, ray.t_max)
                    .is_some()
                {
                    stack[sp] = child;
                    sp += 1;
                }
            }
        }
        false
    }
}
