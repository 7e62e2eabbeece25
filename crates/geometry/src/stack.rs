//! The early-exit bound of rule 3 and the nearest-first stack every tree walk uses.

/// Relative slack of early-exit comparisons: a node or cell is skipped only when its entry
/// distance exceeds [`cull_bound`]`(best_t)`, slightly more than the best `t`.
///
/// Rule 3 of the contract compares a box's entry distance with a primitive's `t`, two
/// numbers computed by different routines, each with its own rounding. A primitive hit at
/// `t` lies inside its box, so the box's true entry is at most the true `t`; but the
/// computed entry can exceed the computed `t` by a few ulps (the slab test rounds twice, the
/// triangle test a handful of times). Without slack, two coincident triangles in different
/// leaves (equal `t`, the tie going to the smaller id) could see the smaller id's leaf
/// skipped. `2^-16` relative dwarfs those few ulps (`~2^-21`) and costs no measurable
/// extra visits.
pub const CULL_SLACK: f32 = 1.0 / 65_536.0;

/// The largest entry distance at which a node or cell must still be visited when the best
/// hit so far is at `best_t` (see [`CULL_SLACK`]).
#[inline]
#[must_use]
pub fn cull_bound(best_t: f32) -> f32 {
    best_t + best_t.abs() * CULL_SLACK
}

/// The nearest-first traversal stack of every tree walk in the workspace: `(node, entry
/// distance)` pairs over storage the caller owns (a fixed array on the stack, or one
/// allocation a batch reuses), which pops only the entries that pass the strict early exit
/// of rule 3: entries entered beyond the current limit are dropped. `N` names a node: an
/// index into a BVH (`u32`, the default), or a `(level, i, j)` cell of a height field's
/// min-max quadtree or of a Bezier patch's region tree.
#[derive(Debug)]
pub struct NodeStack<'a, N: Copy = u32> {
    entries: &'a mut [(N, f32)],
    len: usize,
}

impl<'a, N: Copy> NodeStack<'a, N> {
    /// An empty stack over `storage` (its capacity).
    #[inline]
    pub fn new(storage: &'a mut [(N, f32)]) -> Self {
        Self {
            entries: storage,
            len: 0,
        }
    }

    /// Pushes `node`, entered at `entry`.
    ///
    /// # Panics
    /// When the storage is full (a traversal deeper than it was sized for).
    #[inline]
    pub fn push(&mut self, node: N, entry: f32) {
        self.entries[self.len] = (node, entry);
        self.len += 1;
    }

    /// The most recently pushed entry whose entry distance is at most `limit`
    /// ([`cull_bound`] of the best hit so far), dropping those above it.
    #[inline]
    pub fn pop_within(&mut self, limit: f32) -> Option<(N, f32)> {
        while self.len > 0 {
            self.len -= 1;
            let e = self.entries[self.len];
            // Strict: skip only entries *beyond* the limit (an equal one may hold a tie).
            if e.1 > limit {
                continue;
            }
            return Some(e);
        }
        None
    }
}
