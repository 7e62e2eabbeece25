//! How steady this machine's memory is: random walks through memory sized to stay in the
//! level-2 cache, to stay in the last-level cache, and to miss it, timed in many short
//! samples (the peer benchmark's `--cache-probe`; the last-level walk is also taken for a
//! second before and after every report and peer run).
//!
//! A walk's step is one dependent load, as a BVH traversal's step from a node to its child
//! is, so the time per step is the latency of the level that holds the walk. A walk that
//! fits a cache no other machine shares runs at the same pace sample after sample. Where the
//! last-level cache is shared with other virtual machines, the walk that should stay in it
//! runs at its pace only while the neighbours leave its lines alone: its samples spread
//! between the cache's latency and the memory's, and so do the timings of every mesh whose
//! structure lives there.

pub use crate::results::CacheWalk;
use raybench_core::sampling::pcg3d;
use std::time::{Duration, Instant};

/// Bytes of one slot of the walk: a cache line.
const LINE: usize = 64;

/// Steps per timed sample: about 10 ms at a memory latency of 100 ns.
const STEPS: usize = 100_000;

/// The memory of a walk through `lines` cache lines in one cycle (Sattolo's algorithm with
/// a counter-based generator keyed by `seed`): line `i` holds the index of the next in its
/// first slot.
fn cycle(lines: usize, seed: u32) -> Vec<[u32; LINE / 4]> {
    assert!(lines >= 2 && u32::try_from(lines).is_ok(), "{lines} lines");
    let mut order: Vec<u32> = (0..lines as u32).collect();
    for i in (1..lines).rev() {
        // j < i: every permutation this makes is one cycle through all the lines.
        let j = pcg3d([i as u32, seed, 0])[0] as usize % i;
        order.swap(i, j);
    }
    let mut memory = vec![[0u32; LINE / 4]; lines];
    // `order` as a cycle: each line points to the one after it in `order`.
    for k in 0..lines {
        memory[order[k] as usize][0] = order[(k + 1) % lines];
    }
    memory
}

/// A walk through memory, ready to be timed.
struct Walk {
    memory: Vec<[u32; LINE / 4]>,
    at: u32,
}

impl Walk {
    /// A walk through `bytes` of memory (at least two cache lines), brought into the
    /// caches by one untimed pass.
    fn new(bytes: usize) -> Self {
        let mut walk = Self {
            memory: cycle((bytes / LINE).max(2), 1),
            at: 0,
        };
        walk.steps(walk.memory.len());
        walk
    }

    fn steps(&mut self, n: usize) {
        let mut at = self.at;
        for _ in 0..n {
            at = self.memory[at as usize][0];
        }
        self.at = std::hint::black_box(at);
    }

    /// Nanoseconds per step of one timed sample of [`STEPS`] steps.
    fn sample(&mut self) -> f64 {
        let start = Instant::now();
        self.steps(STEPS);
        start.elapsed().as_secs_f64() * 1e9 / STEPS as f64
    }
}

impl CacheWalk {
    /// Samples of a walk through `bytes` for about `time` (at least one).
    #[must_use]
    pub fn measure(bytes: usize, time: Duration) -> Self {
        let mut walk = Walk::new(bytes);
        let start = Instant::now();
        let mut ns = vec![walk.sample()];
        while start.elapsed() < time {
            ns.push(walk.sample());
        }
        ns.sort_by(f64::total_cmp);
        let at = |q: f64| ns[((ns.len() - 1) as f64 * q).round() as usize];
        Self {
            bytes: bytes as u64,
            samples: u32::try_from(ns.len()).unwrap_or(u32::MAX),
            fastest_ns: at(0.0),
            median_ns: at(0.5),
            p90_ns: at(0.9),
            slowest_ns: at(1.0),
        }
    }

    /// The median sample over the fastest: near 1 where nothing else touches the level that
    /// holds the walk.
    #[must_use]
    pub fn ratio(&self) -> f64 {
        self.median_ns / self.fastest_ns
    }

    /// The bytes walked through, in KiB or MiB.
    #[must_use]
    pub fn size(&self) -> String {
        crate::fmt::bytes(self.bytes)
    }

    /// One line: median and fastest nanoseconds per step and their ratio.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{:.1} ns per step at the median, {:.1} at the fastest ({:.2}x)",
            self.median_ns,
            self.fastest_ns,
            self.ratio()
        )
    }
}

/// The walks' sizes: half the level-2 cache, a quarter of the last-level cache (at most
/// 256 MiB), four times the last-level cache (at most 1 GiB), from sysfs (1 MiB and 32 MiB
/// where it does not say).
fn sizes() -> [(&'static str, usize); 3] {
    let caches = crate::machine::caches().unwrap_or_default();
    let l2 = usize::try_from(caches.l2.unwrap_or(1 << 20)).unwrap_or(1 << 20);
    let last = caches
        .l3
        .and_then(|b| usize::try_from(b).ok())
        .unwrap_or(32 << 20)
        .max(l2);
    [
        ("half the L2", l2 / 2),
        ("a quarter of the last-level cache", (last / 4).min(1 << 28)),
        ("four times the last-level cache", (4 * last).min(1 << 30)),
    ]
}

/// The walk through a quarter of the last-level cache for about `time`: its spread says how
/// much other machines sharing that cache took of it meanwhile.
#[must_use]
pub fn last_level(time: Duration) -> CacheWalk {
    CacheWalk::measure(sizes()[1].1, time)
}

/// Runs the three walks for about `per_size` each and returns a markdown table of their
/// spread.
#[must_use]
pub fn table(per_size: Duration) -> String {
    let mut out = format!(
        "Random walks through memory, one dependent load per step, timed in samples of \
         {STEPS} steps (ns per step; spread: the median sample over the fastest):\n\n\
         | walk | bytes | samples | fastest | median | 90th percentile | slowest | spread |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for (name, bytes) in sizes() {
        let w = CacheWalk::measure(bytes, per_size);
        out += &format!(
            "| {name} | {bytes} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2}x |\n",
            w.samples,
            w.fastest_ns,
            w.median_ns,
            w.p90_ns,
            w.slowest_ns,
            w.ratio()
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk's memory is one cycle through every line.
    #[test]
    fn the_walk_visits_every_line_once_per_cycle() {
        for lines in [2, 3, 17, 1000] {
            let memory = cycle(lines, 1);
            let mut seen = vec![false; lines];
            let mut at = 0usize;
            for _ in 0..lines {
                assert!(!seen[at], "{lines} lines: line {at} twice");
                seen[at] = true;
                at = memory[at][0] as usize;
            }
            assert_eq!(at, 0, "{lines} lines: not back at the start");
        }
        assert!(Walk::new(1 << 16).sample() > 0.0);
        let w = CacheWalk::measure(1 << 16, Duration::from_millis(20));
        assert!(w.samples >= 1, "{w:?}");
        assert!(
            0.0 < w.fastest_ns
                && w.fastest_ns <= w.median_ns
                && w.median_ns <= w.p90_ns
                && w.p90_ns <= w.slowest_ns,
            "{w:?}"
        );
        assert!(w.describe().contains("ns per step"), "{}", w.describe());
    }
}
