//! Online learners over OIESGP experts (DS, GS, DU, GU) and their novelty scores.
//!
//! A learner's whole state saves and loads with serde ([`Ds`], [`Gs`], [`Du`] and [`Gu`]
//! implement `Serialize` and `Deserialize`): a learner loaded from what another saved goes
//! on learning and predicting exactly as that one does, bit for bit. Deserialising is the
//! checked constructor: the parameters, every expert (see [`crate::gp`]) and the learner's
//! own state are checked against each other, and a state that disagrees is an error naming
//! the field (an expert's as `models[2]: invalid state `alpha`: …`, with serde_json's line
//! and column), so that no inconsistent learner can be obtained. Errors of the JSON types
//! themselves (a negative count, a string for a number) are serde's, with line and column.

pub mod ds;
pub mod du;
pub mod evt;
pub mod gs;
pub mod gu;
pub mod novelty;

use ndarray::{Array2, ArrayView2};

pub use ds::{Ds, DsParams};
pub use du::{Du, DuParams, du_novelty};
pub use gs::{Gs, GsParams};
pub use gu::{EvtDraws, Gu, GuAggregate, GuNoise, GuParams};
pub use novelty::{Assignment, NoveltyLearner, NoveltySteps, novelty_due};

use crate::gp::{GpError, Sogp, SogpParams, Window};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LearnerError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    /// A saved state that no learner could have reached (a damaged or crafted file).
    #[error("invalid state `{field}`: {reason}")]
    InvalidState { field: String, reason: String },
    #[error("{0}")]
    Gp(#[from] GpError),
}

impl LearnerError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> LearnerError {
        LearnerError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }

    pub(crate) fn state(field: impl Into<String>, reason: impl Into<String>) -> LearnerError {
        LearnerError::InvalidState {
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// The error as one of the state inside `prefix` (`models[2]` makes `alpha` into
    /// `models[2].alpha`).
    pub fn within(self, prefix: &str) -> LearnerError {
        let (field, reason) = match self {
            LearnerError::InvalidParameter { name, reason } => (name.to_string(), reason),
            LearnerError::InvalidState { field, reason } => (field, reason),
            LearnerError::Gp(GpError::InvalidParameter { name, reason }) => {
                (name.to_string(), reason)
            }
            LearnerError::Gp(GpError::InvalidState { field, reason }) => (field, reason),
        };
        LearnerError::state(format!("{prefix}.{field}"), reason)
    }
}

/// Checks, before a learner of `dim` inputs is built from `gp` to load a state, that its
/// experts (with `n_out` outputs) are within the limits of a loaded model.
fn check_loadable_size(dim: usize, n_out: usize, gp: &SogpParams) -> Result<(), LearnerError> {
    Sogp::check_loadable_size(dim, gp.tau, gp.capacity, n_out).map_err(|e| match e {
        GpError::InvalidState { field, reason } if field != "dim" => {
            LearnerError::state(format!("params.gp.{field}"), reason)
        }
        e => e.into(),
    })
}

/// Checks that loaded experts are those a learner of `dim` inputs builds from `gp` with
/// `n_out` outputs (their hyperparameters may have adapted since).
fn check_experts(
    models: &[Sogp],
    dim: usize,
    n_out: usize,
    gp: &SogpParams,
) -> Result<(), LearnerError> {
    for (c, m) in models.iter().enumerate() {
        let field = |name: &str| format!("models[{c}].{name}");
        let differs = |name: &str, has: String, built: String| {
            Err(LearnerError::state(
                field(name),
                format!("{has}, the learner's experts have {built}"),
            ))
        };
        if m.kernel().dim() != dim {
            return differs("dim", m.kernel().dim().to_string(), dim.to_string());
        }
        if m.n_out() != n_out {
            return differs("n_out", m.n_out().to_string(), n_out.to_string());
        }
        if m.kernel().tau() != gp.tau {
            return differs("tau", m.kernel().tau().to_string(), gp.tau.to_string());
        }
        if m.capacity() != gp.capacity {
            return differs(
                "capacity",
                m.capacity().to_string(),
                gp.capacity.to_string(),
            );
        }
        if m.likelihood() != gp.likelihood {
            return differs(
                "likelihood",
                format!("{:?}", m.likelihood()),
                format!("{:?}", gp.likelihood),
            );
        }
        if m.novelty_eps().to_bits() != gp.novelty_eps.to_bits() {
            return differs(
                "novelty_eps",
                m.novelty_eps().to_string(),
                gp.novelty_eps.to_string(),
            );
        }
        if m.adaptation_params() != gp.adaptation.as_ref() {
            return differs(
                "adaptation",
                format!("{:?}", m.adaptation_params()),
                format!("{:?}", gp.adaptation),
            );
        }
    }
    Ok(())
}

/// Checks a saved window of a learner of `dim` inputs over `tau` lags.
fn check_window(window: &Window, dim: usize, tau: usize) -> Result<(), LearnerError> {
    if window.dim() != dim || window.as_slice().len() != dim * tau {
        return Err(LearnerError::state(
            "window",
            format!(
                "{} lags of {} inputs, the learner has {tau} of {dim}",
                window.as_slice().len() / window.dim(),
                window.dim()
            ),
        ));
    }
    Ok(())
}

/// The experts of a saved learner, an expert's error naming its index.
fn deserialize_models<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<Sogp>, D::Error> {
    struct Models;
    impl<'de> serde::de::Visitor<'de> for Models {
        type Value = Vec<Sogp>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an array of experts")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(
            self,
            mut seq: A,
        ) -> Result<Vec<Sogp>, A::Error> {
            let mut models = Vec::new();
            loop {
                // (serde_json takes the position back out of the end of the message.)
                match seq.next_element::<Sogp>() {
                    Ok(Some(m)) => models.push(m),
                    Ok(None) => return Ok(models),
                    Err(e) => {
                        let i = models.len();
                        return Err(serde::de::Error::custom(format!("models[{i}]: {e}")));
                    }
                }
            }
        }
    }
    d.deserialize_seq(Models)
}

/// The window of a saved learner, its errors named within `window`.
fn deserialize_window<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Window, D::Error> {
    use serde::Deserialize;
    Window::deserialize(d).map_err(|e| serde::de::Error::custom(format!("window: {e}")))
}

/// Checks a per-class vector of a saved learner (one value per expert).
fn check_per_class(name: &str, len: usize, classes: usize) -> Result<(), LearnerError> {
    if len != classes {
        return Err(LearnerError::state(
            name,
            format!("{len} values for {classes} classes"),
        ));
    }
    Ok(())
}

/// One expert per class over sequences of feature vectors (rows of a T × D matrix).
pub trait SequenceClassifier: Send {
    fn dim(&self) -> usize;
    fn n_classes(&self) -> usize;
    /// Add an (untrained) expert; returns its class index.
    fn add_class(&mut self) -> Result<usize, LearnerError>;
    fn models(&self) -> &[Sogp];
    /// The class distribution after every step of the sequence (T × C).
    fn predict_sequence(&mut self, seq: ArrayView2<f64>) -> Array2<f64>;
    fn train_sequence(&mut self, seq: ArrayView2<f64>, class: usize);
    /// The sequence methods one observation at a time (what a step costs): a new sequence
    /// starts, ...
    fn start_sequence(&mut self);
    /// ... the class distribution after observing `o` (as a row of `predict_sequence`)
    /// into `dist`, ...
    fn predict_step(&mut self, o: &[f64], dist: &mut [f64]);
    /// ... or a training step on `o` of class `class` (as in `train_sequence`).
    fn train_step(&mut self, o: &[f64], class: usize);
    /// The class of a sequence (or of its first steps) from its per-step distributions.
    fn decide(&self, dist: ArrayView2<f64>) -> usize;
}

/// The steps of a standard-layout sequence as one slice (empty when its width is not
/// `dim`, so that a mismatched sequence is never read out of step).
fn steps<'a>(seq: &'a ndarray::CowArray<'_, f64, ndarray::Ix2>, dim: usize) -> &'a [f64] {
    if seq.ncols() != dim {
        return &[];
    }
    seq.as_slice().unwrap_or_default()
}

fn argmax(v: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, x) in v.enumerate() {
        if x > best.1 {
            best = (i, x);
        }
    }
    best.0
}

/// Argmax of the per-step distributions averaged over the steps.
pub fn argmax_of_mean(dist: ArrayView2<f64>) -> usize {
    argmax(dist.columns().into_iter().map(|c| c.sum()))
}

/// Argmax of the last step's distribution.
pub fn argmax_of_last(dist: ArrayView2<f64>) -> usize {
    match dist.nrows() {
        0 => 0,
        t => argmax(dist.row(t - 1).iter().copied()),
    }
}

/// Lengthscales of every expert (class × input dimension).
pub fn lengthscales(learner: &dyn SequenceClassifier) -> Array2<f64> {
    let models = learner.models();
    let d = learner.dim();
    Array2::from_shape_fn((models.len(), d), |(c, j)| {
        models[c].kernel_params().lengthscales[j]
    })
}

/// Seeded synthetic grasps and checks shared by the learners' save-and-load tests.
#[cfg(test)]
pub(crate) mod testing {
    use ndarray::{Array2, Axis, concatenate, s};
    use serde::Serialize;
    use serde::de::DeserializeOwned;

    use crate::gp::SngdParams;
    use crate::rng::Rng;

    /// `n` grasps of 8 to 14 steps of `dim` features, each of one of `kinds` objects (in
    /// turn): object k ramps from its own level, with noise of sd 0.05.
    pub fn grasps(seed: u64, n: usize, kinds: usize, dim: usize) -> Vec<(usize, Array2<f64>)> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|g| {
                let k = g % kinds;
                let len = 8 + rng.below(7);
                let grasp = Array2::from_shape_fn((len, dim), |(t, d)| {
                    0.2 + 0.25 * k as f64 * ((d + k) % 3) as f64 / 2.0
                        + 0.03 * t as f64
                        + 0.05 * rng.normal()
                });
                (k, grasp)
            })
            .collect()
    }

    /// Probes of the step-by-step tests: grasps of five objects (three learned), and grasps
    /// that turn from one learned object into another halfway.
    pub fn probes() -> Vec<Array2<f64>> {
        let mut out: Vec<Array2<f64>> = grasps(2, 10, 5, 3).into_iter().map(|g| g.1).collect();
        let learned = grasps(3, 6, 3, 3);
        for pair in learned.windows(2) {
            let (a, b) = (&pair[0].1, &pair[1].1);
            let half = a.nrows() / 2;
            out.push(concatenate![Axis(0), a.slice(s![..half, ..]), b.view()]);
        }
        out
    }

    /// Adaptation that starts early and steps often, so that short runs adapt many times.
    pub fn quick_adaptation() -> SngdParams {
        SngdParams {
            window: 5,
            start_after: 20,
            stop_count: 1000,
            ..SngdParams::default()
        }
    }

    /// The bits of every value, for comparisons that tell −0 from 0.
    pub fn bits<'a>(values: impl IntoIterator<Item = &'a f64>) -> Vec<u64> {
        values.into_iter().map(|v| v.to_bits()).collect()
    }

    /// `learner` saved as JSON and loaded; the loaded one saves to the same JSON.
    pub fn round_trip<T: Serialize + DeserializeOwned>(learner: &T) -> T {
        let json = serde_json::to_string(learner).unwrap();
        let loaded: T = serde_json::from_str(&json).unwrap();
        assert_eq!(serde_json::to_string(&loaded).unwrap(), json);
        loaded
    }

    /// The error of loading `learner`'s JSON after `edit`: it must name `field`.
    pub fn load_error<T: Serialize + DeserializeOwned>(
        learner: &T,
        field: &str,
        edit: impl FnOnce(&mut serde_json::Value),
    ) -> String {
        let mut value = serde_json::to_value(learner).unwrap();
        edit(&mut value);
        let json = serde_json::to_string(&value).unwrap();
        match serde_json::from_str::<T>(&json) {
            Ok(_) => panic!("a state with a bad `{field}` loaded"),
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains(field), "`{field}` not named in: {e}");
                e
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use ndarray::array;

    use super::*;

    /// A tie goes to the first class, so that a decision does not depend on how many
    /// classes tie after it (an untrained learner's uniform distribution decides class 0).
    #[test]
    fn a_tie_goes_to_the_first_class() {
        let uniform = array![[0.25, 0.25, 0.25, 0.25], [0.25, 0.25, 0.25, 0.25]];
        assert_eq!(argmax_of_mean(uniform.view()), 0);
        assert_eq!(argmax_of_last(uniform.view()), 0);
        let tied = array![[0.1, 0.45, 0.45]];
        assert_eq!(argmax_of_mean(tied.view()), 1);
        assert_eq!(argmax_of_last(tied.view()), 1);
    }
}
