//! Incoherent single rays traced a few at a time, interleaved one traversal step each,
//! where the structure exceeds the last-level cache ([`width`]; where it fits, each ray
//! walks alone).
//!
//! One incoherent ray is a chain of dependent loads: the nearest child's node is read as soon
//! as its parent's test is done, so each step waits for memory (the profile of the PEERS.md
//! workload: the cycles sit on the first load of each node and leaf). Advancing several rays
//! by one step in turn gives the processor independent loads to overlap, the software
//! counterpart of a GPU's warps switching on a stall. Every ray's traversal is the one
//! [`crate::single::closest`] makes, step for step, so hits are unchanged, whatever the
//! width.
//!
//! The overlap has a price: the rays' state no longer fits the registers and their branches
//! interleave. Where the structure fits the last-level cache the price is the larger: on a
//! 2-vCPU AMD EPYC Zen 4 guest (2026-12-07, peer benchmark, three alternating pairs judged
//! against Embree's single rays in the same rounds), each ray walking alone through
//! [`crate::single`]'s loop instead of two in flight traced Sponza's ao and diffuse rays
//! 1.20x to 1.22x as fast and its incoherent any hits 1.13x, and left the bunny within the
//! noise; where it does not fit (the terrain's BVH8 on that guest), four in flight stay
//! 1.44x as fast as one on incoherent closest hits. (On a 2-vCPU Intel Xeon, 2026-12-05,
//! four beat two by up to 20% on a 12.6-million-triangle scene whose 820 MB do not fit.)
//! [`width`] chooses by that rule; two in flight remain as an explicit choice.

use crate::layout::{LEAF_BIT, Layout, LeafRef};
use crate::simd::Lanes;
use crate::single::{self, AnyStep, STACK, Stack, WideRay};
use crate::tri::SplatRay;
use raybench_geometry::{Counters, Geometry, NodeStack, PrimHit, Ray, cull_bound};

/// Rays in flight when the structure fits the last-level cache: each ray alone, through
/// [`single::closest`] and [`single::occluded`], whose state stays in registers.
pub(crate) const ONE: usize = 1;

/// Two rays in flight (chosen explicitly only).
pub(crate) const NARROW: usize = 2;

/// Rays in flight when the structure exceeds the last-level cache.
pub(crate) const WIDE: usize = 4;

/// Last-level cache size assumed where the system does not say (Linux's sysfs is read).
const DEFAULT_CACHE: usize = 32 << 20;

/// Rays in flight for a structure of `bytes`: [`WIDE`] when it exceeds the last-level cache,
/// else [`ONE`].
pub(crate) fn width(bytes: usize) -> usize {
    if bytes > last_level_cache() {
        WIDE
    } else {
        ONE
    }
}

/// The largest cache of the highest level that CPU 0 reports, read once.
fn last_level_cache() -> usize {
    static SIZE: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *SIZE.get_or_init(|| {
        let read = |index: usize, file: &str| {
            std::fs::read_to_string(format!(
                "/sys/devices/system/cpu/cpu0/cache/index{index}/{file}"
            ))
            .ok()
        };
        (0..8)
            .filter_map(|i| {
                Some((
                    read(i, "level")?.trim().parse::<u32>().ok()?,
                    read(i, "size")?,
                ))
            })
            .filter_map(|(level, size)| Some((level, cache_bytes(&size)?)))
            .max()
            .map_or(DEFAULT_CACHE, |(_, bytes)| bytes)
    })
}

/// A sysfs cache size (`"32K"`, `"491520K"`, `"2M"`) in bytes.
pub(crate) fn cache_bytes(text: &str) -> Option<usize> {
    let text = text.trim();
    let (digits, unit) = match text.find(|c: char| !c.is_ascii_digit()) {
        Some(i) => text.split_at(i),
        None => (text, ""),
    };
    let shift = match unit {
        "" => 0,
        "K" => 10,
        "M" => 20,
        "G" => 30,
        _ => return None,
    };
    digits.parse::<usize>().ok()?.checked_mul(1 << shift)
}

/// One ray in flight.
struct Walker<'s, L: Lanes> {
    /// Index of the ray in the batch.
    ray: usize,
    wray: WideRay<L::Single>,
    splat: SplatRay<L::Narrow>,
    best: Option<(u32, PrimHit)>,
    limit: f32,
    /// The node to visit next, when the last step chose one (see [`single::descend`]).
    next: Option<u32>,
    stack: NodeStack<'s>,
}

impl<'s, L: Lanes> Walker<'s, L> {
    #[inline(always)]
    fn start(ray: usize, r: &Ray, best: Option<(u32, PrimHit)>, stack: NodeStack<'s>) -> Self {
        Self {
            ray,
            wray: WideRay::new(r),
            splat: SplatRay::new(r),
            best,
            limit: cull_bound(best.map_or(r.t_max, |(_, h)| h.t)),
            next: Some(0),
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
        let Some(index) = single::next_node(&mut self.next, &mut self.stack, self.limit) else {
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
            self.next = single::descend(layout, &self.wray, index, self.limit, &mut self.stack);
        }
        true
    }
}

/// The closest hits of the rays `which` (indices into `rays` and `best`): `best[i]` arrives
/// holding ray `i`'s hit with the unbounded primitives and leaves with its closest hit.
#[inline(always)]
pub(crate) fn closest<L: Lanes, C: Counters, const S: usize>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    which: &[usize],
    best: &mut [Option<(u32, PrimHit)>],
    counters: &mut C,
) {
    if layout.wide.is_empty() {
        return;
    }
    let mut stacks: [Stack; S] = [[(0, 0.0); STACK]; S];
    let mut next = which.iter().copied();
    let mut walkers: [Option<Walker<'_, L>>; S] = stacks.each_mut().map(|s| {
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
    /// The node to visit next without the stack (see [`single::descend_any`]).
    next: Option<u32>,
}

impl<'s, L: Lanes> AnyWalker<'s, L> {
    #[inline(always)]
    fn start(ray: usize, r: &Ray, stack: NodeStack<'s>) -> Self {
        Self {
            ray,
            wray: WideRay::new(r),
            splat: SplatRay::new(r),
            t_max: <L::Single as Lanes>::splat(r.t_max),
            stack,
            next: Some(0),
        }
    }
}

/// Any-hit results of the rays `which` (indices into `rays` and `blocked`), each set to
/// true when something blocks the ray.
#[inline(always)]
pub(crate) fn occluded<L: Lanes, C: Counters, const S: usize>(
    layout: &Layout,
    g: &Geometry,
    rays: &[Ray],
    which: &[usize],
    blocked: &mut [bool],
    counters: &mut C,
) {
    if layout.wide.is_empty() {
        return;
    }
    let mut stacks: [Stack; S] = [[(0, 0.0); STACK]; S];
    let mut next = which.iter().copied();
    let mut walkers: [Option<AnyWalker<'_, L>>; S] = stacks.each_mut().map(|s| {
        let stack = NodeStack::new(s);
        next.next().map(|i| AnyWalker::start(i, &rays[i], stack))
    });
    let mut live = walkers.iter().filter(|w| w.is_some()).count();
    while live > 0 {
        for slot in &mut walkers {
            let Some(w) = slot else { continue };
            let r = &rays[w.ray];
            let done = match single::next_node(&mut w.next, &mut w.stack, f32::INFINITY) {
                None => true,
                Some(index) => {
                    let step = single::leaf_or_descend::<L, C>(
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
                    match step {
                        AnyStep::Blocked => {
                            blocked[w.ray] = true;
                            // Empty the stack for the next ray.
                            while w.stack.pop_within(f32::INFINITY).is_some() {}
                            true
                        }
                        AnyStep::Next(child) => {
                            w.next = child;
                            false
                        }
                    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_sizes_read_as_sysfs_writes_them() {
        assert_eq!(cache_bytes("48K\n"), Some(48 << 10));
        assert_eq!(cache_bytes("491520K"), Some(491_520 << 10));
        assert_eq!(cache_bytes("2M"), Some(2 << 20));
        assert_eq!(cache_bytes("1G"), Some(1 << 30));
        assert_eq!(cache_bytes("4096"), Some(4096));
        assert_eq!(cache_bytes("12 KB"), None);
        assert_eq!(cache_bytes(""), None);
        assert_eq!(cache_bytes("99999999999999999999999G"), None);
    }

    #[test]
    fn a_structure_beyond_the_cache_gets_the_wide_stream() {
        assert_eq!(width(0), ONE);
        assert_eq!(width(last_level_cache()), ONE);
        assert_eq!(width(last_level_cache() + 1), WIDE);
    }
}
