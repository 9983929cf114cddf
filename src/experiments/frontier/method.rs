//! What a frontier needs from a method ([`FrontierMethod`]) and what passes between them:
//! the items, their outputs and what the items share. The items and outputs are one enum
//! each over every method: sweep shards and results files keep them, so their serialized
//! form is shared.

use std::any::Any;

use super::*;

/// A unit of a frontier's work. Its seeds follow from the run's seed and the item alone,
/// so any machine computes it alike.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierItem {
    /// DS/GS: repetition `rep` of the supervised protocol at one size.
    Recognition {
        capacity: usize,
        tau: usize,
        rep: usize,
    },
    /// Sparse coding: one dictionary, coded and cross-validated at every gamma and
    /// repetition.
    Dictionary { num_bases: usize, beta: f64 },
    /// DU/GU: one learning run at one threshold, in order `rep`.
    Threshold { threshold: f64, rep: usize },
    /// k-means / SOM: k centres / units, order `rep`.
    Clusters { k: usize, rep: usize },
    /// RBF SVM: repetition `rep` of the cross validation at (C, gamma).
    Svm { c: f64, gamma: f64, rep: usize },
    /// A registered method: repetition `rep` of its cross validation at its `size`-th size.
    Classifier { size: usize, rep: usize },
}

/// One (num_bases, beta, gamma) cell: its scores over the repetitions and its timings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseCell {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
    pub scores: Vec<f64>,
    /// Microseconds per grasp.
    pub train_us: f64,
    pub predict_us: f64,
}

/// What an item leaves. Times are microseconds per step (DS/GS) or per grasp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierOutput {
    Recognition {
        all: f64,
        final_20: f64,
        train_us: f64,
        predict_us: f64,
    },
    Dictionary {
        cells: Vec<SparseCell>,
    },
    Threshold {
        run: ClusteringRun,
        train_us: f64,
        predict_us: f64,
    },
    Clusters {
        nmi: f64,
        effective: usize,
        train_us: f64,
        predict_us: f64,
    },
    Svm {
        accuracy: f64,
        /// Support vectors summed over the one-vs-one machines: kernel evaluations per
        /// prediction.
        support_vectors: usize,
        train_us: f64,
        predict_us: f64,
    },
    Classifier {
        accuracy: f64,
        train_us: f64,
        predict_us: f64,
    },
}

/// One method (or family of methods sharing a protocol) as a frontier sweeps it.
pub(super) trait FrontierMethod: Sync {
    /// Its own knobs' values (the method and the repetitions are checked before).
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError>;
    /// What every item shares, from the session (parameters checked).
    fn prepare(
        &self,
        session: &Session,
        params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError>;
    /// Every size with its repetitions, in the order the points are assembled.
    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem>;
    /// One item: fit, score and time.
    fn item(
        &self,
        session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError>;
    /// The points from every item's output, in item order.
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints;
    /// The feature set `auto` stands for, by cross validation on the session.
    fn choose_features(
        &self,
        _session: &Session,
        params: &FrontierParams,
        _progress: &Progress,
    ) -> Result<FeatureChoice, ExperimentError> {
        Err(no_sequences(params.method))
    }
    /// The knobs it sweeps, in order, with the values `params` sweeps.
    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob>;
    /// Sweeps `lists` instead: one list per knob of [`Self::size_knobs`], in order (counted
    /// and checked for whole numbers before).
    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]);
    /// "DS, all features", "sparse coding + SVM".
    fn label(&self, params: &FrontierParams) -> String {
        plain_label(params)
    }
    /// A chart legend's name: "DS all", "SOM".
    fn short_label(&self, params: &FrontierParams) -> String {
        plain_short_label(params)
    }
}

/// A knob a frontier sweeps, as a form asks for its values.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepKnob {
    /// The short name messages about its values use, the form's and
    /// [`FrontierParams::set_size_knobs`]'s ("capacities", "C"); `validate` names the
    /// parameter's field instead (`svm_c`).
    pub name: &'static str,
    /// What a form's field says ("numbers of clusters k").
    pub label: String,
    /// Only whole numbers (counts such as capacities and k).
    pub whole: bool,
    pub values: Vec<f64>,
}

impl SweepKnob {
    pub(super) fn new(name: &'static str, label: &str, whole: bool, values: Vec<f64>) -> Self {
        SweepKnob {
            name,
            label: label.into(),
            whole,
            values,
        }
    }
}

/// Counts as a knob's values.
pub(super) fn reals(v: &[usize]) -> Vec<f64> {
    v.iter().map(|&v| v as f64).collect()
}

/// A whole knob's values as counts (checked whole and at most `MAX_WHOLE` before).
pub(super) fn wholes(v: &[f64]) -> Vec<usize> {
    v.iter().map(|&v| v as usize).collect()
}

/// A method's points, the papers' size among them, and what they are scored and timed by.
pub(super) struct MethodPoints {
    pub points: Vec<FrontierPoint>,
    pub paper_default: Option<usize>,
    pub score_name: String,
    /// What the times are per: "step" or "grasp".
    pub unit: &'static str,
}

/// What every item of a frontier shares: each method keeps its own kind.
pub struct FrontierPrep(Box<dyn Any + Send + Sync>);

impl FrontierPrep {
    pub(super) fn new<T: Any + Send + Sync>(prep: T) -> Self {
        FrontierPrep(Box::new(prep))
    }

    /// The method's own prep; None for another method's.
    pub(super) fn get<T: Any>(&self) -> Option<&T> {
        self.0.downcast_ref()
    }
}

pub(super) fn no_sequences(method: MethodId) -> ExperimentError {
    ExperimentError::param(
        "features",
        format!("auto: {} reads no feature sequences", method.key()),
    )
}

pub(super) fn plain_label(params: &FrontierParams) -> String {
    let m = params.method;
    if m.uses_features() {
        format!("{}, {} features", m.title(), params.features.name())
    } else {
        m.title().to_string()
    }
}

pub(super) fn plain_short_label(params: &FrontierParams) -> String {
    let m = params.method;
    if m.uses_features() {
        format!("{} {}", m.title(), params.features.name())
    } else {
        m.title().to_string()
    }
}

pub(super) fn wrong_item(item: &FrontierItem, params: &FrontierParams) -> ExperimentError {
    ExperimentError::param(
        "item",
        format!(
            "{item:?} is not an item of a {} frontier",
            params.method.title()
        ),
    )
}

/// One item per size and repetition, size-major (the order the items' seeds follow).
pub(super) fn each_rep<S: Copy>(
    sizes: impl IntoIterator<Item = S>,
    reps: usize,
    item: impl Fn(S, usize) -> FrontierItem,
) -> Vec<FrontierItem> {
    (sizes.into_iter())
        .flat_map(|size| (0..reps).map(move |rep| (size, rep)))
        .map(|(size, rep)| item(size, rep))
        .collect()
}

pub(super) fn micros(secs: f64, units: usize) -> f64 {
    1e6 * secs / units.max(1) as f64
}
