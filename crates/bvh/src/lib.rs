//! # raybench-bvh
//!
//! Two bounding volume hierarchies behind raybench's [`Accel`](raybench_core::Accel)
//! contract:
//!
//! - [`Bvh`] (backend `bvh`): the textbook structure, written here. A binned SAH builder
//!   (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007), parallel
//!   with rayon; a flattened depth-first layout of 32-byte nodes whose first child follows
//!   its parent; stack traversal, nearest child first, with strict early exits.
//! - [`ObvhsAccel`] (backend `obvhs`): the `obvhs` crate's production layout (PLOC with
//!   reinsertion, compressed wide CWBVH8 nodes) with its own traversal.
//!
//! Both keep unbounded primitives (planes) in a side list tested by every ray, and both
//! test primitives only through the core's routines, so their hits are bit-identical to the
//! naive backend's.

mod build;
mod node;
mod obvhs_adapter;
mod params;
mod traverse;

pub use node::Node;
pub use obvhs_adapter::ObvhsAccel;
pub use params::BvhParams;

use raybench_core::Geometry;
use std::sync::Arc;

/// The workspace's own BVH2.
#[derive(Clone, Debug)]
pub struct Bvh {
    geometry: Arc<Geometry>,
    /// Depth-first nodes; node 0 is the root, an interior node's first child is the next
    /// node. Empty when there are no bounded primitives.
    nodes: Vec<Node>,
    /// Primitive ids in leaf order; a leaf covers `prim_ids[first..first + count]`.
    prim_ids: Vec<u32>,
    params: BvhParams,
}

impl Bvh {
    /// The nodes, depth-first.
    #[must_use]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The primitive ids in leaf order.
    #[must_use]
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &BvhParams {
        &self.params
    }

    /// The geometry it was built over.
    #[must_use]
    pub fn geometry_arc(&self) -> &Arc<Geometry> {
        &self.geometry
    }

    /// Depth of the tree (a lone leaf has depth 1; 0 when empty).
    #[must_use]
    pub fn depth(&self) -> usize {
        fn rec(nodes: &[Node], i: usize) -> usize {
            let n = &nodes[i];
            if n.is_leaf() {
                1
            } else {
                1 + rec(nodes, i + 1).max(rec(nodes, n.first_or_right as usize))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            rec(&self.nodes, 0)
        }
    }

    /// Checks the structure's invariants: every bounded primitive in exactly one leaf and no
    /// unbounded one in any; every leaf non-empty and holding its primitives' boxes; every
    /// interior node with two children inside it; the depth-first layout (first child
    /// adjacent, every node reached exactly once).
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn validate(&self) -> Result<(), String> {
        let g = &*self.geometry;
        if self.nodes.is_empty() {
            return if g.bounded().is_empty() && self.prim_ids.is_empty() {
                Ok(())
            } else {
                Err("no nodes but bounded primitives exist".into())
            };
        }
        let mut seen = vec![0u32; g.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self
                .nodes
                .get(i)
                .ok_or_else(|| format!("child index {i} out of range"))?;
            if std::mem::replace(&mut reached[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            let bounds = node.aabb();
            if node.is_leaf() {
                let (first, count) = (node.first_or_right as usize, node.count as usize);
                if count == 0 {
                    return Err(format!("leaf {i} is empty"));
                }
                let ids = self
                    .prim_ids
                    .get(first..first + count)
                    .ok_or_else(|| format!("leaf {i} range out of bounds"))?;
                for &id in ids {
                    let b = g
                        .shapes()
                        .get(id as usize)
                        .and_then(raybench_core::Shape::bounds)
                        .ok_or_else(|| {
                            format!("leaf {i} holds unbounded or unknown primitive {id}")
                        })?;
                    if !bounds.contains(&b) {
                        return Err(format!("leaf {i} does not contain primitive {id}"));
                    }
                    seen[id as usize] += 1;
                }
            } else {
                let (l, r) = (i + 1, node.first_or_right as usize);
                if r <= l || r >= self.nodes.len() {
                    return Err(format!("interior node {i} has bad children {l}, {r}"));
                }
                for c in [l, r] {
                    if !bounds.contains(&self.nodes[c].aabb()) {
                        return Err(format!("child {c} sticks out of node {i}"));
                    }
                }
                stack.push(r);
                stack.push(l);
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Err(format!("node {i} is unreachable"));
        }
        for &id in g.bounded() {
            if seen[id as usize] != 1 {
                return Err(format!("primitive {id} is in {} leaves", seen[id as usize]));
            }
        }
        Ok(())
    }
}
