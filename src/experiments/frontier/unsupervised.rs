//! DU and GU: the novelty threshold, scored by NMI over seeded orders with the effective
//! clusters it leaves (the runs of [`crate::experiments::clustering`]).

use super::method::{
    FrontierItem, FrontierMethod, FrontierOutput, FrontierPrep, MethodPoints, SweepKnob, each_rep,
    wrong_item,
};
use super::supervised::choose_by_experts;
use super::*;
use crate::experiments::clustering::{
    ClusteringParams, ClusteringPrep, ClusteringRun, one_run, prepare_clustering,
};
use crate::experiments::recognition::SupervisedLearner;

/// The unsupervised experts of one learner.
pub(super) struct Unsupervised(pub UnsupervisedLearner);

/// The clustering run over the thresholds and its data.
struct Prep {
    base: ClusteringParams,
    data: ClusteringPrep,
}

impl Unsupervised {
    /// The clustering run over the thresholds, without the baselines.
    fn protocol(&self, params: &FrontierParams) -> ClusteringParams {
        let mut p = ClusteringParams {
            features: params.features,
            thresholds: params.thresholds.clone(),
            reps: params.reps,
            seed: params.seed,
            baseline_max_k: 0,
            ..ClusteringParams::for_learner(self.0)
        };
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = params.expert_capacity.unwrap_or(gp.capacity);
            gp.tau = params.expert_tau.unwrap_or(gp.tau);
        }
        p
    }
}

impl FrontierMethod for Unsupervised {
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError> {
        if params.thresholds.is_empty() {
            return Err(ExperimentError::param(
                "thresholds",
                "DU/GU need at least one threshold",
            ));
        }
        if let Some(t) = params.thresholds.iter().find(|t| !(0.0..=1.0).contains(*t)) {
            return Err(ExperimentError::param(
                "thresholds",
                format!("{t} is not in [0, 1]"),
            ));
        }
        if params.expert_capacity == Some(0) || params.expert_tau == Some(0) {
            return Err(ExperimentError::param(
                "expert_capacity",
                "the experts' capacity and tau must be ≥ 1",
            ));
        }
        Ok(())
    }

    /// The experts' capacity and tau are fixed for the run (the command line sets them).
    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob> {
        vec![SweepKnob::new(
            "thresholds",
            "novelty thresholds",
            false,
            params.thresholds.clone(),
        )]
    }

    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]) {
        params.thresholds = lists[0].clone();
    }

    fn prepare(
        &self,
        session: &Session,
        params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError> {
        let base = self.protocol(params);
        let data = prepare_clustering(session, &base)?;
        Ok(FrontierPrep::new(Prep { base, data }))
    }

    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem> {
        each_rep(
            params.thresholds.iter().copied(),
            params.reps,
            |threshold, rep| FrontierItem::Threshold { threshold, rep },
        )
    }

    fn item(
        &self,
        _session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        let (Some(Prep { base, data }), FrontierItem::Threshold { threshold, rep }) =
            (prep.get::<Prep>(), *item)
        else {
            return Err(wrong_item(item, params));
        };
        let run = one_run(
            base,
            &data.feats.sequences,
            &data.labels,
            data.feats.dim(),
            threshold,
            rep,
            data.pairs.as_ref(),
            progress,
        )?;
        // Per grasp, as the other clusterers: the observations of a grasp, each scored by
        // every expert.
        let seqs = &data.feats.sequences;
        let per_grasp =
            seqs.iter().map(|s| s.nrows()).sum::<usize>() as f64 / seqs.len().max(1) as f64;
        Ok(FrontierOutput::Threshold {
            train_us: run.learn_step_us * per_grasp,
            predict_us: run.assign_step_us * per_grasp,
            run,
        })
    }

    /// One point per threshold, NMI over the orders with the clusters it leaves.
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints {
        let c = self.protocol(params);
        let expert = match c.learner {
            UnsupervisedLearner::Du => (c.ds.gp.capacity, c.ds.gp.tau),
            UnsupervisedLearner::Gu => (c.gs.gp.capacity, c.gs.gp.tau),
        };
        let points = params
            .thresholds
            .iter()
            .map(|&threshold| {
                let runs: Vec<(&ClusteringRun, f64, f64)> = pairs
                    .iter()
                    .filter_map(|(_, o)| match o {
                        FrontierOutput::Threshold {
                            run,
                            train_us,
                            predict_us,
                        } if run.threshold == threshold => Some((run, *train_us, *predict_us)),
                        _ => None,
                    })
                    .collect();
                let effective = mean(runs.iter().map(|r| r.0.effective as f64));
                let created = mean(runs.iter().map(|r| r.0.clusters as f64));
                let nmi: Vec<f64> = runs.iter().map(|r| r.0.nmi).collect();
                point(
                    format!("θ {threshold}"),
                    format!(
                        "{}: threshold {threshold} (experts: capacity {}, tau {}); \
                         {effective:.1} effective clusters of {created:.1} created (means \
                         over the orders)",
                        self.label(params),
                        expert.0,
                        expert.1
                    ),
                    vec![
                        ("threshold", threshold),
                        ("effective", effective),
                        ("created", created),
                    ],
                    &nmi,
                    runs.iter().map(|r| r.1).collect(),
                    runs.iter().map(|r| r.2).collect(),
                )
            })
            .collect();
        MethodPoints {
            points,
            paper_default: None,
            score_name: "NMI".into(),
            unit: "grasp",
        }
    }

    /// Scored by the supervised experts of the same kind (DU by DS's, GU by GS's).
    fn choose_features(
        &self,
        session: &Session,
        params: &FrontierParams,
        progress: &Progress,
    ) -> Result<FeatureChoice, ExperimentError> {
        let learner = match self.0 {
            UnsupervisedLearner::Du => SupervisedLearner::Ds,
            UnsupervisedLearner::Gu => SupervisedLearner::Gs,
        };
        choose_by_experts(learner, session, params, progress)
    }
}
