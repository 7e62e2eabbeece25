//! Walking a grid: the shared 3D-DDA in grid units, the per-ray mailbox, and the `Accel`
//! queries through the core's traversal frame.

use crate::{Grid, GridParams, INSTANCE_FAR_ORIGIN, MAILBOX};
use raybench_geometry::traverse::{self, AnyHit, Closest};
use raybench_geometry::{
    Accel, AccelStats, Counters, Geometry, GridQuality, Hit, QualityParams, Ray, SlabRay,
    StructureQuality,
};
use std::ops::ControlFlow;
use std::sync::Arc;

impl Grid {
    /// Whether the DDA can locate `ray` in the grid precisely enough (its origin within
    /// [`GridParams::far_origin`] grid sizes of the centre, and finite).
    #[inline]
    pub(crate) fn dda_is_exact_for(&self, ray: &Ray) -> bool {
        if self.ids.is_empty() {
            // Nothing to walk; unless primitives exist that the grid could not hold.
            return self.prims.is_empty();
        }
        if !ray.is_valid() {
            // NaN or zero directions would never step: test everything, as naive does.
            return false;
        }
        let reach = (ray.origin - self.bounds.center()).abs().max_element();
        reach <= self.params.far_origin * self.bounds.extent().max_element()
    }

    /// The cells `ray` visits, in order (for tests and teaching).
    #[must_use]
    pub fn cells_visited(&self, ray: &Ray) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        self.dda(ray, |c, _| {
            out.push(c);
            true
        });
        out
    }

    /// Walks the cells `ray` crosses in order, calling `visit(cell_ids, exit_t)` for each;
    /// `visit` returns `false` to stop. Cells are visited from the ray's entry into the
    /// grid until it leaves the grid or passes `ray.t_max`. Returns the cells visited.
    #[inline]
    pub(crate) fn walk(&self, ray: &Ray, mut visit: impl FnMut(&[u32], f32) -> bool) -> u64 {
        self.dda(ray, |c, exit| {
            let i = self.cell_index(c);
            visit(
                &self.ids[self.offsets[i] as usize..self.offsets[i + 1] as usize],
                exit,
            )
        })
    }

    /// The 3D-DDA ([`raybench_geometry::dda`]) in grid units (`(p - min) / cell`, the same
    /// `t` as the world ray): calls `visit(cell, exit_t)` for each cell crossed from the
    /// ray's entry into the grid (conservative slab test) until `visit` returns `false`, the
    /// ray leaves the grid or passes `ray.t_max`. Returns the cells visited.
    #[inline]
    pub(crate) fn dda(&self, ray: &Ray, mut visit: impl FnMut([u32; 3], f32) -> bool) -> u64 {
        if self.ids.is_empty() {
            return 0;
        }
        let slab = SlabRay::new(ray);
        let Some(t_enter) = slab.entry(self.bounds.min.into(), self.bounds.max.into(), ray.t_max)
        else {
            return 0;
        };
        let o = (ray.origin - self.bounds.min) * self.inv_cell;
        let d = ray.dir * self.inv_cell;
        let mut visits = 0u64;
        let _ = raybench_geometry::dda(self.res, o, d, t_enter, ray.t_max, &mut |c, _, exit| {
            visits += 1;
            if visit(c, exit) {
                ControlFlow::Continue(())
            } else {
                ControlFlow::Break(())
            }
        });
        visits
    }
}

/// A ring of recently tested primitive ids (mailboxing without shared state).
pub(crate) struct Mailbox {
    ids: [u32; MAILBOX],
    next: usize,
}

impl Mailbox {
    pub(crate) fn new() -> Self {
        Self {
            ids: [u32::MAX; MAILBOX],
            next: 0,
        }
    }

    /// True when `id` was tested recently; otherwise remembers it and returns false.
    #[inline]
    pub(crate) fn seen(&mut self, id: u32) -> bool {
        if self.ids.contains(&id) {
            return true;
        }
        self.ids[self.next] = id;
        self.next = (self.next + 1) % MAILBOX;
        false
    }
}

impl Accel for Grid {
    fn build(geometry: Arc<Geometry>) -> Self {
        Self::build_with(geometry, GridParams::default())
    }

    /// The same grid (its resolution's parameters kept) with the bound and padding of
    /// [`INSTANCE_FAR_ORIGIN`].
    fn for_instances(self) -> Self {
        let params = GridParams {
            far_origin: self.params.far_origin.max(INSTANCE_FAR_ORIGIN),
            ..self.params
        };
        if params == self.params {
            return self;
        }
        Self::build_with(self.geometry, params)
    }

    fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        if !self.dda_is_exact_for(ray) {
            return self.geometry.closest_unplaced(ray, counters);
        }
        traverse::closest(&self.geometry, ray, counters, |q| self.walk_closest(q))
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        if !self.dda_is_exact_for(ray) {
            return self.geometry.occluded_unplaced(ray, counters);
        }
        traverse::occluded(&self.geometry, ray, counters, |q| self.walk_any(q))
    }

    fn stats(&self) -> AccelStats {
        let cells = self.offsets.len().saturating_sub(1);
        let non_empty = self.offsets.windows(2).filter(|w| w[1] > w[0]).count();
        AccelStats {
            memory_bytes: std::mem::size_of_val(self.offsets.as_slice())
                + std::mem::size_of_val(self.ids.as_slice()),
            counts: vec![
                ("cells", cells as u64),
                ("non-empty cells", non_empty as u64),
                ("references", self.ids.len() as u64),
                ("nx", u64::from(self.res[0])),
                ("ny", u64::from(self.res[1])),
                ("nz", u64::from(self.res[2])),
            ],
        }
    }

    fn quality(&self, _params: &QualityParams) -> Option<StructureQuality> {
        // A grid has no costs to weigh and nothing to sample: the parameters do not apply.
        Some(StructureQuality::Grid(GridQuality::from_lists(
            self.list_lengths(),
            self.geometry.bounded().len() as u64,
            self.stats().memory_bytes,
        )))
    }
}

impl Grid {
    /// The length of every cell's list, cell after cell.
    pub(crate) fn list_lengths(&self) -> impl Iterator<Item = u64> + '_ {
        self.offsets.windows(2).map(|w| u64::from(w[1] - w[0]))
    }

    /// The closest-hit walk: every cell's list (mailboxed), stopping only when the best hit
    /// lies before the current cell's exit (with the contract's slack).
    fn walk_closest<C: Counters>(&self, q: &mut Closest<'_, C>) {
        let mut mailbox = Mailbox::new();
        let visits = self.walk(q.ray(), |ids, exit| {
            for &id in ids {
                if !mailbox.seen(id) {
                    q.test(id);
                }
            }
            !q.has_hit() || q.limit() >= exit
        });
        q.add_visits(visits);
    }

    /// The any-hit walk: every cell's list (mailboxed) until the first hit.
    fn walk_any<C: Counters>(&self, q: &mut AnyHit<'_, C>) -> bool {
        let mut hit = false;
        let mut mailbox = Mailbox::new();
        let visits = self.walk(q.ray(), |ids, _| {
            hit = ids.iter().any(|&id| !mailbox.seen(id) && q.test(id));
            !hit
        });
        q.add_visits(visits);
        hit
    }
}
