//! The offline baselines of the second paper on the per-grasp Table I features as models:
//! sequential k-means and the SOM (clusters of grasps) and the RBF SVM (the object of a
//! grasp), fitted on every grasp of a session as `baselines` fits them. A calibration
//! decides whose statistics put a new session's features on the model's scale: the
//! min-max map of k-means and the SOM, the RBF SVM's z-scoring.

use std::time::Instant;

use ndarray::{Array2, ArrayView2, s};
use serde::{Deserialize, Serialize};

use super::{Calibration, Model, ModelError, ModelFile, Provenance, SelectionScore, SessionRef};
use crate::catalogue::MethodId;
use crate::cluster::{SelfOrganisingMap, SequentialKMeans, SequentialKMeansParams, SomParams};
use crate::experiments::baselines::{BaselinesParams, BaselinesResult, SvmSummary, svm_grid};
use crate::experiments::clustering::som_setup;
use crate::experiments::result::SizeReason;
use crate::features::Normaliser;
use crate::features::table_one::{feature_names, session_features};
use crate::jobs::Progress;
use crate::session::Session;
use crate::svm::kernel_svm::{KernelSvm, KernelSvmParams};

/// A fitted baseline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "learner", content = "state", rename_all = "snake_case")]
pub enum TableOneLearner {
    KMeans(SequentialKMeans),
    Som(SelfOrganisingMap),
    RbfSvm(KernelSvm),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableOneModel {
    pub learner: TableOneLearner,
    pub feature_names: Vec<String>,
    /// k-means and SOM: the training session's min-max map of the features (the RBF SVM
    /// carries its own z-scoring).
    pub normaliser: Normaliser,
    /// The label set learned (RBF SVM) or scored against (k-means, SOM).
    pub label_set: String,
    /// RBF SVM: the name of each class id.
    pub classes: Vec<String>,
}

/// The session's Table I features, checked against the model's names.
fn features(session: &Session, names: Option<&[String]>) -> Result<Array2<f64>, ModelError> {
    let found = feature_names(session);
    if let Some(names) = names
        && found != names
    {
        return Err(ModelError::Mismatch(format!(
            "the model reads {} Table I features ({}); the session gives {} ({})",
            names.len(),
            names.join(", "),
            found.len(),
            found.join(", ")
        )));
    }
    session_features(session).map_err(ModelError::Features)
}

/// The rows whose statistics stand for the session under `calibration` (None: the
/// model's own).
fn rows(
    x: ArrayView2<f64>,
    calibration: Calibration,
) -> Result<Option<ArrayView2<f64>>, ModelError> {
    Ok(calibration
        .grasps(x.nrows())?
        .map(|r| x.slice_move(s![r, ..])))
}

impl TableOneModel {
    pub fn method(&self) -> MethodId {
        match self.learner {
            TableOneLearner::KMeans(_) => MethodId::KMeans,
            TableOneLearner::Som(_) => MethodId::Som,
            TableOneLearner::RbfSvm(_) => MethodId::RbfSvm,
        }
    }

    /// Clusters (k-means centres, SOM units) or classes (RBF SVM).
    pub fn outputs(&self) -> usize {
        match &self.learner {
            TableOneLearner::KMeans(k) => k.centres.nrows(),
            TableOneLearner::Som(m) => m.weights.nrows(),
            TableOneLearner::RbfSvm(_) => self.classes.len(),
        }
    }

    /// The cluster (k-means, SOM) or class id (RBF SVM) of every grasp of `session`.
    pub fn assign(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<usize>, ModelError> {
        let x = features(session, Some(&self.feature_names))?;
        match &self.learner {
            TableOneLearner::RbfSvm(svm) => {
                let mut svm = svm.clone();
                if let (Some(part), Some(own)) = (rows(x.view(), calibration)?, &svm.scaler) {
                    svm.scaler =
                        Some(Normaliser::fit(own.kind, part).map_err(ModelError::Features)?);
                }
                svm.predict(x.view()).map_err(ModelError::KernelSvm)
            }
            learner @ (TableOneLearner::KMeans(_) | TableOneLearner::Som(_)) => {
                let normaliser = match rows(x.view(), calibration)? {
                    Some(part) => {
                        Normaliser::fit(self.normaliser.kind, part).map_err(ModelError::Features)?
                    }
                    None => self.normaliser.clone(),
                };
                let data = normaliser
                    .transform(x.view())
                    .map_err(ModelError::Features)?;
                match learner {
                    TableOneLearner::KMeans(k) => {
                        k.assign(data.view()).map_err(ModelError::Cluster)
                    }
                    TableOneLearner::Som(m) => m.assign(data.view()).map_err(ModelError::Cluster),
                    TableOneLearner::RbfSvm(_) => unreachable!("handled above"),
                }
            }
        }
    }

    pub fn validate(&self) -> Result<(), ModelError> {
        let n = self.feature_names.len();
        let f = |name: &str| format!("model.{name}");
        if n == 0 || self.normaliser.offset.len() != n || self.normaliser.scale.len() != n {
            return Err(ModelError::field(
                f("normaliser"),
                format!("{} offsets for {n} features", self.normaliser.offset.len()),
            ));
        }
        if !matches!(self.learner, TableOneLearner::RbfSvm(_)) {
            check_scaler(&self.normaliser, &f("normaliser"))?;
        }
        let width = |w: usize, field: &str| {
            if w == n {
                Ok(())
            } else {
                Err(ModelError::field(
                    f(field),
                    format!("{w} columns for {n} features"),
                ))
            }
        };
        match &self.learner {
            TableOneLearner::KMeans(k) => {
                if k.centres.nrows() == 0 {
                    return Err(ModelError::field(f("learner.centres"), "no centres"));
                }
                if k.centres.iter().any(|v| !v.is_finite()) {
                    return Err(ModelError::field(
                        f("learner.centres"),
                        "values must be finite",
                    ));
                }
                width(k.centres.ncols(), "learner.centres")
            }
            TableOneLearner::Som(m) => {
                if m.weights.nrows() == 0 || m.weights.nrows() != m.rows * m.cols {
                    return Err(ModelError::field(
                        f("learner.weights"),
                        format!(
                            "{} units for a {} × {} map",
                            m.weights.nrows(),
                            m.rows,
                            m.cols
                        ),
                    ));
                }
                if m.weights.iter().any(|v| !v.is_finite()) {
                    return Err(ModelError::field(
                        f("learner.weights"),
                        "values must be finite",
                    ));
                }
                width(m.weights.ncols(), "learner.weights")
            }
            TableOneLearner::RbfSvm(svm) => {
                if !(svm.gamma.is_finite() && svm.gamma > 0.0) {
                    return Err(ModelError::field(
                        f("learner.gamma"),
                        format!("{} is not a finite kernel width > 0", svm.gamma),
                    ));
                }
                if svm.classes.is_empty() || svm.classes.windows(2).any(|w| w[0] >= w[1]) {
                    return Err(ModelError::field(
                        f("learner.classes"),
                        "class ids must be listed once each, ascending",
                    ));
                }
                for (i, m) in svm.machines.iter().enumerate() {
                    let at = |field: &str| f(&format!("learner.machines[{i}].{field}"));
                    width(
                        m.support_vectors.ncols(),
                        "learner.machines.support_vectors",
                    )?;
                    if m.coef.len() != m.support_vectors.nrows() {
                        return Err(ModelError::field(
                            at("coef"),
                            "one coefficient per support vector",
                        ));
                    }
                    let (a, b) = m.classes;
                    let known = |c: usize| svm.classes.binary_search(&c).is_ok();
                    if a == b || !known(a) || !known(b) {
                        return Err(ModelError::field(
                            at("classes"),
                            format!(
                                "({a}, {b}) is not a pair of the model's classes {:?}",
                                svm.classes
                            ),
                        ));
                    }
                    let values = m.support_vectors.iter().chain(&m.coef);
                    if !m.rho.is_finite() || values.clone().any(|v| !v.is_finite()) {
                        return Err(ModelError::field(
                            at("coef"),
                            "support vectors, coefficients and rho must be finite",
                        ));
                    }
                }
                if let Some(s) = &svm.scaler {
                    width(s.offset.len(), "learner.scaler")?;
                    check_scaler(s, &f("learner.scaler"))?;
                }
                if svm.classes.iter().any(|&c| c >= self.classes.len()) {
                    return Err(ModelError::field(
                        f("classes"),
                        format!(
                            "{} class names for class ids up to {:?}",
                            self.classes.len(),
                            svm.classes.last()
                        ),
                    ));
                }
                Ok(())
            }
        }
    }
}

/// A feature map read from a file: as many scales as offsets, every value finite, scales
/// ≥ 0 (0: a feature constant in training), and not every scale 0 (the model would read
/// one constant point for every grasp).
fn check_scaler(s: &Normaliser, field: &str) -> Result<(), ModelError> {
    if s.scale.len() != s.offset.len() {
        return Err(ModelError::field(
            field,
            format!("{} scales for {} offsets", s.scale.len(), s.offset.len()),
        ));
    }
    if s.offset.iter().any(|v| !v.is_finite())
        || s.scale.iter().any(|v| !(v.is_finite() && *v >= 0.0))
    {
        return Err(ModelError::field(
            field,
            "offsets must be finite, scales finite and ≥ 0",
        ));
    }
    if s.scale.iter().all(|v| *v == 0.0) {
        return Err(ModelError::field(
            field,
            "every scale is 0 (a deviation of 0 for every feature): the model would see \
             every grasp alike",
        ));
    }
    Ok(())
}

/// What fitting leaves besides the model.
#[derive(Clone, Debug, PartialEq)]
pub struct TableOneFit {
    pub selection: Vec<SelectionScore>,
    pub parameters: Vec<(String, String)>,
    pub secs: f64,
}

/// How a Table I baseline is fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct TableOneFitOptions {
    pub method: MethodId,
    pub label_set: String,
    /// k, seed, normalisation, k-means passes, the SOM and the RBF grid, as `baselines`
    /// runs them.
    pub params: BaselinesParams,
}

impl TableOneFitOptions {
    /// `fit`'s settings: k centres or units (the paper's 10) on the SOM grid of the
    /// clustering comparison, the `baselines` defaults otherwise.
    pub fn new(method: MethodId, label_set: &str, k: usize, seed: u64) -> TableOneFitOptions {
        TableOneFitOptions {
            method,
            label_set: label_set.into(),
            params: BaselinesParams {
                k,
                seed,
                som: som_setup(k, seed),
                ..Default::default()
            },
        }
    }
}

/// Fit k-means, the SOM or the RBF SVM on every grasp of `session`. The RBF SVM takes the
/// C and gamma of `grid` (a `baselines` run's search), else runs the search (repeated
/// 5-fold cross validation).
pub fn fit_table_one(
    session: &Session,
    opts: &TableOneFitOptions,
    grid: Option<&SvmSummary>,
) -> Result<(TableOneModel, TableOneFit), ModelError> {
    let t0 = Instant::now();
    let params = &opts.params;
    let mut parameters = vec![("seed".to_string(), params.seed.to_string())];
    let x = features(session, None)?;
    let normaliser =
        Normaliser::fit(params.normalisation, x.view()).map_err(ModelError::Features)?;
    let data = normaliser
        .transform(x.view())
        .map_err(ModelError::Features)?;
    let (labels, classes) = super::recognition::labels(session, &opts.label_set)?;
    let mut selection = Vec::new();
    let learner = match opts.method {
        MethodId::KMeans => TableOneLearner::KMeans(
            SequentialKMeansParams {
                k: params.k,
                passes: params.kmeans_passes,
                seed: params.seed,
            }
            .fit(data.view())
            .map_err(|e| ModelError::Baselines(e.into()))?,
        ),
        MethodId::Som => {
            let som = SomParams {
                seed: params.seed,
                ..params.som.clone()
            };
            TableOneLearner::Som(
                som.fit(data.view())
                    .map_err(|e| ModelError::Baselines(e.into()))?,
            )
        }
        MethodId::RbfSvm => {
            let searched;
            let grid = match grid {
                Some(g) => g,
                None => {
                    searched = svm_grid(x.view(), &labels, params, &Progress::new())
                        .map_err(ModelError::Baselines)?;
                    &searched
                }
            };
            selection.push(SelectionScore {
                protocol: format!("{} × {}-fold cross validation", grid.repeats, grid.folds),
                name: "accuracy".into(),
                value: grid.best.accuracy_mean,
            });
            parameters.push(("C".into(), grid.best.c.to_string()));
            let p = KernelSvmParams {
                c: grid.best.c,
                gamma: grid.best.gamma,
                ..Default::default()
            };
            TableOneLearner::RbfSvm(
                p.fit(x.view(), &labels)
                    .map_err(|e| ModelError::Baselines(e.into()))?,
            )
        }
        other @ (MethodId::SparseSvm
        | MethodId::RawSvm
        | MethodId::Ds
        | MethodId::Gs
        | MethodId::Du
        | MethodId::Gu
        | MethodId::Classifier(_)) => {
            return Err(ModelError::Param(format!(
                "{} is not a Table I baseline (kmeans, som, rbf-svm)",
                other.key()
            )));
        }
    };
    let model = TableOneModel {
        learner,
        feature_names: feature_names(session),
        normaliser,
        label_set: opts.label_set.clone(),
        classes,
    };
    let fit = TableOneFit {
        selection,
        parameters,
        secs: t0.elapsed().as_secs_f64(),
    };
    Ok((model, fit))
}

/// The model file of a Table I baseline fitted on `session`.
pub fn table_one_file(model: TableOneModel, session: &Session, fit: TableOneFit) -> ModelFile {
    let TableOneFit {
        selection,
        mut parameters,
        secs,
    } = fit;
    parameters.push(("label set".to_string(), model.label_set.clone()));
    let size = match &model.learner {
        TableOneLearner::RbfSvm(svm) => {
            parameters.push(("gamma".into(), svm.gamma.to_string()));
            Vec::new()
        }
        TableOneLearner::KMeans(k) => vec![("k".to_string(), k.centres.nrows())],
        TableOneLearner::Som(m) => vec![("units".to_string(), m.weights.nrows())],
    };
    let classes = match &model.learner {
        TableOneLearner::RbfSvm(_) => model.classes.clone(),
        TableOneLearner::KMeans(_) | TableOneLearner::Som(_) => (0..model.outputs())
            .map(super::clustering::cluster_name)
            .collect(),
    };
    let provenance = Provenance {
        method: model.method(),
        parameters,
        size,
        size_reason: SizeReason::PaperDefault,
        session: SessionRef::of(session),
        features: format!("{} Table I features per grasp: {}", model.feature_names.len(), model.feature_names.join(", ")),
        normalisation: match model.learner {
            TableOneLearner::RbfSvm(_) => "each feature z-scored over the training grasps (a new session: see its calibration)",
            TableOneLearner::KMeans(_) | TableOneLearner::Som(_) => "each feature min-max scaled over the training grasps (a new session: see its calibration)",
        }
        .into(),
        label_set: model.label_set.clone(),
        classes,
        trained_at: Provenance::now(),
        train_seconds: secs,
        selection,
        feature_choice: None,
    };
    ModelFile::new(provenance, Model::TableOne(model))
}

/// The models a `baselines` run leaves: k-means, the SOM and (when the run searched its
/// grid) the RBF SVM, each fitted on every grasp of `session` with the run's settings, the
/// clusterers selected by the run's mean scores over its orders.
pub fn table_one_files_of_run(
    session: &Session,
    label_set: &str,
    run: &BaselinesResult,
) -> Result<Vec<ModelFile>, ModelError> {
    let mut methods = vec![MethodId::KMeans, MethodId::Som];
    if run.svm.is_some() {
        methods.push(MethodId::RbfSvm);
    }
    methods
        .into_iter()
        .map(|method| {
            let opts = TableOneFitOptions {
                method,
                label_set: label_set.into(),
                params: run.params.clone(),
            };
            let (model, mut fit) = fit_table_one(session, &opts, run.svm.as_ref())?;
            let scores = match method {
                MethodId::KMeans => Some(&run.kmeans),
                MethodId::Som => Some(&run.som),
                // The RBF SVM keeps its cross-validated accuracy.
                MethodId::SparseSvm
                | MethodId::RawSvm
                | MethodId::Ds
                | MethodId::Gs
                | MethodId::Du
                | MethodId::Gu
                | MethodId::RbfSvm
                | MethodId::Classifier(_) => None,
            };
            if let Some(s) = scores {
                let protocol = format!("{} random orders", run.params.orders);
                fit.selection = SelectionScore::under(
                    &protocol,
                    &[
                        ("purity", s.mean.purity),
                        ("ARI", s.mean.ari),
                        ("NMI", s.mean.nmi),
                    ],
                );
            }
            Ok(table_one_file(model, session, fit))
        })
        .collect()
}
