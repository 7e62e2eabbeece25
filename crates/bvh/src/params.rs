//! Build parameters with named presets.

/// Parameters of the binned SAH builder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhParams {
    /// Centroid bins per axis.
    pub bins: usize,
    /// Largest leaf; bigger nodes are always split (SAH decides below it).
    pub max_leaf_size: usize,
    /// Cost of one traversal step relative to one primitive test (the SAH's `C_t / C_i`).
    pub traversal_cost: f32,
    /// Nodes with at least this many primitives build their two subtrees in parallel.
    pub parallel_threshold: usize,
    /// Extra references allowed for triangles cut before the build, as a fraction of the
    /// primitive count (0: none; see the builder's pre-splitting). Cut triangles sit in
    /// several leaves, each time with the box of their part there.
    pub presplit: f32,
}

impl BvhParams {
    /// The pre-splitting budget of the `presplit` presets of `bvh` and `packet`
    /// ([`BvhParams::presplit`]): up to 30 % more references. On Sponza it halves the EPO of
    /// `packet`'s tree; the traversal moves by a few per cent either way (see
    /// docs/strategies.md), so no default preset splits.
    pub const PRESPLIT: f32 = 0.3;

    /// Fastest build: 8 bins, leaves of up to 8.
    #[must_use]
    pub const fn fast() -> Self {
        Self {
            bins: 8,
            max_leaf_size: 8,
            traversal_cost: 1.0,
            parallel_threshold: 4096,
            presplit: 0.0,
        }
    }

    /// The default: 16 bins, leaves of up to 4.
    #[must_use]
    pub const fn medium() -> Self {
        Self {
            bins: 16,
            max_leaf_size: 4,
            traversal_cost: 1.0,
            parallel_threshold: 4096,
            presplit: 0.0,
        }
    }

    /// Best trees: 32 bins, leaves of up to 2.
    #[must_use]
    pub const fn quality() -> Self {
        Self {
            bins: 32,
            max_leaf_size: 2,
            traversal_cost: 1.0,
            parallel_threshold: 4096,
            presplit: 0.0,
        }
    }

    /// The preset called `name` (`fast`, `medium`, `quality`).
    #[must_use]
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "fast" => Some(Self::fast()),
            "medium" => Some(Self::medium()),
            "quality" => Some(Self::quality()),
            _ => None,
        }
    }
}

impl Default for BvhParams {
    fn default() -> Self {
        Self::medium()
    }
}
