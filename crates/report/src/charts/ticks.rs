//! The charts' axes: their ranges and ticks, and the plain numbers their labels and
//! tooltips show. Log axes label every decade with minor ticks at 2..9, or 1-2-5 steps (then
//! every integer, then a linear step) where the data span too few decades, so that at least
//! three labels show; values are written plainly (`0.01`, `20`, `1k`, `2.5M`), never `1e0`.

/// An axis (log, or linear for [`super::Plot::Lines`]'s `x`): its range and its ticks.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Axis {
    /// `log10` of the lowest value shown (a linear axis: the value).
    pub(super) lo: f64,
    /// `log10` of the highest value shown (a linear axis: the value).
    pub(super) hi: f64,
    /// Whether values are placed linearly rather than by their logarithm.
    pub(super) linear: bool,
    /// Labelled ticks: value and label.
    pub(super) major: Vec<(f64, String)>,
    /// Unlabelled ticks.
    pub(super) minor: Vec<f64>,
}

impl Axis {
    /// Where `v` sits in the axis's own coordinate: `v` on a linear axis, `log10(v)` on a
    /// log one (the coordinate the chart is drawn in, between [`Self::lo`] and [`Self::hi`]).
    pub(super) fn at(&self, v: f64) -> f64 {
        if self.linear { v } else { v.log10() }
    }

    /// Where `v` falls along the axis, 0 at its low end and 1 at its high end.
    pub(super) fn frac(&self, v: f64) -> f64 {
        (self.at(v) - self.lo) / (self.hi - self.lo)
    }

    /// Whether `v` can be placed on the axis (a log axis: positive values only).
    pub(super) fn shows(&self, v: f64) -> bool {
        v.is_finite() && (self.linear || v > 0.0)
    }
}

/// Superscript digits and sign, for `10⁻⁵`.
fn superscript(e: i32) -> String {
    e.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect()
}

/// Decimals that show a multiple of `step` exactly.
fn decimals_for(step: f64) -> usize {
    if step >= 1.0 - 1e-9 {
        0
    } else {
        ((-step.log10() - 1e-9).ceil() as usize).min(12)
    }
}

/// `v` with `decimals` decimals, trailing zeros dropped.
fn trimmed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A value written plainly, exact to `step`: `0.001`, `0.25`, `20`, `1k`, `2.5M`; below
/// 0.0001 as `2×10⁻⁵`.
pub(super) fn number(v: f64, step: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if a < 1e-4 * (1.0 - 1e-9) {
        let e = a.log10().floor() as i32;
        let scale = 10f64.powi(e);
        let m = trimmed(v / scale, decimals_for(step / scale));
        return if m == "1" {
            format!("10{}", superscript(e))
        } else {
            format!("{m}×10{}", superscript(e))
        };
    }
    let (div, suffix) = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")]
        .into_iter()
        .find(|(d, _)| a >= d * (1.0 - 1e-9))
        .unwrap_or((1.0, ""));
    format!("{}{suffix}", trimmed(v / div, decimals_for(step / div)))
}

/// A measured value for a tooltip: four significant digits.
pub(super) fn value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor();
    number(v, 10f64.powf(e - 3.0))
}

/// The values `m * 10^k` in `[lo, hi]` (logs) for each `m` of `mantissas`, ascending.
fn log_candidates(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in (lo.floor() as i32 - 1)..=(hi.ceil() as i32) {
        for &m in mantissas {
            let v = m * 10f64.powi(k);
            let l = v.log10();
            if l >= lo - 1e-9 && l <= hi + 1e-9 {
                out.push(v);
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// The step of a multiple of 10 that shows `v` exactly (`300` → 100, `0.02` → 0.01).
fn power_step(v: f64) -> f64 {
    10f64.powf((v.abs().log10() + 1e-9).floor())
}

/// A log axis over the positive finite `values`: a little wider than their range, labelled
/// at every decade with minor ticks at 2..9 when at least three decades show; else at 1-2-5
/// steps, every integer multiple of a decade, or a plain step, whichever first gives three
/// labels or more.
pub(super) fn log_axis(values: impl Iterator<Item = f64>) -> Axis {
    let (min, max) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (mut lo, mut hi) = if min.is_finite() {
        (min.log10(), max.log10())
    } else {
        (0.0, 1.0)
    };
    // A little room around the data; a single value gets a factor of 1.4 either side.
    let pad = if hi - lo < 1e-9 {
        0.15
    } else {
        ((hi - lo) * 0.04).max(0.02)
    };
    lo -= pad;
    hi += pad;
    let labelled = |values: Vec<f64>| -> Vec<(f64, String)> {
        values
            .into_iter()
            .map(|v| (v, number(v, power_step(v))))
            .collect()
    };
    let decades = log_candidates(lo, hi, &[1.0]);
    if decades.len() >= 3 {
        // More than ten decades: every other one labelled, the rest minor.
        let every = if decades.len() > 10 { 2 } else { 1 };
        let (mut major, mut minor) = (Vec::new(), Vec::new());
        for (i, v) in decades.iter().copied().enumerate() {
            if i % every == 0 {
                major.push(v);
            } else {
                minor.push(v);
            }
        }
        if decades.len() <= 8 {
            minor.extend(log_candidates(
                lo,
                hi,
                &[2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
            ));
        }
        minor.sort_by(f64::total_cmp);
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(major),
            minor,
        };
    }
    let steps = log_candidates(lo, hi, &[1.0, 2.0, 5.0]);
    if steps.len() >= 3 {
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(steps),
            minor: log_candidates(lo, hi, &[3.0, 4.0, 6.0, 7.0, 8.0, 9.0]),
        };
    }
    let integers = log_candidates(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    if integers.len() >= 3 {
        return Axis {
            lo,
            hi,
            linear: false,
            major: labelled(integers),
            minor: Vec::new(),
        };
    }
    // A narrow range: the largest 1-2-5 step that fits three times.
    let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
    let third = (b - a) / 3.0;
    let p = power_step(third);
    let step = [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s <= third * (1.0 + 1e-9))
        .unwrap_or(p);
    Axis {
        lo,
        hi,
        linear: false,
        major: multiples(a, b, step),
        minor: Vec::new(),
    }
}

/// The multiples of `step` in `[a, b]`, labelled.
fn multiples(a: f64, b: f64, step: f64) -> Vec<(f64, String)> {
    let first = (a / step).ceil() as i64;
    let last = (b / step).floor() as i64;
    (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            (v, number(v, step))
        })
        .collect()
}

/// A linear axis over `values` (the finite ones), labelled every 1, 2 or 5 times a power of
/// ten: the smallest such step that gives at most 8 labels.
pub(super) fn linear_axis(values: impl Iterator<Item = f64>) -> Axis {
    let (min, max) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (min, max) = if min.is_finite() {
        (min, max)
    } else {
        (0.0, 1.0)
    };
    let span = (max - min).max(max.abs().max(1.0) * 1e-9);
    let (lo, hi) = (min - span * 0.03, max + span * 0.03);
    let p = power_step(span / 8.0);
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| span / s <= 8.0 + 1e-9)
        .unwrap_or(10.0 * p);
    Axis {
        lo,
        hi,
        linear: true,
        major: multiples(lo, hi, step),
        minor: Vec::new(),
    }
}
