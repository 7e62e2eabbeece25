//! Pre-splitting of triangles whose box is much larger than they are, before the build
//! (early split clipping: Ernst and Greiner 2007; Karras and Aila, "Fast Parallel
//! Construction of High-Quality Bounding Volume Hierarchies", HPG 2013).
//!
//! A long diagonal sliver, an arch's or a column's, has a box mostly made of empty space,
//! and every node above it inherits that space. Before binning, such a triangle is cut into
//! several references to the same primitive, each with the box of the part of the triangle
//! in its cell, so the builder can place the parts apart. Each cut crosses the part's box on
//! its longest axis at the coarsest plane of a power-of-two grid anchored at the origin (the
//! multiple of the largest power of two inside the box), so neighbouring triangles are cut
//! on the same planes.
//!
//! - **Budget**: at most `fraction * n` extra references for `n` primitives, shared among
//!   the triangles in proportion to their priority (rounded down), the square root of the
//!   part of the box's surface area that the triangle's projected areas do not explain: a
//!   mesh of similar, well-shaped triangles gets no cuts at all. Priorities are integers
//!   when summed, so the shares, and the tree, are the same on any thread count.
//! - **Conservative boxes**: a part's box is the box of the triangle clipped to the cut's
//!   half-space, its clipped points widened on the two other axes by a margin far above the
//!   rounding of the clip (`2^-16` of the triangle's largest coordinate), then intersected
//!   with the box being cut. Every point of the triangle lies in the box of a part, so a ray
//!   that hits the triangle reaches one of its references and the hits stay bit-identical.
//!
//! Only triangles are split; other primitives keep one reference with their box.

use raybench_geometry::{Aabb, Geometry, Shape, Vec3};
use rayon::prelude::*;

/// Fixed-point scale of the integer priorities (the largest priority maps to `2^32`).
const PRIORITY_SCALE: f32 = 4_294_967_296.0;

/// How far a part's box is widened off the cutting axis, relative to the triangle's largest
/// coordinate: far above the rounding of the clip.
const MARGIN: f32 = 1.0 / 65_536.0;

/// The build's references, `make(box, id)` for every bounded primitive in `ids` (a triangle
/// chosen for cutting once per part): every primitive in its place, a cut one by its first
/// part, then the cut ones' other parts.
pub(crate) fn references<T: Send>(
    geometry: &Geometry,
    ids: &[u32],
    fraction: f32,
    make: impl Fn(Aabb, u32) -> T + Sync + Send,
) -> Vec<T> {
    let bounds = |id: u32| geometry.shape(id).bounds().unwrap_or(Aabb::EMPTY);
    let whole = || ids.par_iter().map(|&id| make(bounds(id), id)).collect();
    let budget = (f64::from(fraction.max(0.0)) * ids.len() as f64) as u128;
    if budget == 0 {
        return whole();
    }
    // The square root of the box area that the triangle's projections do not explain (0
    // for a degenerate triangle, which no ray hits).
    let excess = |shape: &Shape| match shape {
        Shape::Triangle(t) => {
            let n = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).abs();
            let projected = n.x + n.y + n.z;
            let e = (t.bounds().surface_area() - projected).max(0.0).sqrt();
            if e.is_finite() && projected > 0.0 {
                e
            } else {
                0.0
            }
        }
        _ => 0.0,
    };
    let excesses: Vec<f32> = ids
        .par_iter()
        .map(|&id| excess(geometry.shape(id)))
        .collect();
    let largest = excesses.par_iter().copied().reduce(|| 0.0, f32::max);
    if largest <= 0.0 {
        return whole();
    }
    let priority = |e: f32| u128::from((e / largest * PRIORITY_SCALE) as u64);
    let total: u128 = excesses.par_iter().map(|&e| priority(e)).sum();
    // Cuts of a primitive: its share of the budget, rounded down (most get none).
    let cuts = |e: f32| {
        let p = priority(e) * budget;
        if p < total { 0 } else { (p / total) as u32 }
    };
    if excesses.par_iter().all(|&e| cuts(e) == 0) {
        return whole();
    }
    // The parts' boxes of a primitive that is cut.
    let parts = |id: u32, e: f32| {
        let mut parts = Vec::new();
        if let Shape::Triangle(t) = geometry.shape(id) {
            let b = t.bounds();
            let margin = b.min.abs().max(b.max.abs()).max_element() * MARGIN;
            split(&t.v, b, cuts(e), margin, &mut |b| parts.push(b));
        }
        parts
    };
    // Every primitive in its place (a cut one by its first part), then the other parts.
    let rest: Vec<T> = ids
        .par_iter()
        .zip(excesses.par_iter())
        .filter(|&(_, &e)| cuts(e) > 0)
        .flat_map_iter(|(&id, &e)| parts(id, e).into_iter().skip(1).map(move |b| (b, id)))
        .map(|(b, id)| make(b, id))
        .collect();
    let mut all = Vec::with_capacity(ids.len() + rest.len());
    all.par_extend(ids.par_iter().zip(excesses.par_iter()).map(|(&id, &e)| {
        if cuts(e) == 0 {
            make(bounds(id), id)
        } else {
            make(parts(id, e).first().copied().unwrap_or(Aabb::EMPTY), id)
        }
    }));
    all.extend(rest);
    all
}

/// The coarsest plane of the power-of-two grid anchored at the origin (the multiple of the
/// largest power of two) strictly inside `(lo, hi)`, if any.
fn plane(lo: f32, hi: f32) -> Option<f32> {
    if !lo.is_finite() || !hi.is_finite() || lo >= hi {
        return None;
    }
    let span = hi - lo;
    // Start at a cell at least as large as the span: at most one of its planes lies inside.
    let mut cell = 2f32.powi(span.log2().ceil() as i32 + 1);
    for _ in 0..48 {
        let c = (lo / cell).floor() * cell + cell;
        if c > lo && c < hi {
            return Some(c);
        }
        cell *= 0.5;
    }
    None
}

/// Cuts the part of triangle `v` inside `bounds` with `splits` cuts, each on the box's
/// longest axis, and hands each part's box to `emit`.
fn split(v: &[Vec3; 3], bounds: Aabb, splits: u32, margin: f32, emit: &mut impl FnMut(Aabb)) {
    if splits == 0 {
        emit(bounds);
        return;
    }
    let e = bounds.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let Some(c) = plane(bounds.min[axis], bounds.max[axis]) else {
        emit(bounds);
        return;
    };
    let left = meet(clip(v, axis, c, false, margin), bounds);
    let right = meet(clip(v, axis, c, true, margin), bounds);
    if left.is_empty() && right.is_empty() {
        // Only for a degenerate clip; the part stays whole rather than be lost.
        emit(bounds);
        return;
    }
    let (al, ar) = (left.surface_area(), right.surface_area());
    let rest = splits - 1;
    let to_left = if al + ar > 0.0 {
        ((rest as f32) * al / (al + ar)).round() as u32
    } else {
        rest / 2
    }
    .min(rest);
    for (part, n) in [(left, to_left), (right, rest - to_left)] {
        if !part.is_empty() {
            split(v, part, n, margin, emit);
        }
    }
}

/// The common part of two boxes (empty when they do not overlap).
fn meet(a: Aabb, b: Aabb) -> Aabb {
    Aabb::new(a.min.max(b.min), a.max.min(b.max))
}

/// The box of triangle `v` clipped to the half-space below (`above == false`) or above
/// plane `c` on `axis`, the clip's edge points widened by `margin` on the other axes.
fn clip(v: &[Vec3; 3], axis: usize, c: f32, above: bool, margin: f32) -> Aabb {
    let inside = |p: Vec3| if above { p[axis] >= c } else { p[axis] <= c };
    let mut b = Aabb::EMPTY;
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        if inside(p) {
            b = b.grow(p);
        }
        if (p[axis] < c && q[axis] > c) || (p[axis] > c && q[axis] < c) {
            let mut x = p + (q - p) * ((c - p[axis]) / (q[axis] - p[axis]));
            x[axis] = c;
            let mut pad = Vec3::splat(margin);
            pad[axis] = 0.0;
            b = b.grow(x - pad).grow(x + pad);
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geometry::Triangle;

    fn sliver() -> Geometry {
        // A long thin triangle across the diagonal of a unit cube, and a small right triangle.
        Geometry::new(vec![
            Shape::Triangle(Triangle::new(
                Vec3::ZERO,
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, 1.0, 0.99),
            )),
            Shape::Triangle(Triangle::new(
                Vec3::new(0.0, 0.9, 0.0),
                Vec3::new(0.1, 0.9, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            )),
        ])
    }

    #[test]
    fn slivers_are_cut_into_parts_that_cover_them() {
        let g = sliver();
        let refs = references(&g, g.bounded(), 4.0, |b, id| (b, id));
        let parts: Vec<Aabb> = refs.iter().filter(|r| r.1 == 0).map(|r| r.0).collect();
        assert!(parts.len() > 2, "the sliver should be cut: {parts:?}");
        assert_eq!(refs.iter().filter(|r| r.1 == 1).count(), 1);
        let whole = g.shape(0).bounds().unwrap();
        let area: f32 = parts.iter().map(Aabb::surface_area).sum();
        assert!(area < 0.5 * whole.surface_area(), "{area} vs {whole:?}");
        // Every point of the triangle lies in some part.
        let Shape::Triangle(t) = g.shape(0) else {
            unreachable!()
        };
        for i in 0..=64 {
            for j in 0..=64 - i {
                let (u, w) = (i as f32 / 64.0, j as f32 / 64.0);
                let p = t.v[0] + (t.v[1] - t.v[0]) * u + (t.v[2] - t.v[0]) * w;
                assert!(
                    parts.iter().any(|b| b.contains(&Aabb::new(p, p))),
                    "{p} in no part"
                );
            }
        }
    }

    #[test]
    fn no_budget_keeps_one_reference_each() {
        let g = sliver();
        let refs = references(&g, g.bounded(), 0.0, |b, id| (b, id));
        assert_eq!(refs.len(), 2);
        assert_eq!(refs[0], (g.shape(0).bounds().unwrap(), 0));
    }
}
