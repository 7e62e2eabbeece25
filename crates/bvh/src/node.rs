//! The flattened node.

use raybench_geometry::{Aabb, Vec3};

/// 32-byte node: Wald's layout. Interior nodes have their first child at the next index and
/// store the second child's index; leaves store a range of the primitive-id array.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    /// Box minimum.
    pub min: Vec3,
    /// Leaf: first index into the primitive-id array. Interior: index of the second child.
    pub first_or_right: u32,
    /// Box maximum.
    pub max: Vec3,
    /// Leaf: number of primitives (at least 1). Interior: 0.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    /// True for leaves.
    #[inline]
    #[must_use]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The node's box.
    #[inline]
    #[must_use]
    pub fn aabb(&self) -> Aabb {
        Aabb::new(self.min, self.max)
    }
}
