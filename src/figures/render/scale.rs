//! Axis limits, pixel mapping and tick values with their labels.

use crate::figures::FigureError;
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
/// A span that cannot be drawn (it overflows, or lies below f64's resolution at its
/// magnitude) is an error naming the axis, not a figure drawn for minutes.
pub(super) fn limits(values: &[f64], axis: &Axis, pad: f64) -> Result<(f64, f64), FigureError> {
    let (lo, hi) = padded(values, axis, pad);
    let drawable = lo.is_finite()
        && hi.is_finite()
        && (hi - lo).is_finite()
        && hi > lo
        // At least ~1e-12 of the magnitude, so that ticks can be told apart.
        && (hi - lo) > 1e-12 * lo.abs().max(hi.abs());
    if drawable {
        Ok((lo, hi))
    } else {
        Err(FigureError::Invalid(format!(
            "axis {:?}: the range {lo:e} … {hi:e} cannot be drawn",
            axis.title
        )))
    }
}

fn padded(values: &[f64], axis: &Axis, pad: f64) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in values.iter().filter(|&&v| axis.scale.can_draw(v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    // An included end the data does not pass is a natural bound (a share's 0 and 1): the
    // axis stops there, unpadded.
    let (mut natural_lo, mut natural_hi) = (false, false);
    if let Some([a, b]) = axis.include {
        natural_lo = a <= lo;
        natural_hi = b >= hi;
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
            let (pl, ph) = (p * f64::from(!natural_lo), p * f64::from(!natural_hi));
            (10f64.powf(l - pl), 10f64.powf(h + ph))
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
            let l = match (natural_lo, lo >= 0.0) {
                (true, _) => lo,
                (false, true) => (lo - p).max(0.0),
                (false, false) => lo - p,
            };
            (l, if natural_hi { hi } else { hi + p })
        }
    }
}

/// "Nice" ticks (steps of 1, 2, 2.5 or 5 × 10^k) within `lo..=hi`, at most about `max`
/// and at least three, with the number of decimals their labels need.
pub(super) fn linear_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, usize) {
    let mut best = (Vec::new(), 0);
    // A coarse step can leave fewer than three ticks inside the range: refine until not.
    for m in max.max(3)..max.max(3) + 8 {
        let (ticks, decimals) = nice_ticks(lo, hi, m);
        let enough = ticks.len() >= 3;
        best = (ticks, decimals);
        if enough {
            break;
        }
    }
    best
}

fn nice_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, usize) {
    let raw = (hi - lo) / max.max(1) as f64;
    if !(raw.is_finite() && raw > 0.0) {
        return (Vec::new(), 0);
    }
    let exp = raw.log10().floor();
    let mag = 10f64.powf(exp);
    let (mant, extra) = [(1.0, 0), (2.0, 0), (2.5, 1), (5.0, 0), (10.0, 0)]
        .into_iter()
        .find(|(m, _)| m * mag >= raw * (1.0 - 1e-9))
        .unwrap_or((10.0, 0));
    let step = mant * mag;
    let decimals = (-(exp + if mant >= 10.0 { 1.0 } else { 0.0 })).max(0.0) as usize + extra;
    let first = (lo / step - 1e-9).ceil();
    let mut ticks = Vec::new();
    // Bounded: a span is at most ~max steps, whatever its magnitude.
    for k in 0..=(4 * max + 4) {
        let v = (first + k as f64) * step;
        if v > hi + step * 1e-9 {
            break;
        }
        ticks.push(if v.abs() < step * 1e-9 { 0.0 } else { v });
    }
    (ticks, decimals)
}

/// Ticks of a log axis at round values: decades; with fewer than three, 1, 2 and 5 per
/// decade; then every integer multiple; and on a range narrower than that, nice linear
/// values (still placed on the log scale).
pub(super) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    let decade = |k: i32| format!("1e{k}").parse::<f64>().unwrap_or(f64::NAN);
    let within = |v: &f64| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12);
    let mut ticks: Vec<f64> = (a..=b).map(decade).collect();
    if ticks.len() > 8 {
        // Many decades: every other one (or sparser), from a round power.
        let every = ticks.len().div_ceil(8) as i32;
        ticks = (a..=b).filter(|k| k % every == 0).map(decade).collect();
    }
    for mantissas in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ] {
        if ticks.len() >= 3 {
            break;
        }
        ticks = (a - 1..=b)
            .flat_map(|k| mantissas.iter().map(move |m| m * decade(k)))
            .filter(within)
            .collect();
    }
    // Too few, or bunched at one end (90, 100, 200 on 85–210: no three labels fit): round
    // linear steps, which a log axis this narrow shows nearly evenly.
    if ticks.len() < 3 || log_spread(&ticks) > 3.0 {
        ticks = linear_ticks(lo, hi, 4).0;
    }
    ticks
}

/// The widest gap between neighbouring ticks over the narrowest, in log space.
fn log_spread(ticks: &[f64]) -> f64 {
    let gaps: Vec<f64> = ticks.windows(2).map(|w| (w[1] / w[0]).log10()).collect();
    let widest = gaps.iter().copied().fold(0.0, f64::max);
    let narrowest = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    widest / narrowest
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

/// A log tick's label: the round value as written ("0.02", "500", "1e-6"), with at most
/// three significant digits.
pub(super) fn format_log_tick(v: f64) -> String {
    let k = v.log10();
    if (k - k.round()).abs() < 1e-9 && !(-3.0..=4.0).contains(&k) {
        return format!("1e{}", k.round());
    }
    if !(1e-3..1e5).contains(&v.abs()) {
        return format!("{v:.2e}").replace(".00e", "e").replace("0e", "e");
    }
    // Three significant digits, trailing zeros dropped.
    let decimals = (2.0 - v.abs().log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

pub(super) struct Ticks {
    pub(super) values: Vec<f64>,
    pub(super) labels: Vec<String>,
}

/// Round linear values on a log axis (labelled as log ticks): where the log ticks bunch
/// into a corner of a narrow span, these spread across it.
pub(super) fn linear_on_log(lo: f64, hi: f64, max: usize) -> Ticks {
    let values = linear_ticks(lo, hi, max).0;
    let labels = (values.iter().zip(log_gaps(&values)))
        .map(|(&v, gap)| log_label(v, gap))
        .collect();
    Ticks { values, labels }
}

/// A log tick's label when its nearest neighbour lies `gap` decades away: the round value
/// as written, or, where neighbours are closer than its three significant digits tell
/// apart (a narrow span of 1.14e-4 … 1.15e-4), the decimals their spacing needs.
fn log_label(v: f64, gap: f64) -> String {
    let ratio = 10f64.powf(gap.abs()) - 1.0;
    if ratio.is_finite() && ratio > 0.0 && ratio < 0.05 {
        tick_label(v, v.abs() * ratio, Scale::Linear)
    } else {
        format_log_tick(v)
    }
}

/// Each tick's distance to its nearest neighbour, in decades.
fn log_gaps(values: &[f64]) -> Vec<f64> {
    let logs: Vec<f64> = values.iter().map(|v| v.log10()).collect();
    (0..logs.len())
        .map(|i| {
            let before = i.checked_sub(1).map(|j| logs[i] - logs[j]);
            let after = logs.get(i + 1).map(|l| l - logs[i]);
            before
                .into_iter()
                .chain(after)
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

pub(super) fn ticks_for(lo: f64, hi: f64, log: bool, max: usize) -> Ticks {
    if log {
        let values = log_ticks(lo, hi);
        let labels = (values.iter().zip(log_gaps(&values)))
            .map(|(&v, gap)| log_label(v, gap))
            .collect();
        Ticks { values, labels }
    } else {
        let (values, decimals) = linear_ticks(lo, hi, max);
        let labels = values.iter().map(|&v| format_tick(v, decimals)).collect();
        Ticks { values, labels }
    }
}

/// The ticks the export draws on an axis from `lo` to `hi` (data units; about `max` of
/// them, at least three): values with their labels. The workbench's plots use them too, so
/// that screen and paper show the same round values.
pub fn axis_ticks(lo: f64, hi: f64, scale: Scale, max: usize) -> Vec<(f64, String)> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) || (scale == Scale::Log && lo <= 0.0) {
        return Vec::new();
    }
    let t = ticks_for(lo, hi, scale == Scale::Log, max);
    t.values.into_iter().zip(t.labels).collect()
}

/// The limits the export gives an axis showing `values`: the data and the axis' included
/// range, padded by `pad` of the span except at a natural bound. None when they cannot be
/// drawn.
pub fn axis_limits(values: &[f64], axis: &Axis, pad: f64) -> Option<(f64, f64)> {
    limits(values, axis, pad).ok()
}

/// The label of a linear tick at `value` among ticks `step` apart, or of a log tick whose
/// nearest neighbour lies `step` decades away.
pub fn tick_label(value: f64, step: f64, scale: Scale) -> String {
    match scale {
        Scale::Log => log_label(value, step),
        Scale::Linear => {
            let step = step.abs();
            let decimals = if step > 0.0 && step.is_finite() {
                // 2.5 × 10^k needs one more decimal than its power.
                let exp = step.log10().floor();
                let extra = usize::from((step / 10f64.powf(exp) - 2.5).abs() < 1e-9);
                (-exp).max(0.0) as usize + extra
            } else {
                0
            };
            format_tick(value, decimals)
        }
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

    /// A log axis spanning less than a decade still gets three round ticks (before, it
    /// read "125.893, 158.489, 199.526" on screen and showed one tick in export).
    #[test]
    fn narrow_log_axes_get_three_round_ticks() {
        assert_eq!(log_ticks(0.3, 4.0), vec![0.5, 1.0, 2.0]);
        assert_eq!(log_ticks(2.5, 9.5), vec![3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        assert_eq!(log_ticks(125.0, 200.0), vec![140.0, 160.0, 180.0, 200.0]);
        assert_eq!(format_log_tick(125.893), "126");
        // 1–9 mantissas give 90, 100, 200 here, bunched at the bottom: linear steps instead.
        let t = log_ticks(85.0, 210.0);
        assert!(
            t.len() >= 3 && t.iter().all(|&v| (85.0..=210.0).contains(&v)),
            "{t:?}"
        );
        assert!(log_spread(&t) <= 3.0, "{t:?}");
        assert_eq!(format_log_tick(0.002), "0.002");
    }

    #[test]
    fn tick_labels_match_their_step() {
        assert_eq!(tick_label(0.25, 0.05, Scale::Linear), "0.25");
        assert_eq!(tick_label(7.5, 2.5, Scale::Linear), "7.5");
        assert_eq!(tick_label(40.0, 20.0, Scale::Linear), "40");
        assert_eq!(tick_label(200.0, 0.5, Scale::Log), "200");
        // Neighbours 0.4 % apart: more digits than a round log label has.
        let close = [1.142e-4, 1.146e-4, 1.150e-4];
        let labels: Vec<String> = (close.iter().zip(log_gaps(&close)))
            .map(|(&v, g)| log_label(v, g))
            .collect();
        assert_eq!(labels, ["1.142e-4", "1.146e-4", "1.15e-4"]);
    }

    #[test]
    fn linear_axes_get_at_least_three_ticks() {
        // One nice step (0.5) would leave a single tick inside 0.04 … 0.96.
        let (t, _) = linear_ticks(0.04, 0.96, 2);
        assert!(t.len() >= 3, "{t:?}");
        assert!(t.iter().all(|v| (0.04..=0.96).contains(v)));
    }

    #[test]
    fn undrawable_ranges_are_errors() {
        let axis = Axis::new("time", "s");
        assert!(limits(&[-1e308, 1e308], &axis, 0.04).is_err());
        assert!(limits(&[1e20, 1e20 + 65536.0], &axis, 0.04).is_err());
        assert!(limits(&[5.0, 5.0], &axis, 0.04).is_ok());
    }

    #[test]
    fn limits_include_range_and_skip_bad_values() {
        let axis = Axis::new("a", "").including(0.0, 1.0);
        assert_eq!(limits(&[0.5, f64::NAN], &axis, 0.0).unwrap(), (0.0, 1.0));
        let log = Axis::new("t", "s").log();
        let (lo, hi) = limits(&[-1.0, 0.01, 100.0], &log, 0.0).unwrap();
        assert!((lo - 0.01).abs() < 1e-12 && (hi - 100.0).abs() < 1e-9);
    }
}
