//! DS and GS: capacity × tau of every expert, scored by the supervised protocol.

use super::method::{
    FrontierItem, FrontierMethod, FrontierOutput, FrontierPrep, MethodPoints, SweepKnob, each_rep,
    micros, reals, wholes, wrong_item,
};
use super::*;
use crate::experiments::feature_choice::{AUTO_FOLDS, choose_features};
use crate::experiments::recognition::{
    ExpertsScorer, RecognitionParams, RecognitionPrep, SupervisedLearner, prepare_recognition,
    recognition_repetition,
};

/// The supervised experts of one learner.
pub(super) struct Supervised(pub SupervisedLearner);

/// The protocol at the paper's size (items set capacity and tau) and its data.
struct Prep {
    base: RecognitionParams,
    data: RecognitionPrep,
}

impl Supervised {
    /// The protocol at the paper's size.
    fn protocol(&self, params: &FrontierParams) -> RecognitionParams {
        RecognitionParams {
            learner: self.0,
            features: params.features,
            reps: params.reps,
            seed: params.seed,
            early_fractions: Vec::new(),
            ..RecognitionParams::default()
        }
    }
}

fn sizes(params: &FrontierParams) -> Vec<(usize, usize)> {
    params
        .capacities
        .iter()
        .flat_map(|&c| params.taus.iter().map(move |&t| (c, t)))
        .collect()
}

/// The feature set `auto` stands for, scored by `learner`'s experts at the paper's size
/// (or the frontier's expert size): DU and GU are chosen for by DS's and GS's experts.
pub(super) fn choose_by_experts(
    learner: SupervisedLearner,
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<FeatureChoice, ExperimentError> {
    let defaults = RecognitionParams::default();
    let (mut ds, mut gs) = (defaults.ds, defaults.gs);
    for gp in [&mut ds.gp, &mut gs.gp] {
        gp.capacity = params.expert_capacity.unwrap_or(gp.capacity);
        gp.tau = params.expert_tau.unwrap_or(gp.tau);
    }
    let scorer = ExpertsScorer {
        learner,
        ds: &ds,
        gs: &gs,
    };
    choose_features(
        session,
        &scorer,
        "object",
        AUTO_FOLDS,
        params.seed,
        progress,
    )
}

impl FrontierMethod for Supervised {
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError> {
        if params.capacities.is_empty() || params.taus.is_empty() {
            return Err(ExperimentError::param(
                "capacities",
                "DS/GS need at least one capacity and one tau",
            ));
        }
        if params.capacities.contains(&0) || params.taus.contains(&0) {
            return Err(ExperimentError::param(
                "capacities",
                "capacity and tau must be ≥ 1",
            ));
        }
        Ok(())
    }

    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob> {
        vec![
            SweepKnob::new("capacities", "capacities", true, reals(&params.capacities)),
            SweepKnob::new("taus", "taus", true, reals(&params.taus)),
        ]
    }

    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]) {
        params.capacities = wholes(&lists[0]);
        params.taus = wholes(&lists[1]);
    }

    fn prepare(
        &self,
        session: &Session,
        params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError> {
        let base = self.protocol(params);
        let data = prepare_recognition(session, &base)?;
        Ok(FrontierPrep::new(Prep { base, data }))
    }

    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem> {
        each_rep(sizes(params), params.reps, |(capacity, tau), rep| {
            FrontierItem::Recognition { capacity, tau, rep }
        })
    }

    fn item(
        &self,
        session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        let (Some(prep), FrontierItem::Recognition { capacity, tau, rep }) =
            (prep.get::<Prep>(), *item)
        else {
            return Err(wrong_item(item, params));
        };
        let mut p = prep.base.clone();
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = capacity;
            gp.tau = tau;
        }
        let r = recognition_repetition(&p, session, &prep.data, rep, progress)?;
        Ok(FrontierOutput::Recognition {
            all: r.all,
            final_20: r.final_20,
            train_us: micros(r.train_seconds, r.train_steps),
            predict_us: micros(r.predict_seconds, r.predict_steps),
        })
    }

    /// One point per capacity × tau.
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints {
        let sizes = sizes(params);
        let base = self.protocol(params);
        let paper = (base.gs.gp.capacity, base.gs.gp.tau);
        let points = sizes
            .iter()
            .map(|&(capacity, tau)| {
                let (mut scores, mut train, mut predict) = (Vec::new(), Vec::new(), Vec::new());
                for (item, out) in &pairs {
                    if let (
                        FrontierItem::Recognition {
                            capacity: c,
                            tau: t,
                            ..
                        },
                        FrontierOutput::Recognition {
                            all,
                            final_20,
                            train_us,
                            predict_us,
                        },
                    ) = (item, out)
                        && (*c, *t) == (capacity, tau)
                    {
                        scores.push(match params.score {
                            RecognitionScore::All => *all,
                            RecognitionScore::Final20 => *final_20,
                        });
                        train.push(*train_us);
                        predict.push(*predict_us);
                    }
                }
                point(
                    format!("capacity {capacity} · τ {tau}"),
                    format!(
                        "{}, {} features: capacity {capacity}, tau {tau}",
                        params.method.title(),
                        params.features.name()
                    ),
                    vec![("capacity", capacity as f64), ("tau", tau as f64)],
                    &scores,
                    train,
                    predict,
                )
            })
            .collect();
        let score_name = match params.score {
            RecognitionScore::All => "accuracy (all)",
            RecognitionScore::Final20 => "accuracy (final 20 %)",
        };
        MethodPoints {
            points,
            paper_default: sizes.iter().position(|&s| s == paper),
            score_name: score_name.into(),
            unit: "step",
        }
    }

    fn choose_features(
        &self,
        session: &Session,
        params: &FrontierParams,
        progress: &Progress,
    ) -> Result<FeatureChoice, ExperimentError> {
        choose_by_experts(self.0, session, params, progress)
    }
}
