//! Bicubic Bezier patches on the GPU (`kernels/bezier.wgsl`, a port of
//! `raybench_geometry::BezierPatch::intersect_counted` and `BezierPatch::normal`).
//!
//! What the CPU precomputes per patch is precomputed here the same way, and what it computes
//! in f64 is prepared so that f32 suffices on the GPU:
//! - the patch is moved to its centre `c` (the middle of its control points' box): the
//!   kernels solve Newton's system for `S(u, v) - c` against the ray origin minus `c`, so
//!   the rounding of `F = S - o - t d` scales with the patch and the ray's distance to it,
//!   not with the coordinates' magnitude;
//! - the derivatives' control points (the hodographs `3 (P[i+1] - P[i])` along `u` and
//!   along `v`) are formed in f64 and rounded once: at a collapsed edge (coincident control
//!   points, as at the teapot's lid and bottom centres) they are exactly zero, so the
//!   kernels' `S_u x S_v` vanishes there as the CPU's f64 one does, and the normal takes the
//!   same fallback;
//! - the region tree's boxes ([`raybench_core::REGION_DEPTH`] levels) are the CPU's own
//!   ([`BezierPatch::region_boxes`], padded by [`BezierPatch::box_pad`]), copied bit for bit.
//!
//! The record: `a.xyz` the centre `c`; `b.x` the index of the patch's data in `geo` (bits),
//! `b.y` Newton's absolute tolerance ([`BezierPatch::tolerance`]), `b.z` the boxes' absolute
//! padding; `c.x` the largest coordinate of a control point relative to `c` (the scale of
//! the kernels' rounding), `c.y` the margin of the parameter square `[0, 1]^2` an accepted
//! hit may lie outside of (relative). `c.w` stays free (the emitter list's CDF).
//!
//! The data in `geo` from the index on, one entry per point (`xyz`, `w` unused):
//! at 0 the 16 control points minus `c` (`4 j + i` weighted by `B_i(u) B_j(v)`), then at
//! [`DU`] the 12 control points of `S_u` (`3 j + i`, `i < 3`), at [`DV`] the 12 of `S_v`
//! (`4 j + i`, `j < 3`), at [`BOXES`] the region tree's boxes in world space, two entries
//! (min, max) per node, level by level, row-major in `v` (node `(l, iu, iv)` is
//! `(4^l - 1) / 3 + 2^l iv + iu`).

use crate::records::{Geo, GpuPrim, next_index};
use raybench_core::{Aabb, BezierPatch, REGION_DEPTH};

/// Offset of the 12 control points of `S_u`.
pub(crate) const DU: u32 = 16;
/// Offset of the 12 control points of `S_v`.
pub(crate) const DV: u32 = 28;
/// Offset of the region tree's boxes.
pub(crate) const BOXES: u32 = 40;
/// Nodes of the region tree: `(4^(D+1) - 1) / 3`.
pub(crate) const NODES: u32 = ((1 << (2 * (REGION_DEPTH + 1))) - 1) / 3;
/// Entries of `geo` per patch.
pub(crate) const ENTRIES: u32 = BOXES + 2 * NODES;
/// Entries of the kernels' search stack: the region tree's nearest-first walk keeps at most
/// three siblings waiting per level, and so does the fallback subdivision below a leaf
/// (`raybench_geometry::bezier`'s `solve_region`, recursive on the CPU), plus the four
/// children of the deepest level being pushed.
pub(crate) const STACK: u32 = 3 * (REGION_DEPTH + raybench_core::FALLBACK_DEPTH) + 1;

/// Whether the kernels can intersect `x`, or why not: they can take any patch.
///
/// # Errors
/// Never.
#[allow(clippy::unnecessary_wraps)]
pub(crate) fn supports(_x: &BezierPatch) -> Result<(), String> {
    Ok(())
}

/// The record of `x`, its control points, derivative control points and region boxes
/// appended to `geo` (layout in the module documentation).
///
/// # Errors
/// When `geo` has grown past `u32` entries.
pub(crate) fn encode(x: &BezierPatch, geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x)?;
    let index = next_index(geo)?;
    index
        .checked_add(ENTRIES)
        .ok_or("the GPU's primitive data exceeds 2^32 entries")?;
    let points = x.points();
    let bounds = Aabb::from_points(*points);
    let c = bounds.center();
    let pad = x.box_pad();
    let c64 = [c.x, c.y, c.z].map(f64::from);
    let p64 = points.map(|p| [p.x, p.y, p.z].map(f64::from));
    let entry = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0];
    let mut scale = 0.0f64;
    for p in &p64 {
        let rel = [0, 1, 2].map(|k| p[k] - c64[k]);
        scale = rel.iter().fold(scale, |m, r| m.max(r.abs()));
        geo.push(entry(rel));
    }
    let diff = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|k| 3.0 * (b[k] - a[k]));
    for j in 0..4 {
        for i in 0..3 {
            geo.push(entry(diff(p64[4 * j + i], p64[4 * j + i + 1])));
        }
    }
    for j in 0..3 {
        for i in 0..4 {
            geo.push(entry(diff(p64[4 * j + i], p64[4 * (j + 1) + i])));
        }
    }
    for [lo, hi] in x.region_boxes() {
        geo.push([lo.x, lo.y, lo.z, 0.0]);
        geo.push([hi.x, hi.y, hi.z, 0.0]);
    }
    debug_assert_eq!(geo.len() as u64, u64::from(index) + u64::from(ENTRIES));
    Ok(GpuPrim {
        a: [c.x, c.y, c.z, 0.0],
        b: [f32::from_bits(index), x.tolerance() as f32, pad, 0.0],
        c: [scale as f32, raybench_core::UV_MARGIN as f32, 0.0, 0.0],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_core::Vec3;

    /// A curved patch: a grid bent into a bump.
    fn bump() -> BezierPatch {
        let points = std::array::from_fn(|k| {
            let (i, j) = ((k % 4) as f32, (k / 4) as f32);
            Vec3::new(i + 10.0, j - 3.0, (i - 1.5) * (j - 1.5) * 0.4 + 2.0)
        });
        BezierPatch::new(points).unwrap()
    }

    #[test]
    fn the_boxes_are_the_cpus() {
        let p = bump();
        let mut geo = Vec::new();
        encode(&p, &mut geo).unwrap();
        let boxes = &geo[BOXES as usize..];
        assert_eq!(boxes.len(), 2 * NODES as usize);
        for (k, [lo, hi]) in p.region_boxes().iter().enumerate() {
            assert_eq!(Vec3::from_slice(&boxes[2 * k]), Vec3::from(*lo));
            assert_eq!(Vec3::from_slice(&boxes[2 * k + 1]), Vec3::from(*hi));
        }
        let b = p.bounds();
        assert_eq!(
            (Vec3::from_slice(&boxes[0]), Vec3::from_slice(&boxes[1])),
            (b.min, b.max)
        );
    }

    #[test]
    fn the_layout_fills_its_entries() {
        let p = bump();
        let mut geo = vec![[0.0; 4]; 3];
        let r = encode(&p, &mut geo).unwrap();
        assert_eq!(geo.len(), 3 + ENTRIES as usize);
        assert_eq!(r.b[0].to_bits(), 3);
        let c = Vec3::from_slice(&r.a);
        // The control points relative to the centre, the scale their largest coordinate.
        for (k, q) in p.points().iter().enumerate() {
            let rel = Vec3::from_slice(&geo[3 + k]);
            assert!((rel + c - *q).abs().max_element() < 1e-6);
        }
        assert!(r.c[0] > 1.4 && r.c[0] < 1.6, "{}", r.c[0]);
        // S_u's first control point: 3 (P[1] - P[0]).
        let du = Vec3::from_slice(&geo[3 + DU as usize]);
        assert_eq!(du, 3.0 * (p.points()[1] - p.points()[0]));
        let dv = Vec3::from_slice(&geo[3 + DV as usize]);
        assert_eq!(dv, 3.0 * (p.points()[4] - p.points()[0]));
        assert_eq!(STACK, 22);
    }
}
