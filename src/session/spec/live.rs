//! The spec's `live` section: how a live stream is cut into grasps where the spec's
//! `grasps` do not say.

use serde::Deserialize;

/// How a live stream is read where the spec's `grasps` do not say: `contact` cuts grasps by
/// the total pressure when the stream has no events topic (see `live::cut`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LiveSpec {
    #[serde(default)]
    pub contact: ContactParams,
}

/// Cutting by contact: the total pressure (every taxel after its transform) over a baseline
/// that follows it while the hand is idle. A grasp begins when the total rises above the
/// baseline by `onset`, ends when it falls back below `offset`, and is kept when it lasted
/// at least `min_duration_s`. The thresholds are the larger of a multiple of the idle
/// total's standard deviation and a floor in pressure units, so that a quiet sensor and a
/// noisy one both need a real touch.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactParams {
    /// Onset: this many standard deviations of the idle total above the baseline (default 6).
    pub onset_sigma: f64,
    /// Offset: back below this many standard deviations (default 3).
    pub offset_sigma: f64,
    /// The onset's floor in pressure units (default 20); the offset's is half of it.
    pub min_rise: f64,
    /// Shorter contacts are taps, not grasps (default 0.3 s).
    pub min_duration_s: f64,
    /// The baseline's time constant while idle (default 2 s): slow enough to ignore a touch
    /// that is about to start, fast enough to follow a BioTac's drift.
    pub baseline_s: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            onset_sigma: 6.0,
            offset_sigma: 3.0,
            min_rise: 20.0,
            min_duration_s: 0.3,
            baseline_s: 2.0,
        }
    }
}

/// Why the spec's contact parameters cannot cut grasps; [`ContactError::field`] names the
/// spec field at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A parameter that is not finite, or below 0.
    #[error("{value} is not a finite number ≥ 0")]
    NotNonNegative { field: &'static str, value: f64 },
    #[error("the time constant must be > 0")]
    ZeroBaseline,
    #[error("{offset} is above the onset's {onset}: the offset must be the lower threshold")]
    OffsetAboveOnset { offset: f64, onset: f64 },
}

impl ContactError {
    /// The spec field at fault, e.g. `live.contact.offset_sigma`.
    pub fn field(&self) -> &'static str {
        match self {
            ContactError::NotNonNegative { field, .. } => field,
            ContactError::ZeroBaseline => "live.contact.baseline_s",
            ContactError::OffsetAboveOnset { .. } => "live.contact.offset_sigma",
        }
    }
}

impl ContactParams {
    /// Each parameter finite and of its sign, the offset below the onset.
    pub fn check(&self) -> Result<(), ContactError> {
        let fields = [
            ("live.contact.onset_sigma", self.onset_sigma),
            ("live.contact.offset_sigma", self.offset_sigma),
            ("live.contact.min_rise", self.min_rise),
            ("live.contact.min_duration_s", self.min_duration_s),
            ("live.contact.baseline_s", self.baseline_s),
        ];
        for (field, v) in fields {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ContactError::NotNonNegative { field, value: v });
            }
        }
        if self.baseline_s == 0.0 {
            return Err(ContactError::ZeroBaseline);
        }
        if self.offset_sigma > self.onset_sigma {
            return Err(ContactError::OffsetAboveOnset {
                offset: self.offset_sigma,
                onset: self.onset_sigma,
            });
        }
        Ok(())
    }
}
