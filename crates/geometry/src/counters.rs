//! Exact, free-when-off counts of the work a query does.

/// Counts of the work a query did. Implemented by [`RayCounters`] (counting) and
/// [`NoCounters`] (a zero-sized no-op, so counting is free when it is off: the choice is made
/// once per frame and monomorphised).
///
/// Counters are plain values owned by one work item (a tile) and summed when the work items
/// are reduced, so they are exact under any parallelism without atomics or thread-locals.
pub trait Counters: Default + Send {
    /// Whether this type counts at all.
    const ENABLED: bool;
    /// Adds `n` ray/primitive tests.
    fn add_tests(&mut self, n: u64);
    /// Adds `n` visits of acceleration-structure nodes or cells.
    fn add_visits(&mut self, n: u64);
    /// Adds another work item's counts.
    fn merge(&mut self, other: &Self);
    /// The counts, or `None` when this type does not count.
    fn counts(&self) -> Option<RayCounters>;
}

/// Exact counts of ray/primitive tests and node or cell visits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Ray/primitive intersection tests.
    pub prim_tests: u64,
    /// Node (BVH) or cell (grid) visits.
    pub node_visits: u64,
}

impl Counters for RayCounters {
    const ENABLED: bool = true;
    #[inline]
    fn add_tests(&mut self, n: u64) {
        self.prim_tests += n;
    }
    #[inline]
    fn add_visits(&mut self, n: u64) {
        self.node_visits += n;
    }
    fn merge(&mut self, other: &Self) {
        self.prim_tests += other.prim_tests;
        self.node_visits += other.node_visits;
    }
    fn counts(&self) -> Option<RayCounters> {
        Some(*self)
    }
}

/// Counters that count nothing and cost nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoCounters;

impl Counters for NoCounters {
    const ENABLED: bool = false;
    #[inline(always)]
    fn add_tests(&mut self, _: u64) {}
    #[inline(always)]
    fn add_visits(&mut self, _: u64) {}
    fn merge(&mut self, _: &Self) {}
    fn counts(&self) -> Option<RayCounters> {
        None
    }
}
