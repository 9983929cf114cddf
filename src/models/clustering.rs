//! The unsupervised OIESGP experts (DU, GU) as models that leave their session: grasps are
//! learned one at a time in a seeded random order, a novel grasp (novelty above the
//! threshold) opening a new cluster; the model keeps every expert's state, so that a new
//! session is clustered by the experts as they are (`evaluate`, `predict`) or learned
//! further (`fit du|gu --from`), where its novel objects open clusters of their own.
//! Sequences are read as for DS and GS (`super::recognition`).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::inputs::SequenceInputs;
use super::{Calibration, Model, ModelError, ModelFile, Provenance, SelectionScore, SessionRef};
use crate::catalogue::MethodId;
use crate::experiments::clustering::{
    ClusteringParams, ClusteringResult, UnsupervisedLearner, choose_auto_features,
};
use crate::experiments::feature_choice::FeatureChoice;
use crate::experiments::result::SizeReason;
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::learners::{Du, DuParams, Gu, GuParams, NoveltyLearner};
use crate::rng::Rng;
use crate::session::Session;

/// The experts of an unsupervised learner with their whole state.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "learner", content = "state", rename_all = "snake_case")]
pub enum Clusterer {
    Du(Du),
    Gu(Gu),
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ClusterModel {
    pub clusterer: Clusterer,
    #[serde(flatten)]
    pub inputs: SequenceInputs,
    /// The label set clusters are scored against (never read while learning).
    pub label_set: String,
    pub threshold: f64,
    /// Seed of the learning order.
    pub seed: u64,
    pub grasps_taught: usize,
}

impl PartialEq for ClusterModel {
    /// Equal when their saved states are: the learners hold caches that rebuild on load.
    fn eq(&self, other: &Self) -> bool {
        serde_json::to_string(self).ok() == serde_json::to_string(other).ok()
    }
}

/// How an unsupervised model is fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterFitOptions {
    pub method: MethodId,
    pub features: FeatureSet,
    pub label_set: String,
    pub threshold: f64,
    pub seed: u64,
    /// The experts' and the novelty's settings (its `threshold` is replaced).
    pub params: ClusteringParams,
}

impl ClusterModel {
    pub fn method(&self) -> MethodId {
        match self.clusterer {
            Clusterer::Du(_) => MethodId::Du,
            Clusterer::Gu(_) => MethodId::Gu,
        }
    }

    pub fn clusters(&self) -> usize {
        match &self.clusterer {
            Clusterer::Du(l) => l.n_clusters(),
            Clusterer::Gu(l) => l.n_clusters(),
        }
    }

    fn dim(&self) -> usize {
        match &self.clusterer {
            Clusterer::Du(l) => crate::learners::SequenceClassifier::dim(l.learner()),
            Clusterer::Gu(l) => crate::learners::SequenceClassifier::dim(l.learner()),
        }
    }

    /// The cluster of every grasp of `session` (the experts are not changed).
    pub fn assign(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<usize>, ModelError> {
        let feats = self.inputs.read(session, Some(calibration))?;
        let mut c = self.clusterer.clone();
        Ok(feats
            .sequences
            .iter()
            .map(|seq| match &mut c {
                Clusterer::Du(l) => l.assign(seq.view()),
                Clusterer::Gu(l) => l.assign(seq.view()),
            })
            .collect())
    }

    /// The novelty of every grasp of `session` after each of its steps: the novelty of the
    /// grasp so far against the clusters learned (the experts are not changed), what
    /// assessing that prefix gives, bit for bit ([`NoveltyLearner::assess_steps`]). Empty
    /// for a model without clusters yet.
    pub fn novelty_steps(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<Vec<f64>>, ModelError> {
        let feats = self.inputs.read(session, Some(calibration))?;
        Ok(feats
            .sequences
            .iter()
            .map(|seq| {
                let steps = match &self.clusterer {
                    Clusterer::Du(l) => l.assess_steps(seq.view()),
                    Clusterer::Gu(l) => l.assess_steps(seq.view()),
                };
                steps.into_iter().map(|(_, n)| n).collect()
            })
            .collect())
    }

    /// Learn every grasp of `session` in a seeded random order, on the model's range.
    fn learn(&mut self, session: &Session) -> Result<(), ModelError> {
        let feats = self.inputs.read(session, None)?;
        let order =
            Rng::stream(self.seed, self.grasps_taught as u64).permutation(session.grasps.len());
        for g in order {
            let seq = feats.sequences[g].view();
            match &mut self.clusterer {
                Clusterer::Du(l) => l.learn(seq)?,
                Clusterer::Gu(l) => l.learn(seq)?,
            };
        }
        self.grasps_taught += session.grasps.len();
        Ok(())
    }

    pub fn validate(&self) -> Result<(), ModelError> {
        self.inputs.validate(self.dim())
    }
}

/// Fit DU or GU on every grasp of `session`.
pub fn fit_clusters(
    session: &Session,
    opts: &ClusterFitOptions,
) -> Result<(ClusterModel, f64), ModelError> {
    let t0 = Instant::now();
    let inputs = SequenceInputs::fit(session, opts.features)?;
    let dim = inputs.feature_names.len();
    let p = &opts.params;
    let clusterer = match opts.method {
        MethodId::Du => Clusterer::Du(Du::new(
            dim,
            &DuParams {
                ds: p.ds.clone(),
                threshold: opts.threshold,
                min_grasps: p.du_min_grasps,
            },
        )?),
        MethodId::Gu => Clusterer::Gu(Gu::new(
            dim,
            &GuParams {
                gs: p.gs.clone(),
                threshold: opts.threshold,
                aggregate: p.gu_aggregate,
                draws: p.gu_draws,
                noise: p.gu_noise,
                noise_floor: p.gu_noise_floor,
                min_grasps: p.gu_min_grasps,
            },
        )?),
        other @ (MethodId::SparseSvm
        | MethodId::RawSvm
        | MethodId::Ds
        | MethodId::Gs
        | MethodId::KMeans
        | MethodId::Som
        | MethodId::RbfSvm
        | MethodId::Classifier(_)) => {
            return Err(ModelError::Param(format!(
                "{} is not an online clustering method (du, gu)",
                other.key()
            )));
        }
    };
    let mut model = ClusterModel {
        clusterer,
        inputs,
        label_set: opts.label_set.clone(),
        threshold: opts.threshold,
        seed: opts.seed,
        grasps_taught: 0,
    };
    model.learn(session)?;
    Ok((model, t0.elapsed().as_secs_f64()))
}

/// `opts` with `auto` features replaced by the family chosen by cross validation of the
/// experts the learner is built from (`experiments::clustering::choose_auto_features`),
/// and that choice; or as they are.
pub fn choose_cluster_features(
    session: &Session,
    opts: &ClusterFitOptions,
    progress: &Progress,
) -> Result<(ClusterFitOptions, Option<FeatureChoice>), ModelError> {
    let learner = UnsupervisedLearner::of(opts.method)
        .ok_or_else(|| ModelError::Param(format!("{} is not du or gu", opts.method.key())))?;
    let params = ClusteringParams {
        learner,
        features: opts.features,
        label_set: opts.label_set.clone(),
        seed: opts.seed,
        ..opts.params.clone()
    };
    let (params, choice) = choose_auto_features(session, &params, progress)?;
    let opts = ClusterFitOptions {
        features: params.features,
        ..opts.clone()
    };
    Ok((opts, choice))
}

/// The model a `clustering` run leaves: DU or GU learned on every grasp of `session` at the
/// threshold the run chose without labels (None when the run chose none), selected by the
/// agreement of its random orders.
pub fn cluster_file_of_run(
    session: &Session,
    run: &ClusteringResult,
) -> Result<Option<ModelFile>, ModelError> {
    let Some(choice) = &run.threshold_choice else {
        return Ok(None);
    };
    let params = &run.params;
    let method = params.learner.method();
    let opts = ClusterFitOptions {
        method,
        features: params.features,
        label_set: params.label_set.clone(),
        threshold: choice.threshold,
        seed: params.seed,
        params: params.clone(),
    };
    let (model, secs) = fit_clusters(session, &opts)?;
    let mut file = cluster_file(model, session, secs, None);
    file.provenance.feature_choice = run.feature_choice.clone();
    file.provenance.selection = SelectionScore::under(
        &format!("{}, {} orders", choice.criterion.text(), params.reps),
        &[("mean pairwise ARI", choice.agreement)],
    );
    Ok(Some(file))
}

/// Learn a saved model further on a new session.
pub fn continue_clusters(
    model: &ClusterModel,
    session: &Session,
) -> Result<(ClusterModel, f64), ModelError> {
    let t0 = Instant::now();
    let mut next = model.clone();
    next.learn(session)?;
    Ok((next, t0.elapsed().as_secs_f64()))
}

/// How a cluster is named in predictions and figures (1-based, as the window counts).
pub fn cluster_name(c: usize) -> String {
    format!("cluster {}", c + 1)
}

/// The model file of an unsupervised model learned (or learned further) on `session`.
pub fn cluster_file(
    model: ClusterModel,
    session: &Session,
    secs: f64,
    previous: Option<&Provenance>,
) -> ModelFile {
    let gp = match &model.clusterer {
        Clusterer::Du(l) => l.params().ds.gp,
        Clusterer::Gu(l) => l.params().gs.gp,
    };
    let mut parameters = vec![
        ("features".to_string(), model.inputs.features.to_string()),
        ("threshold".to_string(), model.threshold.to_string()),
        ("scored against".to_string(), model.label_set.clone()),
        ("order seed".to_string(), model.seed.to_string()),
        ("clusters".to_string(), model.clusters().to_string()),
        (
            "grasps learned".to_string(),
            model.grasps_taught.to_string(),
        ),
    ];
    if let Some(p) = previous {
        parameters.push((
            "continued from".to_string(),
            format!("{} [{}]", p.summary(), p.session.hash),
        ));
    }
    let provenance = Provenance {
        method: model.method(),
        parameters,
        size: vec![("capacity".into(), gp.capacity), ("tau".into(), gp.tau)],
        size_reason: SizeReason::PaperDefault,
        session: SessionRef::of(session),
        features: model.inputs.describe(),
        normalisation: "each feature min-max scaled over every frame of the training session \
                        (a new session: see its calibration; learning further keeps this range)"
            .into(),
        label_set: model.label_set.clone(),
        classes: (1..=model.clusters())
            .map(|c| format!("cluster {c}"))
            .collect(),
        trained_at: Provenance::now(),
        train_seconds: secs,
        selection: Vec::new(),
        // Learned further, the inputs stay the ones the first session chose.
        feature_choice: previous.and_then(|p| p.feature_choice.clone()),
    };
    ModelFile::new(provenance, Model::Clusters(model))
}
