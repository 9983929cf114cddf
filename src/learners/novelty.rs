//! The learning step of the unsupervised learners (DU, GU), split at its one decision: a
//! grasp is assessed against the clusters (the winner and its novelty), then trained into
//! the winner or into a new cluster when the novelty exceeds the threshold.
//!
//! The threshold enters only at that decision. Learners that differ only in their
//! threshold therefore compute the same, bit for bit, until a grasp's novelty falls between
//! their thresholds: a sweep over thresholds can learn them as one and fork a copy there
//! (`experiments::clustering::forked`).

use ndarray::{ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use super::LearnerError;

/// What learning one grasp did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Assignment {
    pub cluster: usize,
    pub novelty: f64,
    pub created: bool,
}

/// A learner that opens a cluster when a grasp's novelty exceeds its threshold.
pub trait NoveltyLearner: Clone {
    /// What [`NoveltyLearner::assess`] found, and training into its winner reuses.
    type Assessment: Clone;
    /// What follows a grasp step by step ([`NoveltyLearner::steps`]).
    type Steps: NoveltySteps;

    fn threshold(&self) -> f64;
    fn n_clusters(&self) -> usize;
    /// The winner and the novelty of `seq` under the clusters learned so far; None before
    /// the first cluster (the first grasp always opens one).
    fn assess(&mut self, seq: ArrayView2<f64>) -> Option<Self::Assessment>;
    fn novelty(a: &Self::Assessment) -> f64;
    /// Train `seq` into a new cluster (`create`) or into the winner of `a`, the assessment
    /// this learner just made of it.
    fn commit(
        &mut self,
        seq: ArrayView2<f64>,
        a: Option<Self::Assessment>,
        create: bool,
    ) -> Result<Assignment, LearnerError>;
    /// The cluster of each grasp under the learned models (no training).
    fn assign_all(&mut self, seqs: &[ArrayView2<f64>]) -> Vec<usize>;

    /// A grasp that starts now, followed step by step on a copy of the learned experts
    /// (the learner does not change); None before the first cluster.
    fn steps(&self) -> Option<Self::Steps>;

    /// The winner and the novelty of every prefix of `seq`: entry t is what
    /// [`NoveltyLearner::assess`] of the first t + 1 steps gives, bit for bit, so the last
    /// is the whole grasp's. Empty before the first cluster, or for a sequence whose width
    /// is not the learner's.
    fn assess_steps(&self, seq: ArrayView2<f64>) -> Vec<(usize, f64)> {
        let Some(mut steps) = self.steps() else {
            return Vec::new();
        };
        if seq.ncols() != steps.dim() {
            return Vec::new();
        }
        let mut row = vec![0.0; seq.ncols()];
        seq.axis_iter(Axis(0))
            .map(|o| {
                row.iter_mut().zip(o).for_each(|(r, x)| *r = *x);
                let winner = steps.push(&row);
                (winner, steps.novelty())
            })
            .collect()
    }

    /// Assign one grasp (opening a cluster if it is novel) and train on it.
    fn learn(&mut self, seq: ArrayView2<f64>) -> Result<Assignment, LearnerError> {
        let a = self.assess(seq);
        let create = a
            .as_ref()
            .is_none_or(|a| Self::novelty(a) > self.threshold());
        self.commit(seq, a, create)
    }
}

/// A grasp followed step by step while it goes on (the live view's "model at work"): after
/// each step, the winner and the novelty of the grasp so far, equal bit for bit to
/// [`NoveltyLearner::assess`] of that prefix. A step costs one prediction of every expert:
/// running sums per cluster stand for the prefix, which is never assessed again.
pub trait NoveltySteps {
    /// The width of a step (the learner's input dimension).
    fn dim(&self) -> usize;
    /// The grasp's next step (`dim` values); the winner of the steps so far.
    ///
    /// # Panics
    /// If `o` is not `dim` values long.
    fn push(&mut self, o: &[f64]) -> usize;
    /// The winner of the steps so far (what the last [`NoveltySteps::push`] gave; 0 before).
    fn winner(&self) -> usize;
    /// The novelty of the steps so far (under the winner [`NoveltySteps::push`] gave).
    /// O(1), but see [`NoveltySteps::novelty_costly`].
    fn novelty(&mut self) -> f64;
    /// Whether [`NoveltySteps::novelty`] costs more than O(1) now: GU's joint novelty
    /// needs the extreme-value parameters of n = D·t dimensions, whose root-finding costs
    /// O(D·t) the first time each size is met. A live view that cannot afford that at
    /// every step asks at geometrically spaced steps ([`novelty_due`]).
    fn novelty_costly(&self) -> bool {
        false
    }
    /// Steps taken.
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Whether a follower that cannot afford a costly novelty at every step asks for it after
/// step `t` (from 1): at t = 1 … 10, 12, 14, 16, 19, 22, 26, … (each about 1.2 times the
/// last), so that costs O(t) each add up to O(T) over a grasp of T steps.
pub fn novelty_due(t: usize) -> bool {
    let mut k = 1;
    while k < t {
        k = (k + 1).max(k + k / 5);
    }
    k == t
}

#[cfg(test)]
mod tests {
    use super::novelty_due;

    /// The steps a costly novelty is asked at: every step up to 6, then about 1.2 times
    /// the last, so a grasp of a million steps asks about 70 times.
    #[test]
    fn a_costly_novelty_is_due_at_geometrically_spaced_steps() {
        let due: Vec<usize> = (1..=40).filter(|&t| novelty_due(t)).collect();
        assert_eq!(
            due,
            [
                1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 19, 22, 26, 31, 37
            ]
        );
        let many = (1..=1_000_000).filter(|&t| novelty_due(t)).count();
        assert!(many < 90, "{many}");
    }
}
