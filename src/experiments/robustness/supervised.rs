//! DS and GS: the second paper's supervised protocol, scored by the "final 20 %" accuracy.

use super::*;

/// The supervised experts of one learner.
pub(super) struct Supervised(pub SupervisedLearner);

impl RecognitionMethod for Supervised {
    fn needs(&self) -> Needs {
        Needs {
            sequences: true,
            ..Needs::default()
        }
    }

    /// Teach one grasp per class, then predict and learn the training part (the grasps
    /// `keep` leaves), then predict the test part.
    fn score(&self, r: &RecognitionRep) -> Result<f64, ExperimentError> {
        let (rc, prep) = (&r.params.recognition, r.prep);
        let mut learner = new_learner(self.0, prep.clean.dim(), prep.n_classes, &rc.ds, &rc.gs)?;
        for &g in &r.teach {
            learner.train_sequence(r.train_seqs.sequences[g].view(), prep.labels[g]);
        }
        let mut hits = 0usize;
        for (i, &g) in r.order.iter().enumerate() {
            let is_test = i >= r.n_train;
            if !is_test && !r.keep[i] {
                continue;
            }
            let seqs = if is_test { r.test_seqs } else { r.train_seqs };
            let seq = seqs.sequences[g].view();
            let dist = learner.predict_sequence(seq);
            if is_test {
                hits += usize::from(learner.decide(dist.view()) == prep.labels[g]);
            } else {
                learner.train_sequence(seq, prep.labels[g]);
            }
        }
        let n_test = r.order.len() - r.n_train;
        Ok(if n_test > 0 {
            hits as f64 / n_test as f64
        } else {
            0.0
        })
    }
}
