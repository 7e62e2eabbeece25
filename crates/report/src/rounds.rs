//! Timed repetitions in rounds: every backend of a workload is timed once per round, in an
//! order rotated from round to round, so that a burst of load lands on every backend alike
//! rather than on the one whose turn it was. A repetition the machine interfered with is
//! run again within a budget; with [`Repeat::Auto`] the rounds go on until each backend's
//! median is known to within [`TARGET_HALF_WIDTH`] or its time budget is spent.
//!
//! This module knows nothing of renderers: a contestant is an index and a sample is what
//! the caller's closure returns, so the rules are tested on synthetic samples.

use crate::stats;

/// Kept repetitions per backend with [`Repeat::Auto`] before it may stop: six, the fewest
/// whose median has a 95 % distribution-free interval ([`stats::median_interval`]).
pub const MIN_AUTO: u32 = 6;
/// Kept repetitions per backend with [`Repeat::Auto`] at most.
pub const MAX_AUTO: u32 = 30;
/// The half-width of a median's 95 % interval, relative to the median, that
/// [`Repeat::Auto`] aims for: 3 %.
pub const TARGET_HALF_WIDTH: f64 = 0.03;

/// Contended samples in a row after which a workload stops redoing them: the machine is
/// busy throughout, not in a burst, and another try would only find it busy again. They
/// are then kept and counted; a clean sample resumes the redoing.
pub const PERSISTENT: u32 = 3;

/// How many timed repetitions each backend gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Repeat {
    /// Exactly this many kept repetitions.
    Fixed(u32),
    /// From [`MIN_AUTO`] to [`MAX_AUTO`]: until the median's interval is within
    /// [`TARGET_HALF_WIDTH`], or the backend's time budget is spent.
    Auto,
}

impl Repeat {
    /// The repetitions every backend gets at least.
    #[must_use]
    pub fn minimum(self) -> u32 {
        match self {
            Self::Fixed(n) => n,
            Self::Auto => MIN_AUTO,
        }
    }

    /// Its name on the command line and in the report: `auto` or the count.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Self::Fixed(n) => n.to_string(),
            Self::Auto => "auto".into(),
        }
    }
}

/// The rules of one run's repetitions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Policy {
    /// How many repetitions.
    pub repeat: Repeat,
    /// Seconds a sample lasts at least: a workload shorter than this is repeated within
    /// the sample, which reports the time per repetition.
    pub min_sample: f64,
    /// Seconds of samples (kept and redone) a backend may spend on one workload beyond
    /// [`Repeat::minimum`] ([`Repeat::Auto`] only).
    pub budget: f64,
}

/// One timed sample of one contestant.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample<X> {
    /// Seconds per repetition of the workload.
    pub seconds: f64,
    /// Seconds the sample took in all (what the budget counts).
    pub elapsed: f64,
    /// Whether the machine interfered with it.
    pub contended: bool,
    /// What else the caller keeps of a kept sample.
    pub extra: X,
}

/// One contestant's kept samples and counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Tally<X> {
    /// Seconds per repetition of each kept sample, in the order taken.
    pub seconds: Vec<f64>,
    /// The kept samples' extras, in the same order.
    pub extra: Vec<X>,
    /// Samples discarded because the machine interfered, and taken again.
    pub redone: u32,
    /// Samples kept although the machine interfered (the redo budget was spent, or the
    /// machine was busy throughout: [`PERSISTENT`]).
    pub contended: u32,
    /// Seconds of samples taken, kept or not.
    pub elapsed: f64,
}

impl<X> Default for Tally<X> {
    fn default() -> Self {
        Self {
            seconds: Vec::new(),
            extra: Vec::new(),
            redone: 0,
            contended: 0,
            elapsed: 0.0,
        }
    }
}

impl<X> Tally<X> {
    /// Whether its median's interval is within [`TARGET_HALF_WIDTH`] of the median.
    fn narrow(&self) -> bool {
        let (Some(median), Some(interval)) = (
            stats::median(&self.seconds),
            stats::median_interval(&self.seconds),
        ) else {
            return false;
        };
        interval.relative_half_width(median) <= TARGET_HALF_WIDTH
    }

    /// Whether it wants another sample under `policy`.
    fn wants_more(&self, policy: &Policy) -> bool {
        let kept = self.seconds.len() as u32;
        match policy.repeat {
            Repeat::Fixed(n) => kept < n,
            Repeat::Auto => {
                kept < MIN_AUTO
                    || (kept < MAX_AUTO && self.elapsed < policy.budget && !self.narrow())
            }
        }
    }
}

/// The contestants' order in round `round` of `n`: `round, round + 1, ...` modulo `n`.
pub fn order(round: usize, n: usize) -> impl Iterator<Item = usize> {
    (0..n).map(move |i| (i + round) % n.max(1))
}

/// The contestants' order in round `round` of `n`, shuffled: a permutation drawn for each
/// round (Fisher-Yates from SplitMix64 keyed by the round), so that no contestant always
/// follows the same one (as each does under [`order`]'s rotation), and whatever one leaves
/// behind (freed memory, cold caches) falls on a different one each round. The same round
/// always gives the same order.
#[must_use]
pub fn shuffled(round: usize, n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    let mut g = stats::SplitMix(0x0b5e_55ed ^ (round as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    for i in (1..n).rev() {
        v.swap(i, g.below(i + 1));
    }
    v
}

/// Times `n` contestants in rounds under `policy`: `sample(i)` takes one sample of
/// contestant `i`. A contended sample is taken again, up to [`Repeat::minimum`] times per
/// contestant and while fewer than [`PERSISTENT`] samples in a row were contended; past
/// that it is kept and counted.
///
/// # Errors
/// The first error of `sample`.
pub fn run<X, E>(
    n: usize,
    policy: &Policy,
    mut sample: impl FnMut(usize) -> Result<Sample<X>, E>,
) -> Result<Vec<Tally<X>>, E> {
    let mut tallies: Vec<Tally<X>> = (0..n).map(|_| Tally::default()).collect();
    let redo_budget = policy.repeat.minimum();
    let mut streak = 0;
    for round in 0.. {
        let due: Vec<usize> = order(round, n)
            .filter(|&i| tallies[i].wants_more(policy))
            .collect();
        if due.is_empty() {
            break;
        }
        for i in due {
            let t = &mut tallies[i];
            loop {
                let s = sample(i)?;
                t.elapsed += s.elapsed;
                streak = if s.contended { streak + 1 } else { 0 };
                if s.contended && t.redone < redo_budget && streak <= PERSISTENT {
                    t.redone += 1;
                    continue;
                }
                t.contended += u32::from(s.contended);
                t.seconds.push(s.seconds);
                t.extra.push(s.extra);
                break;
            }
        }
    }
    Ok(tallies)
}

/// Repetitions of a workload that last `once` seconds within one sample of at least
/// `min_sample` seconds: from 1 to 1000.
#[must_use]
pub fn repetitions_per_sample(once: f64, min_sample: f64) -> u32 {
    if once <= 0.0 || !once.is_finite() {
        return 1;
    }
    (min_sample / once).ceil().clamp(1.0, 1000.0) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy(repeat: Repeat) -> Policy {
        Policy {
            repeat,
            min_sample: 0.0,
            budget: 1.0,
        }
    }

    fn plain(seconds: f64) -> Sample<()> {
        Sample {
            seconds,
            elapsed: seconds,
            contended: false,
            extra: (),
        }
    }

    #[test]
    fn rounds_rotate_the_order() {
        let mut calls = Vec::new();
        run::<(), ()>(3, &policy(Repeat::Fixed(3)), |i| {
            calls.push(i);
            Ok(plain(0.01))
        })
        .unwrap();
        assert_eq!(calls, [0, 1, 2, 1, 2, 0, 2, 0, 1]);
        assert_eq!(order(4, 3).collect::<Vec<_>>(), [1, 2, 0]);
    }

    #[test]
    fn shuffled_rounds_are_permutations_that_change_who_comes_first_and_next() {
        let n = 10;
        let orders: Vec<Vec<usize>> = (0..20).map(|r| shuffled(r, n)).collect();
        for o in &orders {
            let mut sorted = o.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        }
        assert_eq!(
            shuffled(3, n),
            orders[3],
            "a round's order is a function of the round"
        );
        // Over 20 rounds, contestant 0 is first in more than one round and follows more
        // than one contestant (a rotation would give it the same predecessor every round).
        let firsts: std::collections::HashSet<usize> = orders.iter().map(|o| o[0]).collect();
        assert!(firsts.len() > 3, "{orders:?}");
        let before_0: std::collections::HashSet<usize> = orders
            .iter()
            .filter_map(|o| {
                o.iter()
                    .position(|&i| i == 0)
                    .filter(|&p| p > 0)
                    .map(|p| o[p - 1])
            })
            .collect();
        assert!(before_0.len() > 3, "{orders:?}");
        assert!(shuffled(0, 0).is_empty());
        assert_eq!(shuffled(5, 1), [0]);
    }

    #[test]
    fn contended_samples_are_redone_within_the_budget() {
        // Contestant 0 is always interfered with; 1 never.
        let tallies = run::<(), ()>(2, &policy(Repeat::Fixed(3)), |i| {
            Ok(Sample {
                contended: i == 0,
                ..plain(0.01)
            })
        })
        .unwrap();
        assert_eq!(tallies[0].seconds.len(), 3);
        assert_eq!((tallies[0].redone, tallies[0].contended), (3, 3));
        assert_eq!((tallies[1].redone, tallies[1].contended), (0, 0));
        // A burst that passes: redone, then kept clean.
        let mut n = 0;
        let t = run::<(), ()>(1, &policy(Repeat::Fixed(2)), |_| {
            n += 1;
            Ok(Sample {
                contended: n == 1,
                ..plain(0.01)
            })
        })
        .unwrap();
        assert_eq!((t[0].seconds.len(), t[0].redone, t[0].contended), (2, 1, 0));
        // A machine busy throughout: three tries, then every sample kept and counted.
        let t = run::<(), ()>(2, &policy(Repeat::Fixed(3)), |_| {
            Ok(Sample {
                contended: true,
                ..plain(0.01)
            })
        })
        .unwrap();
        let redone: u32 = t.iter().map(|t| t.redone).sum();
        let contended: u32 = t.iter().map(|t| t.contended).sum();
        assert_eq!((redone, contended), (PERSISTENT, 6));
    }

    #[test]
    fn auto_stops_when_narrow_and_spends_its_budget_when_not() {
        // Steady samples: the minimum is enough.
        let t = run::<(), ()>(1, &policy(Repeat::Auto), |_| Ok(plain(0.010))).unwrap();
        assert_eq!(t[0].seconds.len(), MIN_AUTO as usize);
        // Alternating 10 and 12 ms: every interval spans both, wider than 3 %: it goes on
        // until the budget (0.2 s) is spent.
        let mut k = 0;
        let p = Policy {
            budget: 0.2,
            ..policy(Repeat::Auto)
        };
        let t = run::<(), ()>(2, &p, |i| {
            k += 1;
            Ok(if i == 0 {
                plain(if k % 2 == 0 { 0.010 } else { 0.012 })
            } else {
                plain(0.010)
            })
        })
        .unwrap();
        assert!(t[0].elapsed >= 0.2 && t[0].seconds.len() < MAX_AUTO as usize);
        assert_eq!(t[1].seconds.len(), MIN_AUTO as usize);
        // Without a budget it stops at the maximum.
        let p = Policy {
            budget: f64::INFINITY,
            ..policy(Repeat::Auto)
        };
        let mut k = 0;
        let t = run::<(), ()>(1, &p, |_| {
            k += 1;
            Ok(plain(if k % 2 == 0 { 0.010 } else { 0.012 }))
        })
        .unwrap();
        assert_eq!(t[0].seconds.len(), MAX_AUTO as usize);
    }

    #[test]
    fn errors_stop_the_rounds() {
        let r = run::<(), &str>(2, &policy(Repeat::Fixed(2)), |i| {
            if i == 1 {
                Err("broken")
            } else {
                Ok(plain(0.01))
            }
        });
        assert_eq!(r.unwrap_err(), "broken");
    }

    #[test]
    fn repetitions_fill_the_minimum_sample() {
        assert_eq!(repetitions_per_sample(0.001, 0.02), 20);
        assert_eq!(repetitions_per_sample(0.5, 0.02), 1);
        assert_eq!(repetitions_per_sample(1e-9, 0.02), 1000);
        assert_eq!(repetitions_per_sample(0.0, 0.02), 1);
    }
}
