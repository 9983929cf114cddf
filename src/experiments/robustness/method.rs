//! What a robustness sweep needs from a method: the task kind it belongs to, and for a
//! recognition method what its repetition must prepare and its score on one repetition.
//! [`super::registry::robustness_method`] says which object answers for which method.

use super::*;

/// A method as a sweep runs it: on the task kind it belongs to.
#[derive(Clone, Copy)]
pub(super) enum RobustnessMethod {
    Stability(&'static dyn StabilityMethod),
    Recognition(&'static dyn RecognitionMethod),
}

impl RobustnessMethod {
    pub(super) fn family(self) -> Family {
        match self {
            RobustnessMethod::Stability(_) => Family::Stability,
            RobustnessMethod::Recognition(_) => Family::Recognition,
        }
    }
}

/// A grasp-stability method: one of the pipelines every stability repetition scores.
pub(super) trait StabilityMethod: Sync {
    /// Its weighted success rate on one repetition.
    fn score(&self, rep: &StabilityRep) -> f64;
}

/// What a recognition repetition prepares before any method scores: the perturbed
/// feature sequences, the kept grasps' sequences, the Table I features.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Needs {
    pub sequences: bool,
    pub subset_sequences: bool,
    pub table: bool,
}

impl Needs {
    fn or(self, other: Needs) -> Needs {
        Needs {
            sequences: self.sequences || other.sequences,
            subset_sequences: self.subset_sequences || other.subset_sequences,
            table: self.table || other.table,
        }
    }

    /// What the recognition methods of `methods` need between them (a stability method
    /// needs nothing here: the task refuses it when it comes to score it).
    pub(super) fn of(methods: &[MethodId]) -> Needs {
        (methods.iter().filter_map(|&m| recognition_method(m).ok()))
            .fold(Needs::default(), |acc, m| acc.or(m.needs()))
    }
}

/// An object-recognition method (accuracy or NMI).
pub(super) trait RecognitionMethod: Sync {
    fn needs(&self) -> Needs;
    /// Its score on one repetition.
    fn score(&self, rep: &RecognitionRep) -> Result<f64, ExperimentError>;
}

/// The recognition method of `id`, or why a recognition task cannot run it.
pub(super) fn recognition_method(
    id: MethodId,
) -> Result<&'static dyn RecognitionMethod, ExperimentError> {
    match robustness_method(id) {
        RobustnessMethod::Recognition(m) => Ok(m),
        RobustnessMethod::Stability(_) => Err(ExperimentError::param(
            "methods",
            format!("{} is a grasp-stability method", id.key()),
        )),
    }
}

/// The stability method of `id`, or why a stability task cannot run it.
pub(super) fn stability_method(
    id: MethodId,
) -> Result<&'static dyn StabilityMethod, ExperimentError> {
    match robustness_method(id) {
        RobustnessMethod::Stability(m) => Ok(m),
        RobustnessMethod::Recognition(_) => Err(ExperimentError::param(
            "methods",
            format!("{} is not a grasp-stability method", id.key()),
        )),
    }
}
