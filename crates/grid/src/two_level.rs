//! The two-level grid: a uniform grid whose crowded cells hold a grid of their own, which
//! fixes the "teapot in a stadium" (a small detailed object inside a large empty box).

use crate::traverse::Mailbox;
use crate::{Grid, GridParams};
use raybench_geometry::traverse;
use raybench_geometry::{
    Aabb, Accel, AccelStats, Counters, Geometry, GridQuality, Hit, QualityParams, Ray,
    StructureQuality, Vec3,
};
use std::sync::Arc;

/// Parameters of the two-level grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoLevelParams {
    /// Parameters of the top level and of each sub-grid (each sized for its own primitives).
    pub grid: GridParams,
    /// Cells listing more primitives than this get a sub-grid.
    pub dense: usize,
}

impl Default for TwoLevelParams {
    fn default() -> Self {
        Self {
            grid: GridParams::default(),
            dense: 32,
        }
    }
}

/// A top-level uniform grid plus a sub-grid for every dense cell.
#[derive(Clone, Debug)]
pub struct TwoLevelGrid {
    params: TwoLevelParams,
    top: Grid,
    /// For each top cell, an index into `subs` or `u32::MAX`.
    sub_of: Vec<u32>,
    subs: Vec<Grid>,
}

impl TwoLevelGrid {
    /// Builds the top level, then a sub-grid over each cell listing more than
    /// `params.dense` primitives, spanning the part of that cell's (padded) box its
    /// primitives occupy; primitives reaching beyond it are listed in its border sub-cells,
    /// and the sub-grid pads its own box as every grid does.
    #[must_use]
    pub fn build_with(geometry: Arc<Geometry>, params: TwoLevelParams) -> Self {
        let top = Grid::build_with(Arc::clone(&geometry), params.grid);
        let cells = top.offsets.len() - 1;
        let mut sub_of = vec![u32::MAX; cells];
        let mut subs = Vec::new();
        let res = top.res;
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let i = top.cell_index([x, y, z]);
                    let ids = &top.ids[top.offsets[i] as usize..top.offsets[i + 1] as usize];
                    if ids.len() <= params.dense {
                        continue;
                    }
                    let lo = top.bounds.min + top.cell * Vec3::new(x as f32, y as f32, z as f32);
                    let cell_box = Aabb::new(lo - top.pad, lo + top.cell + top.pad);
                    // Shrink to what the cell's primitives occupy (the teapot, not its cell
                    // of the stadium), so the sub-grid's cells follow the detail.
                    let occupied = ids
                        .iter()
                        .filter_map(|&id| geometry.shape(id).bounds())
                        .fold(Aabb::EMPTY, Aabb::union);
                    let region = Aabb::new(
                        cell_box.min.max(occupied.min),
                        cell_box.max.min(occupied.max),
                    );
                    sub_of[i] = subs.len() as u32;
                    subs.push(Grid::build_over(
                        Arc::clone(&geometry),
                        ids.to_vec(),
                        region,
                        params.grid,
                    ));
                }
            }
        }
        Self {
            params,
            top,
            sub_of,
            subs,
        }
    }

    /// Calls `test(ids)` for the primitive lists along `ray`, descending into sub-grids;
    /// `test` returns the bound beyond which nothing can matter (the best hit's
    /// [`raybench_geometry::cull_bound`]), or `None` to stop. Each level stops only when that bound lies before
    /// the current cell's exit. Returns the cells visited on both levels.
    fn walk(&self, ray: &Ray, mut test: impl FnMut(&[u32]) -> Option<f32>) -> u64 {
        let mut sub_visits = 0;
        let top = &self.top;
        let top_visits = top.dda(ray, |c, exit| {
            let i = top.cell_index(c);
            let sub = self.sub_of[i] as usize;
            let bound = match self.subs.get(sub) {
                Some(grid) if grid.dda_is_exact_for(ray) => {
                    let mut last = Some(f32::INFINITY);
                    sub_visits += grid.walk(ray, |ids, sub_exit| {
                        last = test(ids);
                        last.is_some_and(|bound| bound >= sub_exit)
                    });
                    last
                }
                // A sparse cell, or a ray the sub-grid cannot place: the cell's own list.
                _ => test(&top.ids[top.offsets[i] as usize..top.offsets[i + 1] as usize]),
            };
            bound.is_some_and(|bound| bound >= exit)
        });
        top_visits + sub_visits
    }
}

impl Accel for TwoLevelGrid {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, TwoLevelParams::default())
    }

    /// The same two-level grid, every level with the bound and padding of
    /// [`crate::INSTANCE_FAR_ORIGIN`] (`Grid::for_instances`).
    fn for_instances(self) -> Self {
        let grid = GridParams {
            far_origin: self.params.grid.far_origin.max(crate::INSTANCE_FAR_ORIGIN),
            ..self.params.grid
        };
        if grid == self.params.grid {
            return self;
        }
        let params = TwoLevelParams {
            grid,
            ..self.params
        };
        Self::build_with(Arc::clone(&self.top.geometry), params)
    }

    fn geometry(&self) -> &Geometry {
        &self.top.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let g = &*self.top.geometry;
        if !self.top.dda_is_exact_for(ray) {
            return g.closest_unplaced(ray, counters);
        }
        traverse::closest(g, ray, counters, |q| {
            let mut mailbox = Mailbox::new();
            let visits = self.walk(q.ray(), |ids| {
                for &id in ids {
                    if !mailbox.seen(id) {
                        q.test(id);
                    }
                }
                Some(if q.has_hit() {
                    q.limit()
                } else {
                    f32::INFINITY
                })
            });
            q.add_visits(visits);
        })
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let g = &*self.top.geometry;
        if !self.top.dda_is_exact_for(ray) {
            return g.occluded_unplaced(ray, counters);
        }
        traverse::occluded(g, ray, counters, |q| {
            let mut hit = false;
            let mut mailbox = Mailbox::new();
            let visits = self.walk(q.ray(), |ids| {
                hit = ids.iter().any(|&id| !mailbox.seen(id) && q.test(id));
                (!hit).then_some(f32::INFINITY)
            });
            q.add_visits(visits);
            hit
        })
    }

    fn stats(&self) -> AccelStats {
        let mut s = self.top.stats();
        for sub in &self.subs {
            s.memory_bytes += sub.stats().memory_bytes;
        }
        s.memory_bytes += std::mem::size_of_val(self.sub_of.as_slice());
        s.counts.push(("sub-grids", self.subs.len() as u64));
        s.counts.push((
            "sub-grid cells",
            self.subs.iter().map(|g| (g.offsets.len() - 1) as u64).sum(),
        ));
        s
    }

    /// The lists a ray tests: the top cells without a sub-grid, and every sub-grid's cells.
    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        // A grid has no costs to weigh and nothing to sample: the parameters do not apply.
        let top = self
            .top
            .list_lengths()
            .zip(&self.sub_of)
            .filter(|(_, sub)| **sub == u32::MAX)
            .map(|(n, _)| n);
        let subs = self.subs.iter().flat_map(Grid::list_lengths);
        Some(StructureQuality::Grid(GridQuality::from_lists(
            top.chain(subs),
            self.top.geometry.bounded().len() as u64,
            self.stats().memory_bytes,
        )))
    }
}
