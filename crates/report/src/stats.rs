//! The statistics of timed repetitions, a leaf: a median's confidence interval, the interval
//! of a ratio of two medians, and the rules that turn them into words (a fastest backend or a
//! tie, a change or none, noise unknown).
//!
//! The median's interval is distribution-free: the order statistics `x(k)` and `x(n+1-k)`
//! bracket the true median with probability `1 - 2 P(Binomial(n, 1/2) < k)`, whatever the
//! distribution of the times (Hollander and Wolfe; what `pyperf` and `hyperfine` leave out
//! and criterion replaces by a bootstrap of the mean). The interval of a ratio of two medians
//! comes from a bootstrap that resamples both sides independently, seeded, so a report is
//! reproducible from its samples.
//! Ratios measured in independent replicates (alternating pairs of runs) are pooled by
//! Student's t over their logarithms: few replicates allow no distribution-free interval.

/// The confidence of every interval the report gives.
pub const CONFIDENCE: f64 = 0.95;

/// Bootstrap resamples for the interval of a ratio.
pub const RESAMPLES: usize = 2000;

/// The smallest relative change `compare-results` and `--baseline` call a change, whatever
/// the intervals say: 2 %.
pub const MIN_EFFECT: f64 = 0.02;

/// An interval and the confidence it actually has (below [`CONFIDENCE`] where too few
/// repetitions allow no more: `[min, max]` of 5 repetitions covers the median with
/// probability 0.9375).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// The probability that the interval holds the true value.
    pub confidence: f64,
}

impl Interval {
    /// Whether `x` lies inside.
    #[must_use]
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// Half the width, relative to `centre`: the precision the adaptive repetitions aim at.
    #[must_use]
    pub fn relative_half_width(&self, centre: f64) -> f64 {
        if centre > 0.0 {
            0.5 * (self.hi - self.lo) / centre
        } else {
            f64::INFINITY
        }
    }
}

/// `P(Binomial(n, 1/2) < k)`.
fn binomial_below(n: usize, k: usize) -> f64 {
    let mut term = 0.5f64.powi(n as i32); // C(n, 0) / 2^n
    let mut sum = 0.0;
    for i in 0..k.min(n + 1) {
        sum += term;
        term *= (n - i) as f64 / (i + 1) as f64;
    }
    sum
}

/// The sorted copy of `samples`.
fn sorted(samples: &[f64]) -> Vec<f64> {
    let mut v = samples.to_vec();
    v.sort_by(f64::total_cmp);
    v
}

/// The median of `samples` (mean of the middle two for an even count); `None` for none.
#[must_use]
pub fn median(samples: &[f64]) -> Option<f64> {
    let v = sorted(samples);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// The distribution-free interval of the median of `samples`: the narrowest pair of order
/// statistics with at least [`CONFIDENCE`], or `[min, max]` with the confidence it has when
/// there are too few. `None` below two samples: one repetition says nothing of the noise.
#[must_use]
pub fn median_interval(samples: &[f64]) -> Option<Interval> {
    let v = sorted(samples);
    let n = v.len();
    if n < 2 {
        return None;
    }
    // The largest k (1-based) whose [x(k), x(n+1-k)] still has the confidence.
    let mut k = 1;
    while k < n / 2 && 1.0 - 2.0 * binomial_below(n, k + 1) >= CONFIDENCE {
        k += 1;
    }
    Some(Interval {
        lo: v[k - 1],
        hi: v[n - k],
        confidence: 1.0 - 2.0 * binomial_below(n, k),
    })
}

/// SplitMix64: a counter-based generator, so every interval is a function of its samples
/// (and every shuffled round order of [`crate::rounds::shuffled`] a function of its round).
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// An index below `n`.
    pub(crate) fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.next()) * n as u128) >> 64) as usize
    }
}

/// The seed of a bootstrap: a hash of the samples' bits, so the same samples always give
/// the same interval and different ones independent resamples.
fn seed_of(a: &[f64], b: &[f64]) -> u64 {
    let mut g = SplitMix(0x05ee_d0f7_a7e5);
    for x in a.iter().chain([f64::NAN].iter()).chain(b) {
        g.0 ^= x.to_bits();
        g.next();
    }
    g.0
}

/// The median of one bootstrap resample of `v` into `buf`.
fn resampled_median(v: &[f64], g: &mut SplitMix, buf: &mut Vec<f64>) -> f64 {
    buf.clear();
    buf.extend((0..v.len()).map(|_| v[g.below(v.len())]));
    median(buf).unwrap_or(f64::NAN)
}

/// The ratio of the medians `median(a) / median(b)` and its [`CONFIDENCE`] interval by a
/// seeded percentile bootstrap that resamples `a` and `b` independently. The interval is
/// `None` when either side has fewer than two samples (noise unknown).
#[must_use]
pub fn ratio_interval(a: &[f64], b: &[f64]) -> (f64, Option<Interval>) {
    let (Some(ma), Some(mb)) = (median(a), median(b)) else {
        return (f64::NAN, None);
    };
    let ratio = ma / mb;
    if a.len() < 2 || b.len() < 2 {
        return (ratio, None);
    }
    let mut g = SplitMix(seed_of(a, b));
    let (mut ba, mut bb) = (Vec::new(), Vec::new());
    let mut ratios: Vec<f64> = (0..RESAMPLES)
        .map(|_| resampled_median(a, &mut g, &mut ba) / resampled_median(b, &mut g, &mut bb))
        .collect();
    ratios.sort_by(f64::total_cmp);
    let tail = (1.0 - CONFIDENCE) / 2.0;
    let at = |q: f64| ratios[((q * RESAMPLES as f64) as usize).min(RESAMPLES - 1)];
    (
        ratio,
        Some(Interval {
            lo: at(tail),
            hi: at(1.0 - tail),
            confidence: CONFIDENCE,
        }),
    )
}

/// What two sets of times say about each other: `a` against `b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// `a` takes less time: the interval of the ratio lies below 1 and the change is at
    /// least [`MIN_EFFECT`].
    Faster,
    /// `a` takes more time, likewise.
    Slower,
    /// Within the noise or below the minimum effect.
    Same,
    /// One side has a single repetition: its noise is unknown, so no change is claimed.
    Unknown,
}

impl Change {
    /// The verdict as the tables write it: `faster`, `slower`, `within noise` or `noise
    /// unknown`.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Self::Faster => "faster",
            Self::Slower => "slower",
            Self::Same => "within noise",
            Self::Unknown => "noise unknown",
        }
    }
}

/// The median of the round-by-round ratios `a[i] / b[i]` (over the rounds both took part
/// in, the first `min(len)`) and its distribution-free interval ([`median_interval`]).
/// For times taken in the same rounds ([`crate::rounds`]) this is the sharper estimate: a
/// slow phase of the machine lands on both sides of a pair and cancels out. The interval is
/// `None` with fewer than two pairs.
#[must_use]
pub fn paired_ratio(a: &[f64], b: &[f64]) -> (f64, Option<Interval>) {
    let n = a.len().min(b.len());
    let ratios: Vec<f64> = a[..n].iter().zip(&b[..n]).map(|(x, y)| x / y).collect();
    let Some(ratio) = median(&ratios) else {
        return (f64::NAN, None);
    };
    (ratio, (n >= 2).then(|| median_interval(&ratios)).flatten())
}

/// What a ratio of times `a / b` and its interval say: [`Change::Faster`] where the
/// interval lies below 1 and the ratio is at most `1 / (1 + min_effect)`,
/// [`Change::Slower`] where it lies above 1 and the ratio is at least `1 + min_effect`,
/// [`Change::Unknown`] without an interval.
#[must_use]
pub fn judge(ratio: f64, interval: Option<Interval>, min_effect: f64) -> Change {
    let Some(i) = interval else {
        return Change::Unknown;
    };
    if i.hi < 1.0 && ratio <= 1.0 / (1.0 + min_effect) {
        Change::Faster
    } else if i.lo > 1.0 && ratio >= 1.0 + min_effect {
        Change::Slower
    } else {
        Change::Same
    }
}

/// Whether times `a` differ from times `b` taken in the same rounds, round by round
/// ([`paired_ratio`]), beyond the noise and [`MIN_EFFECT`].
#[must_use]
pub fn paired_change(a: &[f64], b: &[f64]) -> Change {
    let (ratio, interval) = paired_ratio(a, b);
    judge(ratio, interval, MIN_EFFECT)
}

/// Student's t quantile `t(0.975, df)` for `df` = 1 to 30: the two-sided 95 %
/// ([`CONFIDENCE`]) bound of a mean of `df + 1` normal samples, in units of its standard
/// error.
const T_975: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
];

/// `t(0.975, df)`: from the table up to 30 degrees of freedom, beyond by the first two
/// terms of its expansion about the normal quantile `z` (Cornish-Fisher: `z + (z^3 + z) /
/// (4 df) + (5 z^5 + 16 z^3 + 3 z) / (96 df^2)`, 2.0395 at 31 as the exact value).
fn t_975(df: usize) -> f64 {
    const Z: f64 = 1.959_964;
    match df {
        0 => f64::INFINITY,
        1..=30 => T_975[df - 1],
        _ => {
            let (z3, df) = (Z * Z * Z, df as f64);
            Z + (z3 + Z) / (4.0 * df) + (5.0 * z3 * Z * Z + 16.0 * z3 + 3.0 * Z) / (96.0 * df * df)
        }
    }
}

/// The geometric mean of `ratios` measured in independent replicates (alternating pairs
/// of runs, each giving one ratio of medians) and its [`CONFIDENCE`] interval by Student's
/// t over their logarithms. Each replicate's ratio carries the noise within its runs and
/// the drift between them, so the spread of the replicates bounds both, where a bootstrap
/// of one replicate's rounds sees only the first. The t interval takes the logarithms as
/// normal; with few replicates it is wide (t = 12.71 for two, 4.30 for three). The
/// interval is `None` with fewer than two ratios or any that is not positive and finite.
#[must_use]
pub fn replicate_ratio(ratios: &[f64]) -> (f64, Option<Interval>) {
    if ratios.is_empty() || ratios.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return (f64::NAN, None);
    }
    let n = ratios.len();
    let logs: Vec<f64> = ratios.iter().map(|r| r.ln()).collect();
    let mean = logs.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return (mean.exp(), None);
    }
    let variance = logs.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let half = t_975(n - 1) * (variance / n as f64).sqrt();
    (
        mean.exp(),
        Some(Interval {
            lo: (mean - half).exp(),
            hi: (mean + half).exp(),
            confidence: CONFIDENCE,
        }),
    )
}

/// Who is fastest on one workload.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Fastest {
    /// One backend, separated from every other: each other's time over its own has an
    /// interval above 1.
    Clear(usize),
    /// The backends (indices, fastest median first) that tie within the noise with the one of
    /// the lowest median.
    Tie(Vec<usize>),
    /// Some backend has a single repetition: the noise is unknown; the index of the lowest
    /// median.
    Unknown(usize),
}

/// The fastest of `times` (one set of repetitions per backend, taken in the same rounds
/// and compared round by round; empty sets are ignored), or the backends that tie with it;
/// `None` when no backend has times.
#[must_use]
pub fn fastest(times: &[&[f64]]) -> Option<Fastest> {
    let mut order: Vec<(usize, f64)> = times
        .iter()
        .enumerate()
        .filter_map(|(i, t)| median(t).map(|m| (i, m)))
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let &(best, _) = order.first()?;
    if order.iter().any(|&(i, _)| times[i].len() < 2) {
        return Some(Fastest::Unknown(best));
    }
    let tied: Vec<usize> = order
        .iter()
        .map(|&(i, _)| i)
        .filter(|&i| i == best || paired_change(times[i], times[best]) != Change::Slower)
        .collect();
    Some(if tied.len() == 1 {
        Fastest::Clear(best)
    } else {
        Fastest::Tie(tied)
    })
}

/// The `p`-th percentile (`p` in percent, `0..=100`) of `sorted`, which must be in ascending
/// order, by the nearest-rank definition: the value of rank `ceil(p / 100 * n)` (ranks from 1,
/// and at least 1), that is the smallest value with at least `p` % of the `n` values at or
/// below it. Every percentile is therefore one of the values (no interpolation), `p = 0`
/// gives the minimum and `p = 100` the maximum. The rank is computed in integers, so no
/// rounding can move it. `None` for no values; a `p` above 100 is read as 100.
#[must_use]
pub fn nearest_rank(sorted: &[u64], p: u32) -> Option<u64> {
    let n = sorted.len() as u128;
    let rank = (u128::from(p.min(100)) * n).div_ceil(100).max(1);
    sorted.get(usize::try_from(rank).ok()? - 1).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Replicates' ratios: the geometric mean, and Student's t interval over their
    /// logarithms (here computed by hand), wide with few replicates and none with one.
    #[test]
    fn replicates_give_a_t_interval_of_the_geometric_mean() {
        let (r, i) = replicate_ratio(&[1.10, 1.12, 1.17]);
        let logs = [1.10f64.ln(), 1.12f64.ln(), 1.17f64.ln()];
        let mean = logs.iter().sum::<f64>() / 3.0;
        let sd = (logs.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        let i = i.expect("an interval");
        assert!((r - mean.exp()).abs() < 1e-12);
        assert!((i.lo - (mean - 4.303 * sd / 3f64.sqrt()).exp()).abs() < 1e-12);
        assert!((i.hi - (mean + 4.303 * sd / 3f64.sqrt()).exp()).abs() < 1e-12);
        assert!(i.lo > 1.0, "{i:?}");
        // Replicates that disagree: the interval holds 1.
        let (_, i) = replicate_ratio(&[0.99, 1.135, 1.27]);
        assert!(i.expect("an interval").contains(1.0));
        // The same spread over fewer replicates: a wider interval.
        let two = replicate_ratio(&[1.05, 1.15]).1.expect("an interval");
        let four = replicate_ratio(&[1.05, 1.15, 1.05, 1.15])
            .1
            .expect("an interval");
        assert!(two.lo < four.lo && two.hi > four.hi, "{two:?} {four:?}");
        let (one, none) = replicate_ratio(&[1.2]);
        assert!((one - 1.2).abs() < 1e-12 && none.is_none());
        assert!(replicate_ratio(&[]).0.is_nan());
        assert_eq!(replicate_ratio(&[1.1, 0.0]).1, None);
        assert_eq!(replicate_ratio(&[1.1, f64::NAN]).1, None);
    }

    /// The t quantile falls towards the normal's and joins its expansion smoothly.
    #[test]
    fn t_quantiles_fall_to_the_normal() {
        assert!(T_975.windows(2).all(|w| w[0] > w[1]));
        assert!(t_975(31) < t_975(30) && (t_975(31) - 2.0395).abs() < 0.0002);
        assert!((t_975(1000) - 1.96234).abs() < 0.0001);
        assert!(t_975(0).is_infinite());
    }

    /// Times from a skewed distribution (a floor plus exponential noise, as a busy machine
    /// gives): `floor * (1 + scale * Exp(1))`.
    fn skewed(g: &mut SplitMix, n: usize, floor: f64, scale: f64) -> Vec<f64> {
        (0..n)
            .map(|_| {
                let u = (g.next() >> 11) as f64 / (1u64 << 53) as f64;
                floor * (1.0 - scale * (1.0 - u).max(1e-300).ln())
            })
            .collect()
    }

    /// The median of `floor * (1 + scale * Exp(1))`: `floor * (1 + scale * ln 2)`.
    fn true_median(floor: f64, scale: f64) -> f64 {
        floor * (1.0 + scale * std::f64::consts::LN_2)
    }

    #[test]
    fn medians_and_small_intervals() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median_interval(&[1.0]), None);
        let two = median_interval(&[2.0, 1.0]).unwrap();
        assert_eq!((two.lo, two.hi, two.confidence), (1.0, 2.0, 0.5));
        let five = median_interval(&[5.0, 1.0, 4.0, 2.0, 3.0]).unwrap();
        assert_eq!((five.lo, five.hi, five.confidence), (1.0, 5.0, 0.9375));
        // Six samples reach 95 % with the extremes (96.9 %); nine with the second ones.
        assert!((median_interval(&[1.0; 6]).unwrap().confidence - 0.96875).abs() < 1e-12);
        let nine: Vec<f64> = (1..=9).map(f64::from).collect();
        let i = median_interval(&nine).unwrap();
        assert_eq!((i.lo, i.hi), (2.0, 8.0));
        assert!((i.confidence - 0.9609375).abs() < 1e-12);
    }

    #[test]
    fn the_median_interval_covers_as_stated() {
        let mut g = SplitMix(1);
        for n in [6, 11, 20] {
            let trials = 4000;
            let truth = true_median(1.0, 0.3);
            let mut covered = 0;
            let mut stated = 0.0;
            for _ in 0..trials {
                let i = median_interval(&skewed(&mut g, n, 1.0, 0.3)).unwrap();
                covered += usize::from(i.contains(truth));
                stated = i.confidence;
            }
            let rate = covered as f64 / trials as f64;
            assert!(stated >= CONFIDENCE, "n={n}: {stated}");
            // The binomial standard error over 4000 trials is about 0.3 %.
            assert!(
                (rate - stated).abs() < 0.015,
                "n={n}: {rate} against {stated}"
            );
        }
    }

    #[test]
    fn the_ratio_interval_covers_close_to_its_confidence() {
        let mut g = SplitMix(2);
        let (trials, n) = (400, 12);
        let truth = true_median(1.0, 0.2) / true_median(1.25, 0.2);
        let mut covered = 0;
        for _ in 0..trials {
            let a = skewed(&mut g, n, 1.0, 0.2);
            let b = skewed(&mut g, n, 1.25, 0.2);
            let (_, i) = ratio_interval(&a, &b);
            covered += usize::from(i.unwrap().contains(truth));
        }
        let rate = covered as f64 / trials as f64;
        // Percentile bootstraps of medians are a little liberal or conservative with few
        // samples; within 5 points of 95 % over 400 trials.
        assert!((rate - CONFIDENCE).abs() < 0.05, "coverage {rate}");
    }

    #[test]
    fn intervals_are_reproducible_from_their_samples() {
        let a = [1.0, 1.1, 0.9, 1.05, 1.2, 0.95];
        let b = [2.0, 2.1, 1.9, 2.2, 2.05, 1.95];
        assert_eq!(ratio_interval(&a, &b), ratio_interval(&a, &b));
        assert_ne!(ratio_interval(&a, &b).1, ratio_interval(&b, &a).1);
    }

    /// Two runs' times compared apart, as `compare-results` does before its common mode.
    fn change(a: &[f64], b: &[f64]) -> Change {
        let (ratio, interval) = ratio_interval(a, b);
        judge(ratio, interval, MIN_EFFECT)
    }

    #[test]
    fn changes_need_the_interval_and_the_minimum_effect() {
        let a: Vec<f64> = (0..10).map(|i| 1.0 + 0.001 * f64::from(i)).collect();
        let half: Vec<f64> = a.iter().map(|x| x * 0.5).collect();
        let slight: Vec<f64> = a.iter().map(|x| x * 1.01).collect();
        assert_eq!(change(&half, &a), Change::Faster);
        assert_eq!(change(&a, &half), Change::Slower);
        // Separated by the intervals, but 1 % is below the minimum effect.
        assert_eq!(change(&slight, &a), Change::Same);
        assert_eq!(change(&[0.5], &a), Change::Unknown);
        // A larger minimum effect claims less.
        let (r, i) = ratio_interval(&a, &half);
        assert_eq!(judge(r, i, 1.5), Change::Same);
        // The same distribution twice claims no change nearly always (an A/A test).
        let mut g = SplitMix(3);
        let trials = 300;
        let claimed = (0..trials)
            .filter(|_| {
                change(&skewed(&mut g, 8, 1.0, 0.2), &skewed(&mut g, 8, 1.0, 0.2)) != Change::Same
            })
            .count();
        assert!(
            claimed * 20 <= trials,
            "{claimed} of {trials} A/A pairs called a change"
        );
    }

    #[test]
    fn the_fastest_is_named_only_when_separated() {
        let fast = [1.0, 1.01, 0.99, 1.02, 0.98, 1.0];
        let close = [1.01, 1.0, 1.02, 0.99, 1.03, 1.0];
        let slow = [2.0, 2.02, 1.98, 2.01, 1.99, 2.0];
        assert_eq!(fastest(&[&slow, &fast]), Some(Fastest::Clear(1)));
        assert_eq!(
            fastest(&[&slow, &close, &fast]),
            Some(Fastest::Tie(vec![2, 1]))
        );
        assert_eq!(fastest(&[&slow, &[1.0]]), Some(Fastest::Unknown(1)));
        assert_eq!(fastest(&[&[], &slow]), Some(Fastest::Clear(1)));
        assert_eq!(fastest(&[]), None);
    }

    #[test]
    fn rounds_cancel_the_machine_s_slow_phases() {
        // Two backends, one 5 % faster, through rounds where the machine is 30 % slower in
        // the middle: apart, the phases swamp the difference; round by round, it shows.
        let phase = [1.0, 1.0, 1.3, 1.3, 1.3, 1.0, 1.0, 1.3, 1.0, 1.0];
        let a: Vec<f64> = phase.iter().map(|p| p * 1.00).collect();
        let b: Vec<f64> = phase.iter().map(|p| p * 1.05).collect();
        assert_eq!(change(&b, &a), Change::Same);
        assert_eq!(paired_change(&b, &a), Change::Slower);
        let (ratio, interval) = paired_ratio(&b, &a);
        let interval = interval.unwrap();
        assert!((ratio - 1.05).abs() < 1e-12 && interval.lo > 1.04 && interval.hi < 1.06);
        // Only the rounds both took part in are paired; one pair has no interval.
        assert_eq!(paired_ratio(&[2.0, 9.0], &[1.0]), (2.0, None));
        assert!(paired_ratio(&[], &[1.0]).0.is_nan());
    }

    /// Nearest-rank percentiles on hand-made lists, each value chosen so that an off-by-one
    /// in the rank (rounding down instead of up, or indexing from 1) gives another answer.
    #[test]
    fn nearest_rank_percentiles_are_exact() {
        let tens: Vec<u64> = (1..=10).map(|i| i * 10).collect();
        // n = 10: p50 is rank 5, p90 rank 9, p99 rank ceil(9.9) = 10.
        assert_eq!(nearest_rank(&tens, 50), Some(50));
        assert_eq!(nearest_rank(&tens, 90), Some(90));
        assert_eq!(nearest_rank(&tens, 99), Some(100));
        assert_eq!(nearest_rank(&tens, 0), Some(10));
        assert_eq!(nearest_rank(&tens, 100), Some(100));
        assert_eq!(nearest_rank(&tens, 101), Some(100));
        // n = 7: p50 is rank ceil(3.5) = 4 (rounding down would give 3), p90 rank
        // ceil(6.3) = 7 (not 6), p10 rank ceil(0.7) = 1.
        let seven = [1, 2, 3, 4, 5, 6, 7];
        assert_eq!(nearest_rank(&seven, 50), Some(4));
        assert_eq!(nearest_rank(&seven, 90), Some(7));
        assert_eq!(nearest_rank(&seven, 10), Some(1));
        // n = 200: p99 is rank 198 exactly, p1 rank 2.
        let many: Vec<u64> = (1..=200).collect();
        assert_eq!(nearest_rank(&many, 99), Some(198));
        assert_eq!(nearest_rank(&many, 1), Some(2));
        assert_eq!(nearest_rank(&many, 50), Some(100));
        // Ties: half the rays do no work, so the median is 0 and p90 the rest.
        assert_eq!(nearest_rank(&[0, 0, 0, 5], 50), Some(0));
        assert_eq!(nearest_rank(&[0, 0, 0, 5], 75), Some(0));
        assert_eq!(nearest_rank(&[0, 0, 0, 5], 76), Some(5));
        assert_eq!(nearest_rank(&[42], 50), Some(42));
        assert_eq!(nearest_rank(&[], 50), None);
    }
}
