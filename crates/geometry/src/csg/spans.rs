//! Span lists and the regularised interval algebra that combines them.

use crate::optree::Operator;
use glam::Vec3;

/// A CSG set operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    /// Points in either operand (`min(A, B)`).
    Union,
    /// Points in both operands (`max(A, B)`).
    Intersection,
    /// Points in the first operand and not the second (`max(A, -B)`).
    Difference,
}

impl CsgOp {
    /// Lower-case name used in scene files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Union => "union",
            Self::Intersection => "intersection",
            Self::Difference => "difference",
        }
    }

    #[inline]
    pub(super) fn apply(self, a: bool, b: bool) -> bool {
        match self {
            Self::Union => a || b,
            Self::Intersection => a && b,
            Self::Difference => a && !b,
        }
    }
}

impl Operator for CsgOp {
    const UNION: Self = Self::Union;
    const DIFFERENCE: Self = Self::Difference;
}

/// One end of a span: where, the outward normal of the combined solid there, and the leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct End {
    pub(super) t: f32,
    pub(super) normal: Vec3,
    pub(super) leaf: u32,
}

/// A closed interval of the ray's line inside a solid (`enter.t < exit.t`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Span {
    pub(super) enter: End,
    pub(super) exit: End,
}

/// The spans of a subtree: a leaf's (at most two, inline), or an operator's list.
pub(super) enum Spans {
    Leaf(LeafSpans),
    Many(Vec<Span>),
}

impl Spans {
    pub(super) fn as_slice(&self) -> &[Span] {
        match self {
            Self::Leaf(s) => &s.spans[..s.len],
            Self::Many(v) => v,
        }
    }
}

/// Up to two sorted, disjoint spans of one leaf, without a heap allocation.
pub(super) struct LeafSpans {
    pub(super) spans: [Span; 2],
    pub(super) len: usize,
}

impl LeafSpans {
    pub(super) const NONE: Self = Self {
        spans: [Span {
            enter: End {
                t: f32::NAN,
                normal: Vec3::ZERO,
                leaf: 0,
            },
            exit: End {
                t: f32::NAN,
                normal: Vec3::ZERO,
                leaf: 0,
            },
        }; 2],
        len: 0,
    };

    /// Appends `span` when it has positive length (tangent and NaN spans are dropped).
    pub(super) fn push(&mut self, span: Span) {
        if let Some(s) = finish(span) {
            self.spans[self.len] = s;
            self.len += 1;
        }
    }
}

/// Drops zero-length (tangent) and NaN spans.
#[inline]
pub(super) fn finish(span: Span) -> Option<Span> {
    (span.enter.t < span.exit.t).then_some(span)
}

/// Combines two sorted, disjoint span lists with `op` in one merge sweep. Events at the same
/// `t` are applied together (the first operand's first); a span starts or ends where the
/// combined state changes, with the normal of the last event of the group that moved the
/// state to its new value, negated when it comes from a subtracted operand.
#[inline]
pub(super) fn combine(op: CsgOp, a: &[Span], b: &[Span]) -> Vec<Span> {
    // Event k of a span list: span k / 2's entry (even k) or exit (odd k), read in place.
    struct Events<'a>(&'a [Span]);
    impl Events<'_> {
        fn len(&self) -> usize {
            2 * self.0.len()
        }
        fn get(&self, k: usize) -> Option<(End, bool)> {
            self.0.get(k / 2).map(|s| {
                if k.is_multiple_of(2) {
                    (s.enter, true)
                } else {
                    (s.exit, false)
                }
            })
        }
    }
    let (ea, eb) = (Events(a), Events(b));
    let (mut i, mut j) = (0, 0);
    let (mut in_a, mut in_b) = (false, false);
    let mut out = Vec::new();
    let mut open: Option<End> = None;
    while i < ea.len() || j < eb.len() {
        let t = match (ea.get(i), eb.get(j)) {
            (Some(x), Some(y)) => x.0.t.min(y.0.t),
            (Some(x), None) => x.0.t,
            (None, Some(y)) => y.0.t,
            (None, None) => break,
        };
        let before = op.apply(in_a, in_b);
        let mut chosen: Option<End> = None;
        while let Some((e, entering)) = ea.get(i).filter(|e| e.0.t == t) {
            in_a = entering;
            i += 1;
            if op.apply(in_a, in_b) != before {
                chosen = Some(e);
            }
        }
        while let Some((e, entering)) = eb.get(j).filter(|e| e.0.t == t) {
            in_b = entering;
            j += 1;
            if op.apply(in_a, in_b) != before {
                let normal = if op == CsgOp::Difference {
                    -e.normal
                } else {
                    e.normal
                };
                chosen = Some(End { normal, ..e });
            }
        }
        let after = op.apply(in_a, in_b);
        if after == before {
            continue;
        }
        let Some(e) = chosen else { continue };
        if after {
            open = Some(e);
        } else if let Some(enter) = open.take()
            && enter.t < e.t
        {
            out.push(Span { enter, exit: e });
        }
    }
    out
}
