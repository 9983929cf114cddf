//! k nearest neighbours under dynamic time warping: a grasp takes the majority class of
//! the k training grasps whose sequences it warps onto at the least cost (squared
//! Euclidean distance between steps, summed along the path, over the path's longest
//! possible length), the path kept within a Sakoe–Chiba band of `band` steps around the
//! diagonal (widened to the length difference, so that a path exists). The classic
//! time-series baseline; the model is its training grasps.

use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use super::classifier::{Classifier, ClassifierError, Fitted, Size, Training};
use super::{ClassifierId, Input, MethodId, MethodInfo, SizeKnob, Task};
use crate::features::FeatureSet;
use crate::jobs::Progress;

pub struct DtwKnn;

static INFO: MethodInfo = MethodInfo {
    id: MethodId::Classifier(ClassifierId::DtwKnn),
    key: "dtw-knn",
    aliases: &[],
    title: "DTW k-NN",
    task: Task::Recognition,
    input: Input::Sequences,
    score: "accuracy (10-fold)",
    size_knobs: &[
        SizeKnob {
            name: "k",
            meaning: "neighbours that vote",
        },
        SizeKnob {
            name: "band",
            meaning: "Sakoe–Chiba band: steps a path may stray from the diagonal",
        },
    ],
    robustness_default: true,
};

/// The warping cost of `a` onto `b` within `band` steps of the diagonal, per step of the
/// longer path (n + m), so that long and short grasps compare alike.
fn dtw(a: ArrayView2<f64>, b: ArrayView2<f64>, band: usize) -> f64 {
    let (n, m) = (a.nrows(), b.nrows());
    if n == 0 || m == 0 {
        return if n == m { 0.0 } else { f64::INFINITY };
    }
    let w = band.max(n.abs_diff(m));
    let mut prev = vec![f64::INFINITY; m + 1];
    let mut cur = vec![f64::INFINITY; m + 1];
    prev[0] = 0.0;
    for i in 1..=n {
        cur.fill(f64::INFINITY);
        let lo = i.saturating_sub(w).max(1);
        let hi = (i + w).min(m);
        let ai = a.row(i - 1);
        for j in lo..=hi {
            let d: f64 = ai
                .iter()
                .zip(b.row(j - 1))
                .map(|(x, y)| (x - y) * (x - y))
                .sum();
            cur[j] = d + prev[j - 1].min(prev[j]).min(cur[j - 1]);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[m] / (n + m) as f64
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Model {
    k: usize,
    band: usize,
    n_classes: usize,
    sequences: Vec<Array2<f64>>,
    labels: Vec<usize>,
}

impl Classifier for DtwKnn {
    fn info(&self) -> &'static MethodInfo {
        &INFO
    }

    fn features(&self) -> FeatureSet {
        FeatureSet::ALL
    }

    fn default_size(&self) -> Size {
        vec![1.0, 5.0]
    }

    fn sizes(&self) -> Vec<Size> {
        let mut out = Vec::new();
        for k in [1.0, 3.0, 5.0] {
            for band in [0.0, 5.0, 15.0] {
                out.push(vec![k, band]);
            }
        }
        out
    }

    fn check(&self, size: &[f64]) -> Result<(), ClassifierError> {
        ClassifierError::check_knobs(&INFO, size, &[(true, 1.0), (true, 0.0)])
    }

    fn fit(
        &self,
        size: &[f64],
        data: &Training,
        progress: &Progress,
    ) -> Result<Box<dyn Fitted>, ClassifierError> {
        self.check(size)?;
        data.check()?;
        progress.checkpoint()?;
        Ok(Box::new(Model {
            k: size[0] as usize,
            band: size[1] as usize,
            n_classes: data.n_classes,
            sequences: data.sequences.iter().map(|s| s.to_owned()).collect(),
            labels: data.labels.to_vec(),
        }))
    }

    fn load(&self, state: &serde_json::Value) -> Result<Box<dyn Fitted>, ClassifierError> {
        let m: Model = serde_json::from_value(state.clone())
            .map_err(ClassifierError::state_json)?;
        let dim = m.sequences.first().map_or(0, |s| s.ncols());
        let bad = |why: &str| Err(ClassifierError::State(why.into()));
        if m.k == 0 || m.sequences.is_empty() || m.sequences.len() != m.labels.len() {
            return bad("k ≥ 1 and one label per training grasp, at least one");
        }
        if m.labels.iter().any(|&l| l >= m.n_classes) {
            return bad("a label beyond the classes");
        }
        if (m.sequences.iter()).any(|s| s.ncols() != dim || s.iter().any(|v| !v.is_finite())) {
            return bad("training sequences need one width and finite values");
        }
        Ok(Box::new(m))
    }
}

impl Fitted for Model {
    fn predict(&self, sequence: ArrayView2<f64>) -> usize {
        let mut near: Vec<(f64, usize)> = (self.sequences.iter().zip(&self.labels))
            .map(|(s, &l)| (dtw(sequence, s.view(), self.band), l))
            .collect();
        let k = self.k.min(near.len());
        near.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
        near[..k].sort_by(|a, b| a.0.total_cmp(&b.0));
        // Votes per class; a tie goes to the class with the nearest neighbour.
        let mut votes = vec![0usize; self.n_classes];
        for &(_, l) in &near[..k] {
            votes[l] += 1;
        }
        let most = votes.iter().copied().max().unwrap_or(0);
        near[..k]
            .iter()
            .find(|&&(_, l)| votes[l] == most)
            .map_or(0, |&(_, l)| l)
    }

    fn state(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn dim(&self) -> usize {
        self.sequences.first().map_or(0, |s| s.ncols())
    }

    fn n_classes(&self) -> usize {
        self.n_classes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn warping_matches_a_shifted_sequence_that_lock_step_does_not() {
        // The same bump, one step later: DTW with a band of 1 aligns it exactly.
        let a = array![[0.0], [1.0], [0.0], [0.0]];
        let b = array![[0.0], [0.0], [1.0], [0.0]];
        assert!(dtw(a.view(), b.view(), 0) > 0.0);
        assert_eq!(dtw(a.view(), b.view(), 1), 0.0);
    }
}
