//! The temporal-feature SVM: each grasp's sequence summarised per feature by its mean, its
//! standard deviation, its change from first to last step and its change over the first
//! half of contact; the summaries z-scored on the training grasps; one linear SVM per class
//! against the rest (`crate::svm`), the class of the largest decision value. A plain,
//! strong baseline for recognition and slip tasks.

use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use super::classifier::{Classifier, ClassifierError, Fitted, Size, Training};
use super::{ClassifierId, Input, MethodId, MethodInfo, SizeKnob, Task};
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::svm::{LinearSvm, LinearSvmParams};

pub struct TemporalSvm;

static INFO: MethodInfo = MethodInfo {
    id: MethodId::Classifier(ClassifierId::TemporalSvm),
    key: "temporal-svm",
    aliases: &[],
    title: "temporal-feature SVM",
    task: Task::Recognition,
    input: Input::Sequences,
    score: "accuracy (10-fold)",
    size_knobs: &[SizeKnob {
        name: "c",
        meaning: "box constraint of each one-vs-rest machine",
    }],
    robustness_default: true,
};

/// Summaries per feature: mean, sd, last − first, change over the first half.
const STATS: usize = 4;

/// The summaries of one sequence (steps × features), `STATS` per feature.
fn summarise(seq: ArrayView2<f64>) -> Vec<f64> {
    let t = seq.nrows();
    let mut out = Vec::with_capacity(STATS * seq.ncols());
    for col in seq.columns() {
        if t == 0 {
            out.extend([0.0; STATS]);
            continue;
        }
        let mean = col.sum() / t as f64;
        let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / t as f64;
        let half = col[t / 2] - col[0];
        out.extend([mean, var.sqrt(), col[t - 1] - col[0], half]);
    }
    out
}

/// One machine per class; None for a class without training grasps (it is never chosen).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Model {
    dim: usize,
    machines: Vec<Option<LinearSvm>>,
    /// The most frequent training class: the answer when no machine could be trained.
    majority: usize,
}

impl Classifier for TemporalSvm {
    fn info(&self) -> &'static MethodInfo {
        &INFO
    }

    fn features(&self) -> FeatureSet {
        FeatureSet::RAW
    }

    fn default_size(&self) -> Size {
        vec![1.0]
    }

    fn sizes(&self) -> Vec<Size> {
        [0.01, 0.1, 1.0, 10.0, 100.0].map(|c| vec![c]).to_vec()
    }

    fn check(&self, size: &[f64]) -> Result<(), ClassifierError> {
        ClassifierError::check_knobs(&INFO, size, &[(false, f64::MIN_POSITIVE)])
    }

    fn fit(
        &self,
        size: &[f64],
        data: &Training,
        progress: &Progress,
    ) -> Result<Box<dyn Fitted>, ClassifierError> {
        self.check(size)?;
        let dim = data.check()?;
        let rows: Vec<Vec<f64>> = data.sequences.iter().map(|s| summarise(*s)).collect();
        let x = Array2::from_shape_vec((rows.len(), STATS * dim), rows.concat())
?;
        let params = LinearSvmParams {
            c: size[0],
            seed: data.seed,
            ..LinearSvmParams::default()
        };
        let mut machines = Vec::with_capacity(data.n_classes);
        for class in 0..data.n_classes {
            progress.checkpoint()?;
            let y: Vec<bool> = data.labels.iter().map(|&l| l == class).collect();
            // A class with no grasps, or the only class, has no "rest" to learn against.
            let machine = if y.iter().any(|&b| b) && y.iter().any(|&b| !b) {
                Some(params.fit(x.view(), &y)?)
            } else {
                None
            };
            machines.push(machine);
        }
        let mut counts = vec![0usize; data.n_classes];
        for &l in data.labels {
            counts[l] += 1;
        }
        let majority = (0..data.n_classes).max_by_key(|&c| counts[c]).unwrap_or(0);
        Ok(Box::new(Model {
            dim,
            machines,
            majority,
        }))
    }

    fn load(&self, state: &serde_json::Value) -> Result<Box<dyn Fitted>, ClassifierError> {
        let m: Model = serde_json::from_value(state.clone())
            .map_err(ClassifierError::state_json)?;
        if m.majority >= m.machines.len() {
            return Err(ClassifierError::State(format!(
                "majority class {} of {} classes",
                m.majority,
                m.machines.len()
            )));
        }
        for svm in m.machines.iter().flatten() {
            if svm.weights.len() != STATS * m.dim
                || !svm.intercept.is_finite()
                || svm.weights.iter().any(|w| !w.is_finite())
            {
                return Err(ClassifierError::State(format!(
                    "a machine needs {} finite weights and a finite intercept",
                    STATS * m.dim
                )));
            }
        }
        Ok(Box::new(m))
    }
}

impl Fitted for Model {
    fn predict(&self, sequence: ArrayView2<f64>) -> usize {
        let x = ndarray::Array1::from(summarise(sequence));
        let best = (self.machines.iter().enumerate())
            .filter_map(|(c, m)| m.as_ref().map(|m| (c, m.decision(x.view()))))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        best.map_or(self.majority, |(c, _)| c)
    }

    fn state(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn dim(&self) -> usize {
        self.dim
    }

    fn n_classes(&self) -> usize {
        self.machines.len()
    }
}
