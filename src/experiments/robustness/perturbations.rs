//! The perturbations of the sweep: what each does, its scope and its strengths.

use super::*;
// The sweep's axes are declared beside the session perturbations they apply (figures
// are named by them too); what they mean for the experiment is here.
pub use crate::perturb::Perturbation;

/// Where a perturbation acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scope {
    /// Every grasp, training and test.
    All,
    /// Only the grasps a model is tested on, after learning on clean ones.
    Test,
    /// Which grasps a model learns from (the data are clean).
    Training,
}

impl Perturbation {
    /// The session perturbation behind it (None for the protocol ones).
    pub fn session_kind(self) -> Option<PerturbationKind> {
        Some(match self {
            Perturbation::Noise => PerturbationKind::Noise,
            Perturbation::DeadTaxels => PerturbationKind::DeadTaxels { stuck: Stuck::Zero },
            Perturbation::SaturatedTaxels => PerturbationKind::DeadTaxels { stuck: Stuck::Max },
            Perturbation::DeadSensor => PerturbationKind::DeadSensor { stuck: Stuck::Zero },
            Perturbation::Drift => PerturbationKind::Drift,
            Perturbation::Gain => PerturbationKind::Gain,
            Perturbation::Truncation => PerturbationKind::Truncation,
            Perturbation::MissingFrames => PerturbationKind::MissingFrames,
            _ => return None,
        })
    }

    pub fn scope(self) -> Scope {
        match self {
            Perturbation::Noise => Scope::All,
            Perturbation::Imbalance | Perturbation::FewExamples | Perturbation::NewObjects => {
                Scope::Training
            }
            _ => Scope::Test,
        }
    }

    /// The strength at which nothing changes (None where the clean protocol is not a point
    /// of the sweep's axis).
    pub fn neutral(self) -> Option<f64> {
        self.session_kind().map(PerturbationKind::neutral)
    }

    /// Axis title and unit of the strength.
    pub fn strength_title(self, family: Family) -> (&'static str, &'static str) {
        if let Some(k) = self.session_kind() {
            return k.strength_title();
        }
        match (self, family) {
            (Perturbation::Imbalance, Family::Stability) => {
                ("failures' share of the training set", "fraction")
            }
            (Perturbation::Imbalance, Family::Recognition) => {
                ("training grasps kept by the minority classes", "fraction")
            }
            (Perturbation::FewExamples, _) => ("training grasps per class", "count"),
            _ => ("share of objects never seen in training", "fraction"),
        }
    }

    /// The default sweep, from mild to severe.
    pub fn default_strengths(self, family: Family) -> Vec<f64> {
        match (self, family) {
            (Perturbation::Noise, _) => {
                vec![25.0, 50.0, 100.0, 200.0, 400.0, 700.0, 1000.0, 1500.0]
            }
            (Perturbation::DeadTaxels | Perturbation::SaturatedTaxels, _) => {
                vec![0.05, 0.1, 0.2, 0.3, 0.5, 0.75]
            }
            (Perturbation::DeadSensor, _) => vec![1.0, 2.0],
            (Perturbation::Drift, _) => vec![0.01, 0.02, 0.05, 0.1, 0.2, 0.3],
            (Perturbation::Gain, _) => vec![1.1, 1.25, 1.5, 2.0, 3.0],
            (Perturbation::Truncation, _) => vec![0.9, 0.8, 0.6, 0.4, 0.2, 0.1],
            (Perturbation::MissingFrames, _) => vec![0.1, 0.2, 0.4, 0.6, 0.8],
            (Perturbation::Imbalance, Family::Stability) => vec![0.4, 0.3, 0.2, 0.1, 0.05],
            (Perturbation::Imbalance, Family::Recognition) => vec![0.5, 0.25, 0.1, 0.05],
            (Perturbation::FewExamples, Family::Stability) => {
                vec![200.0, 100.0, 50.0, 20.0, 10.0, 5.0, 2.0]
            }
            (Perturbation::FewExamples, Family::Recognition) => {
                vec![10.0, 5.0, 3.0, 2.0, 1.0]
            }
            (Perturbation::NewObjects, _) => vec![0.1, 0.2, 0.3, 0.5, 0.7, 0.9],
        }
    }

    /// Check one strength of a protocol perturbation (session ones are checked by
    /// [`PerturbParams::validate`]).
    pub(super) fn check_protocol_strength(self, s: f64) -> Result<(), ExperimentError> {
        let bad = |why: &str| {
            Err(ExperimentError::param(
                "strengths",
                format!("{}: {why}, got {s}", self.key()),
            ))
        };
        match self {
            Perturbation::Imbalance if !(s > 0.0 && s <= 1.0) => bad("a share in (0, 1]"),
            Perturbation::FewExamples if !(s >= 1.0 && s.fract() == 0.0 && s.is_finite()) => {
                bad("a whole number of grasps ≥ 1")
            }
            Perturbation::NewObjects if !(s > 0.0 && s < 1.0) => bad("a share in (0, 1)"),
            _ => Ok(()),
        }
    }
}

impl FromStr for Perturbation {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Perturbation::ALL
            .into_iter()
            .find(|p| p.key() == s)
            .ok_or_else(|| {
                ExperimentError::param(
                    "perturbations",
                    format!(
                        "`{s}` is not one of {}",
                        Perturbation::ALL.map(|p| p.key()).join(", ")
                    ),
                )
            })
    }
}
