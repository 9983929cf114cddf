//! Per-finger moments of the tactile data, per time step (the second paper, Sec. V-B):
//! over one fingertip's pressures (255 − reading on the iCub) the mean, standard
//! deviation, skewness, maximum and minimum.

use serde::{Deserialize, Serialize};

/// Summary statistics of one sensor's pressures at one time step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FingerStats {
    pub mean: f64,
    /// Population standard deviation (divides by n).
    pub sd: f64,
    /// Population skewness m3 / m2^1.5; 0 when the values are all equal.
    pub skewness: f64,
    pub max: f64,
    pub min: f64,
}

impl FingerStats {
    pub const NAMES: [&'static str; 5] = ["mean", "sd", "skewness", "max", "min"];

    pub fn of(values: &[f64]) -> FingerStats {
        if values.is_empty() {
            return FingerStats::default();
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let (mut m2, mut m3) = (0.0, 0.0);
        let (mut max, mut min) = (f64::NEG_INFINITY, f64::INFINITY);
        for &v in values {
            let d = v - mean;
            m2 += d * d;
            m3 += d * d * d;
            max = max.max(v);
            min = min.min(v);
        }
        m2 /= n;
        m3 /= n;
        // A spread below rounding noise of the mean counts as constant.
        let skewness = if m2 > 1e-24 * (1.0 + mean * mean) {
            m3 / m2.powf(1.5)
        } else {
            0.0
        };
        FingerStats {
            mean,
            sd: m2.sqrt(),
            skewness,
            max,
            min,
        }
    }

    pub fn to_array(self) -> [f64; 5] {
        [self.mean, self.sd, self.skewness, self.max, self.min]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_moments() {
        // values 1, 2, 6: mean 3, deviations -2, -1, 3; m2 = 14/3, m3 = (−8 − 1 + 27)/3 = 6
        let s = FingerStats::of(&[1.0, 2.0, 6.0]);
        assert!((s.mean - 3.0).abs() < 1e-12);
        assert!((s.sd - (14.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((s.skewness - 6.0 / (14.0f64 / 3.0).powf(1.5)).abs() < 1e-12);
        assert_eq!((s.max, s.min), (6.0, 1.0));
        let c = FingerStats::of(&[4.0; 12]);
        assert_eq!(c.skewness, 0.0);
        assert_eq!(c.sd, 0.0);
    }
}
