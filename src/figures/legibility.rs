//! The legibility rules the export and the screen share, in whatever unit the caller draws
//! in (device pixels on paper, points on screen): which category labels fit, how many
//! ticks a colour bar or an axis of a given length takes, and the decimals a set of values
//! needs. The export (`render/`) and the workbench's figure widget both call these, so that
//! a figure reads the same in a tile and on the page.

/// Which of a category axis' labels are drawn: every `step`-th from the first, at `scale`
/// of the text's size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thinning {
    pub step: usize,
    pub scale: f64,
}

impl Thinning {
    /// Is category `i`'s label drawn?
    pub fn shows(&self, i: usize) -> bool {
        i.is_multiple_of(self.step)
    }
}

/// `count` category labels along slots `slot` apart, each needing `needed` along the axis:
/// every one when they fit, else every k-th; never fewer than three (the first, middle and
/// last), drawn smaller (down to 60 %) when three would not fit at full size.
pub fn thin_categories(count: usize, slot: f64, needed: f64) -> Thinning {
    let slot = slot.max(1e-9);
    let mut step = (needed / slot).ceil().max(1.0) as usize;
    let mut scale = 1.0;
    if count >= 3 && count.div_ceil(step) < 3 {
        step = (count - 1) / 2;
        scale = (slot * step as f64 / needed).clamp(0.6, 1.0);
    }
    Thinning { step, scale }
}

/// About how many ticks an axis `length` long takes when one label needs `per_label`
/// along it: at least three, at most ten.
pub fn tick_count(length: f64, per_label: f64) -> usize {
    (length / per_label.max(1e-9)).floor().clamp(3.0, 10.0) as usize
}

/// The decimals that show `values` to the precision their spread needs: two significant
/// digits of the spread (of the value when all are equal), none for whole numbers, at
/// most six.
pub fn decimals_for(values: &[f64]) -> usize {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.iter().all(|v| v.fract() == 0.0) {
        return 0;
    }
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let spread = if hi > lo {
        hi - lo
    } else {
        hi.abs().max(lo.abs())
    };
    if !(spread.is_finite() && spread > 0.0) {
        return 0;
    }
    (1.0 - spread.log10().floor()).clamp(0.0, 6.0) as usize
}

/// The unit a time axis reads best in, and its factor from seconds: the largest of whose
/// multiples still leaves the longest time at 1 or more (0.000015 s reads "15 µs": five
/// digits shorter, so that a narrow span's ticks fit side by side).
pub fn time_unit(longest_seconds: f64) -> (&'static str, f64) {
    [("s", 1.0), ("ms", 1e3), ("µs", 1e6)]
        .into_iter()
        .find(|(_, f)| longest_seconds * f >= 1.0)
        .unwrap_or(("ns", 1e9))
}

/// `v` with `decimals` decimals, never "-0".
pub fn value_text(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_read_in_the_unit_that_leaves_them_at_one_or_more() {
        assert_eq!(time_unit(42.0), ("s", 1.0));
        assert_eq!(time_unit(1.0), ("s", 1.0));
        assert_eq!(time_unit(0.25), ("ms", 1e3));
        assert_eq!(time_unit(1.9e-5), ("µs", 1e6));
        assert_eq!(time_unit(3e-10), ("ns", 1e9));
    }

    #[test]
    fn categories_thin_to_what_fits_and_keep_three() {
        // Fifty basis indices in 6-px slots, each label 20 px with its gap: every 4th.
        let t = thin_categories(50, 6.0, 20.0);
        assert_eq!(t.step, 4);
        assert!(t.shows(0) && t.shows(48) && !t.shows(1));
        assert_eq!(thin_categories(10, 40.0, 30.0).step, 1);
        // Far too little room: first, middle and last, smaller.
        let t = thin_categories(5, 5.0, 40.0);
        assert_eq!(t.step, 2);
        assert!((t.scale - 0.6).abs() < 1e-12);
    }

    #[test]
    fn numbers_get_the_decimals_their_spread_needs() {
        assert_eq!(decimals_for(&[380.0, 357.216]), 0);
        assert_eq!(decimals_for(&[380.0, 120.0]), 0);
        assert_eq!(decimals_for(&[0.974, 0.961, 0.934]), 3);
        assert_eq!(decimals_for(&[0.5, 0.75]), 2);
        assert_eq!(decimals_for(&[0.25]), 2);
        assert_eq!(decimals_for(&[3.0, 40.0]), 0);
        assert_eq!(value_text(-0.0001, 2), "0.00");
        assert_eq!(tick_count(100.0, 36.0), 3);
        assert_eq!(tick_count(2000.0, 36.0), 10);
    }
}
