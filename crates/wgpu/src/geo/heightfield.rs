//! Height fields on the GPU (`kernels/heightfield.wgsl`): the record and the `geo` data of
//! raybench-geometry's [`HeightField`], whose closest hit (`HeightField::intersect` with the
//! min-max tree walk `walk_tree` and the cell test `test_cell`) and shading normal
//! (`HeightField::normal`) the kernels port.
//!
//! # What the kernels get
//!
//! The cell triangles are the CPU's, bit for bit: the world-space vertices are written
//! here with [`HeightField::vertex`] (the CPU's `transform_point3` of each vertex), and the
//! kernels test cell `(i, j)`'s triangles `2 c` = `(p00, p01, p11)` and `2 c + 1` =
//! `(p00, p11, p10)` (`c = j nx + i`) with the workspace's watertight triangle test
//! (`triangle_hit`, as for mesh triangles) against the original world-space ray. The
//! closest hit is the CPU's: smallest `t`, ties to the smaller sub-primitive id (the
//! triangle's clip is the best `t` so far, inclusive, and `keep_closer`'s rule picks). The
//! result does not depend on the order the cells are tested in, so the walk's rounding
//! (which only decides which cells to test, conservatively) never changes a hit; `t`, `u`,
//! `v` differ from the CPU's only by the GPU's rounding of the triangle test (division not
//! correctly rounded, possible fused multiply-adds, no f64 retry of a zero edge function),
//! as for mesh triangles.
//!
//! The min-max tree is the CPU's quadtree: level `l` holds blocks of `2^l x 2^l` cells,
//! `dims(l) = (ceil(nx / 2^l), ceil(nz / 2^l))` of them, row-major, the top level a single
//! block. Where the CPU keeps each block's object-space height range and derives its world
//! box on each visit (exact without a placement; with one, the padded bounds of the
//! transformed corners), the GPU keeps each block's world box for levels 1 and up: the
//! bounds of the world vertices of its cells, computed here (unions of the children's
//! boxes, exact in f32). Without a placement these are the CPU's boxes exactly; with one
//! they are tighter than the CPU's padded ones and still hold every triangle of the block
//! (a triangle lies in the bounds of its vertices). A cell's box (level 0) is the bounds of
//! its four vertices, made by the kernel from the vertices it loads for the triangle test.
//! The walk is the CPU's: depth first from the top block, the children visited in the order
//! of the signs of the object-space direction's x and z (nearest first), each entered with
//! the workspace's conservative slab test (`box_entry`, `SlabRay::entry`) against the
//! culling limit `cull_bound(best t)`, popped entries beyond the limit skipped. The one
//! change: the cells of a level-1 block are tested when the block is opened, nearest first,
//! instead of being pushed and popped at once (the same cells, in the same order, each
//! entered against the same limit).
//!
//! Shading normals port `HeightField::normal`: the triangle's geometric normal, or with
//! smooth normals the barycentric blend of the vertices' object-space normals (central
//! differences of the heights over the object-space x and z, one-sided at the borders),
//! carried to world space by the inverse transpose of the placement (computed here, as the
//! CPU computes it, in f32), normalised (the geometric normal where that fails) and turned
//! to the geometric normal's side.
//!
//! # Layout
//!
//! The record: `a = (header, nx, nz, kind)`, `b = (vertices, top level, smooth, id)`,
//! `c = (xs, zs, bilinear, emitter weight)`, integers by their bits, each a `geo` index:
//!
//! - `header`: three entries, the columns of the normals' matrix (the inverse transpose of
//!   the placement's linear part, the identity without one; its rows 0 and 2 turn the ray
//!   direction into object space for the visiting order), then `ceil(top / 4)` entries of
//!   level bases: the `geo` index of level `l`'s first box in component `(l - 1) % 4` of
//!   entry `(l - 1) / 4`.
//! - `xs`, `zs`: the object-space x of each vertex column and z of each vertex row, four to
//!   an entry (the CPU's own values, [`HeightField::object_xz`]).
//! - `vertices`: one entry per vertex, row by row: the world position and, in `w`, the
//!   object-space height.
//! - level `l` (1 to top): two entries per block, its box's minimum and maximum.
//!
//! Memory: 16 bytes per vertex plus 32 bytes per block (about a third of the cells), so
//! about 27 bytes per cell (28 MB for the 1024^2-cell `heightfield` scene).
//!
//! Bilinear cells ([`CellSurface::Bilinear`]) take the same walk; a cell's test is then
//! `BilinearPatch::intersect` (`bilinear_hit` in `kernels/bilinear.wgsl`, Reshetov's
//! quadratic in `u`) of the patch through the cell's four world vertices
//! ([`HeightField::cell_patch`]), clipped to the best `t` so far and kept under the id `2 c`,
//! and the normal `HeightField::normal`'s for such cells: the negated patch normal
//! (`BilinearPatch::normal`), or with smooth normals the bilinear blend (weights of the
//! patch's `u`, `v`) of the four vertex normals. The patch lies in the bounds of its
//! corners, so the walk's boxes hold it. The patch test computes in f32 as the CPU's does;
//! the GPU's quotient and square root are not correctly rounded (2.5 ULP and about 1 ULP),
//! so `u` and `t` differ by a few ULPs of the quadratic's conditioning, as for the Bezier
//! patches' last resort, which shares the routine.
//!
//! The 2D-DDA traversal finds the same hits as the tree (the CPU's tests
//! assert it), so a field that asks for it is walked with the tree here.

use crate::records::{Geo, GpuPrim, next_index};
use raybench_core::{CellSurface, HeightField, Vec3, Vec3A};

/// Entries of the kernels' walk stack (written into the kernels' source as `HF_STACK` by
/// `constants.rs`). The walk keeps at most three waiting
/// siblings per level above the cells and the block being opened: `3 (top - 1) + 1`
/// entries for a tree of `top` levels above the cells. The vertex limit
/// (`MAX_HEIGHT_FIELD_VERTICES` = 2^26, at least two vertices per side) bounds a side at
/// 2^25 - 1 cells and so `top` at 25: 73 entries.
pub(crate) const HF_STACK: u32 = 73;

/// Blocks per side of level `l` (level 0: single cells): `HeightField::dims`.
fn dims(nx: u32, nz: u32, l: u32) -> (u32, u32) {
    (((nx - 1) >> l) + 1, ((nz - 1) >> l) + 1)
}

/// The level of the single top block: the first `l` with `dims(l) == (1, 1)`.
fn top_level(nx: u32, nz: u32) -> u32 {
    let mut l = 0;
    while dims(nx, nz, l) != (1, 1) {
        l += 1;
    }
    l
}

/// Stack entries the walk needs for a tree of `top` levels above the cells.
fn stack_need(top: u32) -> u32 {
    if top == 0 { 0 } else { 3 * (top - 1) + 1 }
}

/// `geo` entries the field takes (see the layout in the module documentation).
fn entries(nx: u32, nz: u32) -> u64 {
    let top = top_level(nx, nz);
    let (nx, nz) = (u64::from(nx), u64::from(nz));
    let blocks: u64 = (1..=top)
        .map(|l| {
            let (w, h) = dims(nx as u32, nz as u32, l);
            u64::from(w) * u64::from(h)
        })
        .sum();
    3 + u64::from(top).div_ceil(4)
        + (nx + 1).div_ceil(4)
        + (nz + 1).div_ceil(4)
        + (nx + 1) * (nz + 1)
        + 2 * blocks
}

/// Whether the kernels can intersect `x`, or why not: the walk's stack must hold the tree ([`HF_STACK`]) and the data must be addressable with
/// `u32` indices.
///
/// # Errors
/// The reason, naming height fields.
pub(crate) fn supports(x: &HeightField) -> Result<(), String> {
    let (nx, nz) = x.cells();
    let top = top_level(nx, nz);
    if stack_need(top) > HF_STACK {
        return Err(format!(
            "a height field of {nx} x {nz} cells has a min-max tree of {top} levels, deeper \
             than the GPU walk's stack of {HF_STACK} entries holds (render it with a CPU \
             backend)"
        ));
    }
    let need = entries(nx, nz);
    if need > u64::from(u32::MAX) {
        return Err(format!(
            "a height field of {nx} x {nz} cells needs {need} GPU data entries, more than \
             32-bit indices address (render it with a CPU backend)"
        ));
    }
    Ok(())
}

/// Appends `values` to `geo`, four to an entry, and returns the index of the first.
fn push_packed(geo: &mut Geo, values: impl Iterator<Item = f32>) -> Result<u32, String> {
    let first = next_index(geo)?;
    let values: Vec<f32> = values.collect();
    for chunk in values.chunks(4) {
        let mut e = [0.0; 4];
        e[..chunk.len()].copy_from_slice(chunk);
        geo.push(e);
    }
    Ok(first)
}

/// The record of `x`, its data appended to `geo` (the layout of the module documentation).
///
/// # Errors
/// See [`supports`]; also when `geo` as a whole outgrows `u32` indices.
pub(crate) fn encode(x: &HeightField, geo: &mut Geo) -> Result<GpuPrim, String> {
    supports(x)?;
    let bits = f32::from_bits;
    let (nx, nz) = x.cells();
    let top = top_level(nx, nz);
    // The normals' matrix, as `HeightField::normal` computes it (`Mat3A` columns).
    let columns = x.transform().map_or([Vec3A::X, Vec3A::Y, Vec3A::Z], |a| {
        let m = a.matrix3.inverse().transpose();
        [m.x_axis, m.y_axis, m.z_axis]
    });
    let header = next_index(geo)?;
    for c in columns {
        geo.push([c.x, c.y, c.z, 0.0]);
    }
    let bases_at = geo.len();
    for _ in 0..top.div_ceil(4) {
        geo.push([0.0; 4]);
    }
    let xs = push_packed(geo, (0..=nx).map(|i| x.object_xz(i, 0).0))?;
    let zs = push_packed(geo, (0..=nz).map(|j| x.object_xz(0, j).1))?;
    let vertices = next_index(geo)?;
    let heights = x.heights();
    let row = nx as usize + 1;
    for j in 0..=nz {
        for i in 0..=nx {
            let p = x.vertex(i, j);
            geo.push([p.x, p.y, p.z, heights[j as usize * row + i as usize]]);
        }
    }
    // Level 1 from the vertices of each block's cells, each next level from its children.
    let vertex = |i: u32, j: u32| {
        let e = geo[vertices as usize + j as usize * row + i as usize];
        Vec3::new(e[0], e[1], e[2])
    };
    let mut boxes: Vec<(Vec3, Vec3)> = Vec::new();
    if top >= 1 {
        let (w, h) = dims(nx, nz, 1);
        for bj in 0..h {
            for bi in 0..w {
                let mut b = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for j in 2 * bj..=(2 * bj + 2).min(nz) {
                    for i in 2 * bi..=(2 * bi + 2).min(nx) {
                        let p = vertex(i, j);
                        b = (b.0.min(p), b.1.max(p));
                    }
                }
                boxes.push(b);
            }
        }
    }
    let mut bases = Vec::with_capacity(top as usize);
    for l in 1..=top {
        bases.push(next_index(geo)?);
        for &(lo, hi) in &boxes {
            geo.push([lo.x, lo.y, lo.z, 0.0]);
            geo.push([hi.x, hi.y, hi.z, 0.0]);
        }
        if l < top {
            let (pw, ph) = dims(nx, nz, l);
            let (w, h) = dims(nx, nz, l + 1);
            let mut next = Vec::with_capacity(w as usize * h as usize);
            for bj in 0..h {
                for bi in 0..w {
                    let mut b = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                    for j in 2 * bj..(2 * bj + 2).min(ph) {
                        for i in 2 * bi..(2 * bi + 2).min(pw) {
                            let c = boxes[(j * pw + i) as usize];
                            b = (b.0.min(c.0), b.1.max(c.1));
                        }
                    }
                    next.push(b);
                }
            }
            boxes = next;
        }
    }
    for (k, base) in bases.into_iter().enumerate() {
        geo[bases_at + k / 4][k % 4] = bits(base);
    }
    // Every index the kernels form stays below the buffer's length.
    next_index(geo)?;
    Ok(GpuPrim {
        a: [bits(header), bits(nx), bits(nz), 0.0],
        b: [
            bits(vertices),
            bits(top),
            bits(u32::from(x.smooth_normals())),
            0.0,
        ],
        c: [
            bits(xs),
            bits(zs),
            bits(u32::from(x.surface() == CellSurface::Bilinear)),
            0.0,
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stack_holds_the_deepest_field() {
        // The deepest fields the vertex limit allows: one cell row, and a square.
        let side = (raybench_core::limits::MAX_HEIGHT_FIELD_VERTICES / 2 - 1) as u32;
        assert_eq!(top_level(side, 1), 25);
        assert!(stack_need(top_level(side, 1)) <= HF_STACK);
        assert_eq!(top_level(4096, 4096), 12);
        assert_eq!(top_level(1, 1), 0);
        assert_eq!(top_level(2, 1), 1);
        assert_eq!(top_level(5, 3), 3);
    }

    #[test]
    fn the_layout_fills_what_entries_counts_and_the_boxes_hold_their_cells() {
        let (nx, nz) = (7u32, 5u32);
        let heights: Vec<f32> = (0..(nx + 1) * (nz + 1))
            .map(|k| ((k * 37 % 11) as f32) * 0.05)
            .collect();
        let a = raybench_core::Affine3A::from_translation(Vec3::new(0.1, 0.0, -0.2))
            * raybench_core::Affine3A::from_rotation_y(0.3)
            * raybench_core::Affine3A::from_scale(Vec3::new(1.0, 2.0, 0.5));
        let f = HeightField::new(nx, nz, heights, Some(a)).unwrap();
        let mut geo = vec![[9.0; 4]; 3];
        let p = encode(&f, &mut geo).unwrap();
        assert_eq!(geo.len() as u64 - 3, entries(nx, nz));
        assert_eq!(p.a[0].to_bits(), 3);
        let top = p.b[1].to_bits();
        assert_eq!(top, 3);
        let v0 = p.b[0].to_bits() as usize;
        assert_eq!(geo[v0 + 9][..3], f.vertex(1, 1).to_array());
        // The top box holds every vertex, and is their bounds.
        let bases = geo[3 + 3];
        let t = bases[(top - 1) as usize].to_bits() as usize;
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        for j in 0..=nz {
            for i in 0..=nx {
                lo = lo.min(f.vertex(i, j));
                hi = hi.max(f.vertex(i, j));
            }
        }
        assert_eq!(geo[t][..3], lo.to_array());
        assert_eq!(geo[t + 1][..3], hi.to_array());
        // Bilinear cells are marked in the record.
        let bilinear = f.clone().with_surface(CellSurface::Bilinear);
        let mut g = Vec::new();
        assert_eq!(encode(&bilinear, &mut g).unwrap().c[2].to_bits(), 1);
        assert_eq!(p.c[2].to_bits(), 0);
    }
}
