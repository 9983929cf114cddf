//! Axis limits, pixel mapping and tick values with their labels.

use crate::figures::model::{Axis, Scale};

/// One numeric axis mapped onto a pixel span.
#[derive(Clone, Copy, Debug)]
pub(super) struct Span {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) log: bool,
    pub(super) p0: f64,
    pub(super) p1: f64,
}

impl Span {
    pub(super) fn map(&self, v: f64) -> f64 {
        let t = if self.log {
            (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        self.p0 + t * (self.p1 - self.p0)
    }
}

/// Axis limits covering `values` and the axis' included range, padded by `pad` of the span
/// on each side (in log space on a log axis). Falls back to a unit range when empty.
pub(super) fn limits(values: &[f64], axis: &Axis, pad: f64) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in values.iter().filter(|&&v| axis.scale.can_draw(v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if let Some([a, b]) = axis.include {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    match axis.scale {
        Scale::Log => {
            if !(lo.is_finite() && hi.is_finite()) {
                return (1.0, 10.0);
            }
            let (l, h) = if hi > lo {
                (lo.log10(), hi.log10())
            } else {
                (lo.log10() - 0.5, lo.log10() + 0.5)
            };
            let p = (h - l) * pad;
            (10f64.powf(l - p), 10f64.powf(h + p))
        }
        Scale::Linear => {
            if !(lo.is_finite() && hi.is_finite()) {
                return (0.0, 1.0);
            }
            if hi <= lo {
                let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
                return (lo - d, lo + d);
            }
            let p = (hi - lo) * pad;
            // Padding never pushes a non-negative range below 0 (counts, scores).
            let l = if lo >= 0.0 { (lo - p).max(0.0) } else { lo - p };
            (l, hi + p)
        }
    }
}

/// "Nice" ticks (steps of 1, 2, 2.5 or 5 × 10^k) within `lo..=hi`, at most about `max`,
/// with the number of decimals their labels need.
pub(super) fn linear_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, usize) {
    let raw = (hi - lo) / max.max(1) as f64;
    let exp = raw.log10().floor();
    let mag = 10f64.powf(exp);
    let (mant, extra) = [(1.0, 0), (2.0, 0), (2.5, 1), (5.0, 0), (10.0, 0)]
        .into_iter()
        .find(|(m, _)| m * mag >= raw * (1.0 - 1e-9))
        .unwrap_or((10.0, 0));
    let step = mant * mag;
    let decimals = (-(exp + if mant >= 10.0 { 1.0 } else { 0.0 })).max(0.0) as usize + extra;
    let first = (lo / step - 1e-9).ceil() as i64;
    let mut ticks = Vec::new();
    for k in first.. {
        let v = k as f64 * step;
        if v > hi + step * 1e-9 {
            break;
        }
        ticks.push(if v.abs() < step * 1e-9 { 0.0 } else { v });
    }
    (ticks, decimals)
}

pub(super) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    let decade = |k: i32| format!("1e{k}").parse::<f64>().unwrap_or(f64::NAN);
    let mut ticks: Vec<f64> = (a..=b).map(decade).collect();
    if ticks.len() < 3 {
        // Less than three decades: also 2× and 5× each decade.
        ticks = (a - 1..=b)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * decade(k)))
            .filter(|&v| v >= lo && v <= hi)
            .collect();
    }
    ticks
}

pub(super) fn format_tick(v: f64, decimals: usize) -> String {
    // Scientific notation for large values and for steps finer than 1e-4.
    let big = v != 0.0 && (v.abs() >= 1e5 || decimals > 4);
    let s = if big {
        format!("{v:e}")
    } else {
        format!("{v:.decimals$}")
    };
    // No "-0" or "-0.0".
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

pub(super) fn format_log_tick(v: f64) -> String {
    let k = v.log10();
    if (k - k.round()).abs() < 1e-9 && !(-4.0..=4.0).contains(&k) {
        format!("1e{}", k.round())
    } else {
        format!("{v}")
    }
}

pub(super) struct Ticks {
    pub(super) values: Vec<f64>,
    pub(super) labels: Vec<String>,
}

pub(super) fn ticks_for(lo: f64, hi: f64, log: bool, max: usize) -> Ticks {
    if log {
        let values = log_ticks(lo, hi);
        let labels = values.iter().map(|&v| format_log_tick(v)).collect();
        Ticks { values, labels }
    } else {
        let (values, decimals) = linear_ticks(lo, hi, max);
        let labels = values.iter().map(|&v| format_tick(v, decimals)).collect();
        Ticks { values, labels }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_nice() {
        let (t, d) = linear_ticks(0.0, 1.0, 5);
        assert_eq!(t, vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]);
        assert_eq!(d, 1);
        assert_eq!(format_tick(t[3], d), "0.6");
        let (t, d) = linear_ticks(-3.0, 7.0, 4);
        assert_eq!(
            (t.first().copied(), t.last().copied(), d),
            (Some(-2.5), Some(5.0), 1)
        );
        assert_eq!(format_tick(-0.00002, 5), "-2e-5");
        assert_eq!(format_tick(250000.0, 0), "2.5e5");
        assert_eq!(format_tick(-0.001, 2), "0.00");
    }

    #[test]
    fn log_ticks_cover_decades() {
        assert_eq!(log_ticks(0.005, 200.0), vec![0.01, 0.1, 1.0, 10.0, 100.0]);
        assert_eq!(log_ticks(1.5, 30.0), vec![2.0, 5.0, 10.0, 20.0]);
        assert_eq!(format_log_tick(1e-6), "1e-6");
        assert_eq!(format_log_tick(0.01), "0.01");
    }

    #[test]
    fn limits_include_range_and_skip_bad_values() {
        let axis = Axis::new("a", "").including(0.0, 1.0);
        assert_eq!(limits(&[0.5, f64::NAN], &axis, 0.0), (0.0, 1.0));
        let log = Axis::new("t", "s").log();
        let (lo, hi) = limits(&[-1.0, 0.01, 100.0], &log, 0.0);
        assert!((lo - 0.01).abs() < 1e-12 && (hi - 100.0).abs() < 1e-9);
    }
}
