//! Incoherent single rays traced [`STREAMS`] at a time, interleaved one traversal step each.
//!
//! One incoherent ray is a chain of dependent loads: the nearest child's node is read as soon
//! as its parent's test is done, so each step waits for memory (the profile of the PEERS.md
//! workload: the cycles sit on the first load of each node and leaf). Advancing several rays
//! by one step in turn gives the processor independent loads to overlap, the software
//! counterpart of a GPU's warps switching on a stall. Every ray's traversal is the one
//! [`crate::single::closest`] makes, step for step, so hits are unchanged.

use crate::layout::{LEAF_BIT, Layout, LeafRef};
use crate::simd::Lanes;
use crate::single::{self, Stack, WideRay};
use crate::tri::SplatRay;
use raybench_geometry::{Counters, Geometry, NodeStack, PrimHit, Ray, cull_bound};

/// Rays in flight at once.
pub(crate) const STREAMS: usize = 4;

/// One ray in flight.
struct Walker<'s, L: Lanes> {
    /// Index of the ray in the batch.
    ray: usize,
    wray: WideRay<L::Single>,
    splat: SplatRay<L::Narrow>,
    best: Option<(u32, PrimHit)>,
    limit: f32,
    stack: NodeStack<'s>,
}

impl<'s, L: Lanes> Walker<'s, L> {
    #[inline(always)]
    fn start(ray: usize, r: &Ray, best: Option<(u32, PrimHit)>, mut stack: NodeStack<'s>) -> Self {
        stack.push(0, f32::NEG_INFINITY);
        Self {
            ray,
            wray: WideRay::new(r),
            splat: SplatRay::new(r),
            best,
            limit: cull_bound(best.map_or(r.t_max, |(_, h)| h.t)),
            stack,
        }
    }

    /// Takes one step (a node's children pushed, or a leaf tested); false when the ray is
    /// done.
    #[inline(always)]
    fn step<C: Counters>(
        &mut self,
        layout: &Layout,
        g: &Geometry,
        r: &Ray,
        counters: &mut C,
    ) -> bool {
        let Some((index, _)) = self.stack.pop_within(self.limit) else {
            return false;
        };
        counters.add_visits(1);
        if index & LEAF_BIT != 0 {
            single::leaf_closest(
                layout,
                g,
                LeafRef::decode(index),
                r,
                &self.splat,
                &mut self.best,
                counters,
            );
            self.limit = cull_bound(self.best.map_or(r.t_max, |(_, h)| h.t));
        } else {
            single::push_children(layout, &self.wray, index, self.limit, &mut self.stack);
        }
        true
    }
}

/// The closest hits of the rays `which` (indices into `rays` and `best`): `best[i]` arrives
/// holding ray `i`'s hit with the unbounded primitives and leaves with its closest hit.
#[inline(always)]
pub(crate) fn closest<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    which: &[usize],
    best: &mut [Option<(u32, PrimHit)>],
    stacks: &mut [Stack; STREAMS],
    counters: &mut C,
) {
    if layout.wide.is_empty() {
        return;
    }
    let mut next = which.iter().copied();
    let mut walkers: [Option<Walker<'_, L>>; STREAMS] = stacks.each_mut().map(|s| {
        let stack = NodeStack::new(s);
        next.next()
            .map(|i| Walker::start(i, &rays[i], best[i], stack))
    });
    let mut live = walkers.iter().filter(|w| w.is_some()).count();
    while live > 0 {
        for slot in &mut walkers {
            let Some(w) = slot else { continue };
            if w.step(layout, g, &rays[w.ray], counters) {
                continue;
            }
            best[w.ray] = w.best;
            // The stack is empty again: the next ray reuses it.
            let stack = std::mem::replace(&mut w.stack, NodeStack::new(&mut []));
            match next.next() {
                Some(i) => *w = Walker::start(i, &rays[i], best[i], stack),
                None => {
                    *slot = None;
                    live -= 1;
                }
            }
        }
    }
}

/// One any-hit ray in flight.
struct AnyWalker<'s, L: Lanes> {
    /// Index of the ray in the batch.
    ray: usize,
    wray: WideRay<L::Single>,
    splat: SplatRay<L::Narrow>,
    t_max: <L::Single as Lanes>::V,
    stack: NodeStack<'s>,
}

impl<'s, L: Lanes> AnyWalker<'s, L> {
    #[inline(always)]
    fn start(ray: usize, r: &Ray, mut stack: NodeStack<'s>) -> Self {
        stack.push(0, f32::NEG_INFINITY);
        Self {
            ray,
            wray: WideRay::new(r),
            splat: SplatRay::new(r),
            t_max: <L::Single as Lanes>::splat(r.t_max),
            stack,
        }
    }
}

/// Any-hit results of the rays `which` (indices into `rays` and `blocked`), each set to
/// true when something blocks the ray.
#[inline(always)]
pub(crate) fn occluded<L: Lanes, C: Counters>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    which: &[usize],
    blocked: &mut [bool],
    stacks: &mut [Stack; STREAMS],
    counters: &mut C,
) {
    if layout.wide.is_empty() {
        return;
    }
    let mut next = which.iter().copied();
    let mut walkers: [Option<AnyWalker<'_, L>>; STREAMS] = stacks.each_mut().map(|s| {
        let stack = NodeStack::new(s);
        next.next().map(|i| AnyWalker::start(i, &rays[i], stack))
    });
    let mut live = walkers.iter().filter(|w| w.is_some()).count();
    while live > 0 {
        for slot in &mut walkers {
            let Some(w) = slot else { continue };
            let r = &rays[w.ray];
            let done = match w.stack.pop_within(f32::INFINITY) {
                None => true,
                Some((index, _)) => {
                    let hit = single::leaf_or_push::<L, C>(
                        layout,
                        g,
                        r,
                        &w.wray,
                        &w.splat,
                        w.t_max,
                        index,
                        &mut w.stack,
                        counters,
                    );
                    if hit {
                        blocked[w.ray] = true;
                        // Empty the stack for the next ray.
                        while w.stack.pop_within(f32::INFINITY).is_some() {}
                    }
                    hit
                }
            };
            if !done {
                continue;
            }
            let stack = std::mem::replace(&mut w.stack, NodeStack::new(&mut []));
            match next.next() {
                Some(i) => *w = AnyWalker::start(i, &rays[i], stack),
                None => {
                    *slot = None;
                    live -= 1;
                }
            }
        }
    }
}
