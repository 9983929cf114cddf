//! DU and GU: one clustering run at the setup's novelty threshold on the kept grasps,
//! scored by NMI (the runs of [`crate::experiments::clustering`]).

use super::*;

/// The unsupervised experts of one learner.
pub(super) struct Unsupervised(pub UnsupervisedLearner);

impl RecognitionMethod for Unsupervised {
    fn needs(&self) -> Needs {
        Needs {
            sequences: true,
            subset_sequences: true,
            table: false,
        }
    }

    /// The NMI of one run at the setup's threshold in repetition `rep`'s order.
    fn score(&self, r: &RecognitionRep) -> Result<f64, ExperimentError> {
        let rc = &r.params.recognition;
        let threshold = match self.0 {
            UnsupervisedLearner::Du => rc.du_threshold,
            UnsupervisedLearner::Gu => rc.gu_threshold,
        };
        let cp = ClusteringParams {
            learner: self.0,
            features: rc.features,
            thresholds: vec![threshold],
            reps: 1,
            seed: r.params.seed,
            label_set: rc.label_set.clone(),
            ds: rc.ds.clone(),
            gs: rc.gs.clone(),
            gu_aggregate: rc.gu_aggregate,
            gu_min_grasps: rc.gu_min_grasps,
            baseline_max_k: 0,
            // The rest as the clustering experiment's defaults.
            ..ClusteringParams::default()
        };
        // One threshold on a subset: as short as the other tasks, cancelled between them.
        Ok(one_run(
            &cp,
            &r.sub_seqs,
            &r.sub_labels,
            r.test_seqs.dim(),
            threshold,
            r.rep,
            None,
            &Progress::new(),
        )?
        .nmi)
    }
}
