//! How a recording the model did not train on is put on the model's scale.
//!
//! Tactile sensors drift between recording days: a BioTac's electrode baselines moved from a
//! mean of 2729 in the palm-down training file to 2861 in its test file, and classifiers
//! that read raw electrodes then fall to chance on the new day. A calibration decides which
//! per-taxel statistics (mean and standard deviation over grasps' key frames) stand for the
//! new recording:
//!
//! - `none`: the training session's, as if nothing had drifted;
//! - `session`: the new session's own, over all its grasps (no labels are read);
//! - `first:K`: the new session's first K grasps only, as a robot has them after K grasps.
//!
//! The default is `session`: drift of the baselines is the sensors' physics (temperature,
//! fluid and skin wear move every electrode's offset), it is known before any test label
//! is seen, and per-session statistics remove it whatever its size. On a pair of days that
//! happens not to drift the cost is a few points (docs/held-out.md shows all three).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::ModelError;

/// Written as on the command line: `none`, `session`, `first:K`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum Calibration {
    /// The training session's statistics.
    None,
    /// The new session's statistics over all its grasps.
    #[default]
    Session,
    /// The new session's statistics over its first `grasps` grasps.
    First { grasps: usize },
}

impl Calibration {
    /// The grasps whose statistics stand for a session of `grasps` grasps (None: the
    /// training session's).
    pub fn grasps(self, grasps: usize) -> Result<Option<std::ops::Range<usize>>, ModelError> {
        match self {
            Calibration::None => Ok(None),
            Calibration::Session => Ok(Some(0..grasps)),
            Calibration::First { grasps: k } if k == 0 || k > grasps => {
                Err(ModelError::Param(format!(
                    "calibration first:{k} needs 1 to {grasps} grasps (the session has {grasps})"
                )))
            }
            Calibration::First { grasps: k } => Ok(Some(0..k)),
        }
    }

    /// In words, for result cards and tables.
    pub fn describe(self) -> String {
        match self {
            Calibration::None => "none (the training session's taxel statistics)".into(),
            Calibration::Session => "session (each taxel z-scored over the new session)".into(),
            Calibration::First { grasps } => {
                format!(
                    "first {grasps} grasps (each taxel z-scored over the new session's first {grasps} grasps)"
                )
            }
        }
    }
}

impl fmt::Display for Calibration {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Calibration::None => f.write_str("none"),
            Calibration::Session => f.write_str("session"),
            Calibration::First { grasps } => write!(f, "first:{grasps}"),
        }
    }
}

impl From<Calibration> for String {
    fn from(c: Calibration) -> String {
        c.to_string()
    }
}

impl TryFrom<String> for Calibration {
    type Error = ModelError;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl FromStr for Calibration {
    type Err = ModelError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || {
            ModelError::Param(format!(
                "calibration {s:?}: expected none, session or first:K (K grasps)"
            ))
        };
        match s.trim() {
            "none" => Ok(Calibration::None),
            "session" => Ok(Calibration::Session),
            other => {
                let k = other.strip_prefix("first:").ok_or_else(bad)?;
                let grasps: usize = k.parse().map_err(|_| bad())?;
                if grasps == 0 {
                    return Err(bad());
                }
                Ok(Calibration::First { grasps })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints_each_calibration() {
        for (text, c) in [
            ("none", Calibration::None),
            ("session", Calibration::Session),
            ("first:25", Calibration::First { grasps: 25 }),
        ] {
            assert_eq!(text.parse::<Calibration>().unwrap(), c);
            assert_eq!(c.to_string(), text);
        }
        for bad in ["", "first:", "first:0", "first:x", "sessions"] {
            assert!(bad.parse::<Calibration>().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn first_k_needs_that_many_grasps() {
        assert_eq!(Calibration::None.grasps(10).unwrap(), None);
        assert_eq!(Calibration::Session.grasps(10).unwrap(), Some(0..10));
        assert_eq!(
            Calibration::First { grasps: 4 }.grasps(10).unwrap(),
            Some(0..4)
        );
        assert!(Calibration::First { grasps: 11 }.grasps(10).is_err());
    }
}
