//! Refitting: the tree's boxes recomputed bottom up over another frame of its geometry, its
//! topology (nodes, leaves, primitive order) kept.
//!
//! The depth-first layout puts every child after its parent, so one pass over the nodes in
//! reverse order sees both children of a node before the node: a leaf's box becomes the
//! union of its primitives' boxes, an interior node's the union of its children's. Those are
//! the unions the builder takes (minimum and maximum are exact), so refitting a tree to the
//! geometry it was built over gives back its nodes bit for bit; over moved primitives the
//! boxes are tight again but the splits are the old ones, so the tree's SAH cost decays as
//! the primitives move away from where they were built.

use crate::Bvh;
use raybench_geometry::{Aabb, Geometry, same_topology};
use std::sync::Arc;

impl Bvh {
    /// [`raybench_geometry::Accel::refit`]: refits the tree to `geometry`, another frame of the geometry it was built over
    /// ([`same_topology`]); see the module documentation. Returns false, and changes
    /// nothing, when the topology differs (rebuild instead).
    pub(crate) fn refit_to(&mut self, geometry: Arc<Geometry>) -> bool {
        if !same_topology(&self.geometry, &geometry) {
            return false;
        }
        self.geometry = geometry;
        self.refit_boxes();
        true
    }

    /// One reverse pass over the nodes (children before parents).
    pub(crate) fn refit_boxes(&mut self) {
        let g = &*self.geometry;
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let b = if node.is_leaf() {
                let first = node.first_or_right as usize;
                self.prim_ids[first..first + node.count as usize]
                    .iter()
                    .fold(Aabb::EMPTY, |b, &id| {
                        b.union(g.shape(id).bounds().unwrap_or(Aabb::EMPTY))
                    })
            } else {
                self.nodes[i + 1]
                    .aabb()
                    .union(self.nodes[node.first_or_right as usize].aabb())
            };
            self.nodes[i].min = b.min;
            self.nodes[i].max = b.max;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams};
    use raybench_geometry::{Accel, Geometry, TwoLevel};
    use std::sync::Arc;

    /// The built-in moving scene (a twisting mesh, moving instances, a twisting instanced
    /// mesh) at frames 0 to 31.
    fn frames() -> Vec<Arc<Geometry>> {
        let scene = raybench_scene::load("moving", std::path::Path::new("/nonexistent"))
            .expect("the built-in moving scene loads");
        (0..32)
            .map(|f| Arc::clone(&scene.at_frame(f).unwrap().geometry))
            .collect()
    }

    /// Refitting to the geometry a tree was built over gives the built tree back, and a
    /// refitted tree is valid (every primitive's box in its leaf's, every child inside its
    /// parent) on every frame, while its SAH cost decays against a rebuilt tree's.
    #[test]
    fn refitted_trees_are_valid_on_every_frame_and_decay() {
        let frames = frames();
        let built = Bvh::build_with(Arc::clone(&frames[0]), BvhParams::default());
        let mut same = built.clone();
        assert!(same.refit_to(Arc::clone(&frames[0])));
        assert_eq!(same.nodes(), built.nodes());
        let mut tree = built.clone();
        for (f, g) in frames.iter().enumerate().skip(1) {
            assert!(tree.refit_to(Arc::clone(g)));
            tree.validate()
                .unwrap_or_else(|e| panic!("frame {f}: refitted tree: {e}"));
            assert_eq!(tree.prim_ids(), built.prim_ids(), "the topology is kept");
        }
        let rebuilt = Bvh::build_with(Arc::clone(&frames[31]), BvhParams::default());
        assert!(
            tree.sah_cost() > 1.1 * rebuilt.sah_cost(),
            "refitted {} against rebuilt {}",
            tree.sah_cost(),
            rebuilt.sah_cost()
        );
        // Another topology is refused, and nothing changes.
        let other = Arc::new(Geometry::new(vec![
            frames[0].shapes()[1].clone(),
            frames[0].shapes()[2].clone(),
        ]));
        let before = tree.nodes().to_vec();
        assert!(!tree.refit_to(other));
        assert_eq!(tree.nodes(), &before[..]);
    }

    /// Mutation check: a refit that leaves any one node's box as it was (a skipped node)
    /// yields a tree that `validate` rejects, so the tests above would catch such a refit.
    #[test]
    fn a_refit_that_skips_a_node_is_caught() {
        let frames = frames();
        let built = Bvh::build_with(Arc::clone(&frames[0]), BvhParams::default());
        let mut refitted = built.clone();
        assert!(refitted.refit_to(Arc::clone(&frames[12])));
        refitted.validate().unwrap();
        let mut caught = 0;
        let mut moved = 0;
        for i in 0..built.nodes().len() {
            if built.nodes()[i] == refitted.nodes()[i] {
                continue; // this node's box did not change: skipping it changes nothing
            }
            moved += 1;
            let mut broken = refitted.clone();
            broken.nodes[i].min = built.nodes()[i].min;
            broken.nodes[i].max = built.nodes()[i].max;
            caught += usize::from(broken.validate().is_err());
        }
        assert!(moved > 1000, "{moved} nodes moved");
        assert_eq!(caught, moved, "every stale box is caught");
    }

    /// The two-level form refits its flat part and the meshes that deform, and rebuilds its
    /// top level: every structure valid on every frame, the still mesh's untouched.
    #[test]
    fn two_level_refits_on_every_frame() {
        let frames = frames();
        let mut two = TwoLevel::<Bvh>::build(Arc::clone(&frames[0]));
        two.validate_top().unwrap();
        let still: Vec<_> = two.meshes().iter().map(|m| m.nodes().to_vec()).collect();
        for (f, g) in frames.iter().enumerate().skip(1) {
            assert!(two.refit(Arc::clone(g)), "frame {f}");
            two.flat().validate().unwrap();
            for (k, m) in two.meshes().iter().enumerate() {
                m.validate()
                    .unwrap_or_else(|e| panic!("frame {f}, mesh {k}: {e}"));
                let deforms = g.meshes()[k].shapes() != frames[0].meshes()[k].shapes();
                assert_eq!(m.nodes() != &still[k][..], deforms, "frame {f}, mesh {k}");
            }
            two.validate_top()
                .unwrap_or_else(|e| panic!("frame {f}: top level: {e}"));
        }
    }
}
