//! The 3D-DDA of Amanatides and Woo ("A Fast Voxel Traversal Algorithm for Ray Tracing",
//! 1987): the cells of a uniform grid that a ray crosses, in order. One walk serves the
//! uniform grids of `raybench-grid` (which cells' primitive lists a ray meets) and the voxel
//! volumes of `raybench-core` (which voxels a ray integrates, and which empty blocks it skips).

use glam::Vec3;
use std::ops::ControlFlow;

/// Walks the grid of `dims` unit cells (cell `c` covers `[c, c + 1]` on each axis) along the
/// ray `o + t d`, given in grid units, over `[t0, t1]`: calls `visit(cell, t_enter,
/// t_exit)` for each cell crossed, in order, until `visit` breaks or the ray leaves the grid
/// or passes `t1`.
///
/// The start cell is the one holding `o + t0 d` (clamped into the grid, so that the rounding
/// of the entry point never puts it outside). Each crossing distance is recomputed from the
/// cell index, `(border - o) / d`, when the walk steps across that axis, not accumulated,
/// so no error builds up along long walks. `t_exit` is clipped to `t1` and never precedes
/// `t_enter`: a cell crossed for a zero length (a ray through an edge or a corner) is
/// visited with `t_enter == t_exit`, and callers that integrate along the ray skip it.
/// A NaN or empty interval visits nothing.
pub fn dda(
    dims: [u32; 3],
    o: Vec3,
    d: Vec3,
    t0: f32,
    t1: f32,
    visit: &mut impl FnMut([u32; 3], f32, f32) -> ControlFlow<()>,
) -> ControlFlow<()> {
    // Also refuses NaN intervals.
    if t0 >= t1 || t0.is_nan() || t1.is_nan() || dims.contains(&0) {
        return ControlFlow::Continue(());
    }
    let p = o + d * t0;
    let mut cell = [0i64; 3];
    let mut step = [0i64; 3];
    for a in 0..3 {
        // `as` maps NaN to 0; the clamp keeps rounding inside.
        cell[a] = (p[a].floor() as i64).clamp(0, i64::from(dims[a]) - 1);
        step[a] = if d[a] > 0.0 {
            1
        } else if d[a] < 0.0 {
            -1
        } else {
            0
        };
    }
    // Distance at which the ray leaves `cell` across axis `a`'s border.
    let next = |cell: &[i64; 3], a: usize| -> f32 {
        if step[a] == 0 {
            f32::INFINITY
        } else {
            ((cell[a] + i64::from(step[a] > 0)) as f32 - o[a]) / d[a]
        }
    };
    let mut tn = [next(&cell, 0), next(&cell, 1), next(&cell, 2)];
    let mut t = t0;
    loop {
        // One comparison per axis: the border crossed first.
        let axis = if tn[0] <= tn[1] && tn[0] <= tn[2] {
            0
        } else if tn[1] <= tn[2] {
            1
        } else {
            2
        };
        let te = tn[axis].min(t1).max(t);
        visit([cell[0] as u32, cell[1] as u32, cell[2] as u32], t, te)?;
        t = te;
        if tn[axis] >= t1 || tn[axis].is_nan() {
            return ControlFlow::Continue(());
        }
        cell[axis] += step[axis];
        if cell[axis] < 0 || cell[axis] >= i64::from(dims[axis]) {
            return ControlFlow::Continue(());
        }
        tn[axis] = next(&cell, axis);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells and segments of one walk.
    fn walk(dims: [u32; 3], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Vec<([u32; 3], f32, f32)> {
        let mut out = Vec::new();
        let _ = dda(dims, o, d, t0, t1, &mut |c, a, b| {
            out.push((c, a, b));
            ControlFlow::Continue(())
        });
        out
    }

    #[test]
    fn an_axis_ray_crosses_its_row_in_order() {
        let cells = walk([4, 2, 2], Vec3::new(0.0, 0.5, 0.5), Vec3::X, 0.0, 4.0);
        let got: Vec<[u32; 3]> = cells.iter().map(|c| c.0).collect();
        assert_eq!(got, [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]);
        for (k, &(_, a, b)) in cells.iter().enumerate() {
            assert_eq!((a, b), (k as f32, k as f32 + 1.0));
        }
    }

    #[test]
    fn segments_are_contiguous_and_clipped_to_the_interval() {
        let d = Vec3::new(0.7, -0.3, 0.2);
        let cells = walk([8, 8, 8], Vec3::new(0.5, 7.5, 0.5), d, 0.25, 6.0);
        assert!(cells.len() > 3);
        assert_eq!(cells[0].1, 0.25);
        assert_eq!(cells.last().unwrap().2, 6.0);
        for w in cells.windows(2) {
            assert_eq!(w[0].2, w[1].1, "a gap or an overlap between cells");
            let steps: u32 = (0..3).map(|a| w[0].0[a].abs_diff(w[1].0[a])).sum();
            assert_eq!(steps, 1, "consecutive cells share a face");
        }
    }

    #[test]
    fn a_ray_through_a_corner_visits_the_zero_length_cell() {
        // Diagonal through the corner (1, 1): one of the two side cells is crossed for a
        // zero length; it is visited, with an empty segment.
        let cells = walk(
            [2, 2, 1],
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(1.0, 1.0, 0.0),
            0.0,
            2.0,
        );
        assert_eq!(cells.first().unwrap().0, [0, 0, 0]);
        assert_eq!(cells.last().unwrap().0, [1, 1, 0]);
        assert!(cells.iter().any(|&(_, a, b)| a == b));
    }

    #[test]
    fn empty_nan_and_breaking_walks_stop() {
        assert!(walk([2, 2, 2], Vec3::ZERO, Vec3::X, 1.0, 1.0).is_empty());
        assert!(walk([2, 2, 2], Vec3::ZERO, Vec3::X, f32::NAN, 1.0).is_empty());
        assert!(walk([0, 2, 2], Vec3::ZERO, Vec3::X, 0.0, 1.0).is_empty());
        let mut n = 0;
        let flow = dda(
            [8, 1, 1],
            Vec3::new(0.0, 0.5, 0.5),
            Vec3::X,
            0.0,
            8.0,
            &mut |_, _, _| {
                n += 1;
                if n == 3 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        );
        assert_eq!((n, flow), (3, ControlFlow::Break(())));
    }
}
