//! Whether the machine interfered with a timed run: how long this process's threads waited
//! for a CPU while they were ready to run (the kernel's run-queue delay, Linux
//! `/proc/self/task/*/schedstat`), against the CPU time they got.
//!
//! A repetition on a quiet machine waits well under 1 % of its running time; with one other
//! busy process on two cores, about a third. The share of waiting is a sharper signal than
//! CPU time over wall time x threads, which also falls when a frame's serial part (assembly)
//! runs or when a GPU backend sleeps on its device, with nobody else on the machine.

use std::collections::HashMap;

/// The run-queue delay, as a share of the time the threads wanted a CPU, above which a
/// repetition counts as contended: 10 %.
pub const CONTENDED_WAIT_SHARE: f64 = 0.10;

/// The run-queue delay a repetition must also exceed to count as contended: 2 ms, about
/// what one time slice of another busy process costs. Below it the delay is the threads'
/// own wake-up latency (tens of microseconds per wake-up), which is most of a
/// millisecond-long repetition's wait on a quiet machine.
pub const CONTENDED_WAIT_SECONDS: f64 = 0.002;

/// What the scheduler says of one timed call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Interference {
    /// Seconds of CPU the process's threads got.
    pub cpu_seconds: f64,
    /// Seconds its threads were ready to run but waited for a CPU.
    pub wait_seconds: f64,
}

impl Interference {
    /// The share of the wanted CPU time spent waiting: `wait / (cpu + wait)`.
    #[must_use]
    pub fn wait_share(&self) -> f64 {
        let wanted = self.cpu_seconds + self.wait_seconds;
        if wanted > 0.0 {
            self.wait_seconds / wanted
        } else {
            0.0
        }
    }

    /// Whether the waiting passed both [`CONTENDED_WAIT_SHARE`] and
    /// [`CONTENDED_WAIT_SECONDS`].
    #[must_use]
    pub fn contended(&self) -> bool {
        self.wait_share() > CONTENDED_WAIT_SHARE && self.wait_seconds > CONTENDED_WAIT_SECONDS
    }
}

/// CPU and run-queue nanoseconds per thread of this process; `None` where the kernel does
/// not expose them (not Linux, or schedstats off).
fn per_thread() -> Option<HashMap<u64, (u64, u64)>> {
    let mut out = HashMap::new();
    for entry in std::fs::read_dir("/proc/self/task").ok()? {
        let entry = entry.ok()?;
        let Some(tid) = entry.file_name().to_str().and_then(|s| s.parse().ok()) else {
            continue;
        };
        // A thread may end between the listing and the read: skip it.
        let Ok(text) = std::fs::read_to_string(entry.path().join("schedstat")) else {
            continue;
        };
        let mut fields = text.split_whitespace().map(str::parse::<u64>);
        if let (Some(Ok(cpu)), Some(Ok(wait))) = (fields.next(), fields.next()) {
            out.insert(tid, (cpu, wait));
        }
    }
    (!out.is_empty()).then_some(out)
}

/// Runs `f` and says how much the machine interfered with it; `None` where the kernel does
/// not tell.
pub fn during<T>(f: impl FnOnce() -> T) -> (T, Option<Interference>) {
    let before = per_thread();
    let value = f();
    let after = per_thread();
    let interference = before.zip(after).map(|(before, after)| {
        let (mut cpu, mut wait) = (0u64, 0u64);
        for (tid, (c, w)) in after {
            let (c0, w0) = before.get(&tid).copied().unwrap_or((0, 0));
            cpu += c.saturating_sub(c0);
            wait += w.saturating_sub(w0);
        }
        Interference {
            cpu_seconds: cpu as f64 * 1e-9,
            wait_seconds: wait as f64 * 1e-9,
        }
    });
    (value, interference)
}

/// The machine's load averages over 1, 5 and 15 minutes (`/proc/loadavg`), where known.
#[must_use]
pub fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(str::parse::<f64>);
    Some([it.next()?.ok()?, it.next()?.ok()?, it.next()?.ok()?])
}

/// What the whole machine's CPUs did up to a moment, for the share other processes took
/// between two moments ([`MachineUse::others_since`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MachineUse {
    /// Clock ticks of every CPU busy (user, nice, system, interrupts) or taken by the
    /// hypervisor (steal), since boot.
    pub busy: u64,
    /// Of those, stolen by the hypervisor.
    pub steal: u64,
    /// Every CPU's ticks, idle included.
    pub total: u64,
    /// This process's user and system ticks, its threads included.
    pub own: u64,
}

/// The share of the machine's CPU time, between two [`MachineUse`] readings, that other
/// processes (and the hypervisor) took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OthersUse {
    /// Busy time not this process's, hypervisor steal included, over all CPUs' time.
    pub share: f64,
    /// Of the machine's CPU time, the share the hypervisor stole.
    pub steal: f64,
}

impl MachineUse {
    /// The counters now (`/proc/stat`, `/proc/self/stat`); `None` where the system does not
    /// tell.
    #[must_use]
    pub fn now() -> Option<Self> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let cpu: Vec<u64> = stat
            .lines()
            .next()?
            .strip_prefix("cpu ")?
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .ok()?;
        // user nice system idle iowait irq softirq steal [guest guest_nice]: guest time is
        // already counted in user and nice.
        let field = |i: usize| cpu.get(i).copied().unwrap_or(0);
        let busy = field(0) + field(1) + field(2) + field(5) + field(6) + field(7);
        let total = busy + field(3) + field(4);
        let own_stat = std::fs::read_to_string("/proc/self/stat").ok()?;
        // The fields after the command name (in parentheses, which may hold spaces):
        // utime and stime are the 12th and 13th of them.
        let after = own_stat.rsplit_once(')')?.1;
        let mut it = after.split_whitespace().skip(11).map(str::parse::<u64>);
        let own = it.next()?.ok()? + it.next()?.ok()?;
        Some(Self {
            busy,
            steal: field(7),
            total,
            own,
        })
    }

    /// What other processes took of the machine between `earlier` and `self`; `None` when
    /// no tick passed.
    #[must_use]
    pub fn others_since(&self, earlier: &Self) -> Option<OthersUse> {
        let total = self.total.checked_sub(earlier.total).filter(|&t| t > 0)? as f64;
        let busy = self.busy.saturating_sub(earlier.busy);
        let own = self.own.saturating_sub(earlier.own);
        Some(OthersUse {
            share: busy.saturating_sub(own) as f64 / total,
            steal: self.steal.saturating_sub(earlier.steal) as f64 / total,
        })
    }
}

/// The kernel's memory events since boot that slow a build down without another process
/// running (Linux `/proc/vmstat`): page faults served with a transparent huge page, and
/// allocations that stalled to compact memory for one. A build that took huge pages
/// touched fewer pages (one fault per 2 MiB instead of per 4 KiB); one that stalled waited
/// for the kernel to move other pages first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryEvents {
    /// `thp_fault_alloc`: faults served with a newly allocated huge page.
    pub thp_fault_alloc: u64,
    /// `compact_stall`: allocations that waited for direct compaction.
    pub compact_stall: u64,
}

impl MemoryEvents {
    /// The counters now; `None` where the system does not tell.
    #[must_use]
    pub fn now() -> Option<Self> {
        Self::parse(&std::fs::read_to_string("/proc/vmstat").ok()?)
    }

    /// The counters in the text of `/proc/vmstat` (`name value` lines); `None` when either
    /// is missing.
    #[must_use]
    pub fn parse(vmstat: &str) -> Option<Self> {
        let (mut thp, mut stall) = (None, None);
        for line in vmstat.lines() {
            let mut it = line.split_whitespace();
            let (Some(name), Some(value)) = (it.next(), it.next()) else {
                continue;
            };
            match name {
                "thp_fault_alloc" => thp = value.parse().ok(),
                "compact_stall" => stall = value.parse().ok(),
                _ => {}
            }
        }
        Some(Self {
            thp_fault_alloc: thp?,
            compact_stall: stall?,
        })
    }

    /// The events between `earlier` and `self`.
    #[must_use]
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            thp_fault_alloc: self.thp_fault_alloc.saturating_sub(earlier.thp_fault_alloc),
            compact_stall: self.compact_stall.saturating_sub(earlier.compact_stall),
        }
    }
}

impl std::ops::AddAssign for MemoryEvents {
    fn add_assign(&mut self, other: Self) {
        self.thp_fault_alloc += other.thp_fault_alloc;
        self.compact_stall += other.compact_stall;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_events_read_their_two_counters() {
        let text =
            "nr_free_pages 1000\ncompact_stall 3\nthp_fault_alloc 315\nthp_fault_fallback 2\n";
        let now = MemoryEvents::parse(text).expect("both counters");
        assert_eq!(
            now,
            MemoryEvents {
                thp_fault_alloc: 315,
                compact_stall: 3
            }
        );
        let earlier = MemoryEvents {
            thp_fault_alloc: 300,
            compact_stall: 3,
        };
        assert_eq!(
            now.since(&earlier),
            MemoryEvents {
                thp_fault_alloc: 15,
                compact_stall: 0
            }
        );
        let mut total = now;
        total += earlier;
        assert_eq!((total.thp_fault_alloc, total.compact_stall), (615, 6));
        assert_eq!(
            MemoryEvents::parse("nr_free_pages 1000\ncompact_stall 3\n"),
            None
        );
    }
}
