//! The learning step of the unsupervised learners (DU, GU), split at its one decision: a
//! grasp is assessed against the clusters (the winner and its novelty), then trained into
//! the winner or into a new cluster when the novelty exceeds the threshold.
//!
//! The threshold enters only at that decision. Learners that differ only in their
//! threshold therefore compute the same, bit for bit, until a grasp's novelty falls between
//! their thresholds: a sweep over thresholds can learn them as one and fork a copy there
//! (`experiments::clustering::forked`).

use ndarray::ArrayView2;
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

    /// Assign one grasp (opening a cluster if it is novel) and train on it.
    fn learn(&mut self, seq: ArrayView2<f64>) -> Result<Assignment, LearnerError> {
        let a = self.assess(seq);
        let create = a
            .as_ref()
            .is_none_or(|a| Self::novelty(a) > self.threshold());
        self.commit(seq, a, create)
    }
}
