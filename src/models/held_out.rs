//! A model on a session it did not train on: every grasp's prediction and decision value
//! and the scores of the method's kind against the session's labels (their figures, the
//! same as the within-session analyses', are in `held_out_report`). Every result states
//! where its model trained and how the new session was calibrated.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::clustering::cluster_name;
use super::recognition::{EARLY_FRACTIONS, SequencePrediction};
use super::table_one::TableOneLearner;
use super::{Calibration, Model, ModelError, ModelFile, SequenceModel, SessionRef};
use crate::catalogue::MethodId;
use crate::figures::csv_row;
use crate::session::Session;
use crate::svm::Confusion;

/// One grasp of the tested session as the model sees it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspPrediction {
    /// Index into the session's grasps.
    pub grasp: usize,
    pub object: String,
    pub trial: Option<u32>,
    /// The true class, when the session has the model's label set.
    pub truth: Option<String>,
    pub predicted: String,
    /// Grasp stability: the SVM's decision value, positive for failure. DS/GS: the
    /// decided class's probability at the grasp's last step.
    pub decision: f64,
}

/// The scores of the method's kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "task", rename_all = "snake_case")]
pub enum HeldOutScores {
    Stability {
        weighted_success_rate: f64,
        failure_recall: f64,
        success_recall: f64,
        /// Rows: true success, failure; columns: predicted success, failure.
        confusion: Confusion,
    },
    Recognition {
        /// Share of grasps whose class is decided right from the whole grasp.
        accuracy: f64,
        /// Accuracy of the decision from the first ⌈f·T⌉ steps, per fraction f.
        early: Vec<(f64, f64)>,
        /// Counts: rows the true class, columns the decided class (the model's classes).
        confusion: Vec<Vec<usize>>,
    },
    Clustering {
        purity: f64,
        ari: f64,
        nmi: f64,
        /// Clusters the model holds, and how many of them the session's grasps fall in.
        clusters: usize,
        effective: usize,
        /// The session's classes under the label set scored against (rows of the
        /// contingency table; its columns are the clusters).
        truth_classes: Vec<String>,
        contingency: Vec<Vec<usize>>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldOutResult {
    pub method: MethodId,
    /// The model in a few words ("sparse coding + SVM (num_bases 29), trained on …").
    pub model: String,
    pub trained_on: SessionRef,
    pub tested_on: SessionRef,
    pub calibration: Calibration,
    pub calibration_text: String,
    pub label_set: String,
    pub classes: Vec<String>,
    #[serde(flatten)]
    pub scores: HeldOutScores,
    pub predictions: Vec<GraspPrediction>,
    /// Seconds to evaluate (every grasp's prediction and the scores).
    pub secs: f64,
    /// Seconds the model took to train (its provenance's), for the speed chart.
    #[serde(default)]
    pub train_seconds: f64,
}

/// What a model gives every grasp of a session, before it is named.
enum Outputs {
    /// Grasp stability: the SVM's decision values.
    Decisions(Vec<f64>),
    /// DS/GS: the class distributions after every step, and the decisions.
    Steps(Vec<SequencePrediction>),
    /// DU/GU, k-means, SOM: a cluster; RBF SVM: a class id.
    Ids(Vec<usize>),
}

fn outputs(
    model: &Model,
    session: &Session,
    calibration: Calibration,
) -> Result<Outputs, ModelError> {
    // A decision past f64's range (weights a file made huge) or a NaN is no class.
    let not_finite = |g: usize, what: &str| {
        ModelError::NotFinite(format!(
            "the model's {what} for grasp {} ({}) is not a finite number: the model's values \
             overflow on this session; it cannot predict it",
            g + 1,
            session.grasps[g].object
        ))
    };
    Ok(match model {
        Model::Stability(c) => {
            let decisions = c.decisions(session, calibration)?;
            if let Some(g) = decisions.iter().position(|v| !v.is_finite()) {
                return Err(not_finite(g, "decision value"));
            }
            Outputs::Decisions(decisions)
        }
        Model::Sequences(m) => {
            let steps = m.predict(session, calibration)?;
            if let Some(g) = steps
                .iter()
                .position(|p| p.distributions.iter().any(|v| !v.is_finite()))
            {
                return Err(not_finite(g, "class distribution"));
            }
            Outputs::Steps(steps)
        }
        Model::Clusters(m) => Outputs::Ids(m.assign(session, calibration)?),
        Model::TableOne(m) => Outputs::Ids(m.assign(session, calibration)?),
        Model::Classifier(m) => Outputs::Ids(m.assign(session, calibration)?),
    })
}

/// Every grasp's predicted name and decision value, with its truth under the model's
/// label set where the session has it.
fn rows(model: &Model, session: &Session, out: &Outputs) -> Vec<GraspPrediction> {
    let named: Vec<(String, f64)> = match (model, out) {
        (Model::Stability(c), Outputs::Decisions(d)) => d
            .iter()
            .map(|&v| {
                let class = if v > 0.0 {
                    &c.failure_class
                } else {
                    &c.success_class
                };
                (class.clone(), v)
            })
            .collect(),
        (Model::Sequences(m), Outputs::Steps(steps)) => steps
            .iter()
            .map(|p| {
                let last = p.distributions.rows().into_iter().next_back();
                (
                    m.classes[p.class].clone(),
                    last.map_or(f64::NAN, |r| r[p.class]),
                )
            })
            .collect(),
        (Model::TableOne(m), Outputs::Ids(ids))
            if matches!(m.learner, TableOneLearner::RbfSvm(_)) =>
        {
            ids.iter()
                .map(|&id| (m.classes.get(id).cloned().unwrap_or_default(), f64::NAN))
                .collect()
        }
        (Model::Classifier(m), Outputs::Ids(ids)) => ids
            .iter()
            .map(|&id| (m.classes.get(id).cloned().unwrap_or_default(), f64::NAN))
            .collect(),
        (Model::Clusters(_) | Model::TableOne(_), Outputs::Ids(ids)) => {
            ids.iter().map(|&c| (cluster_name(c), f64::NAN)).collect()
        }
        (Model::Stability(_), Outputs::Steps(_) | Outputs::Ids(_))
        | (Model::Sequences(_), Outputs::Decisions(_) | Outputs::Ids(_))
        | (
            Model::Clusters(_) | Model::TableOne(_) | Model::Classifier(_),
            Outputs::Decisions(_) | Outputs::Steps(_),
        ) => unreachable!("outputs() gives each model its kind of output"),
    };
    let set = session.label_set(label_set_of(model));
    session
        .grasps
        .iter()
        .zip(named)
        .enumerate()
        .map(|(g, (grasp, (predicted, decision)))| GraspPrediction {
            grasp: g,
            object: grasp.object.clone(),
            trial: grasp.trial,
            truth: truth_of(session, set, g),
            predicted,
            decision,
        })
        .collect()
}

fn label_set_of(model: &Model) -> &str {
    match model {
        Model::Stability(c) => &c.label_set,
        Model::Sequences(m) => &m.label_set,
        Model::Clusters(m) => &m.label_set,
        Model::TableOne(m) => &m.label_set,
        Model::Classifier(m) => &m.label_set,
    }
}

/// Every grasp's prediction (labels are read only to fill `truth`).
pub fn predict(
    file: &ModelFile,
    session: &Session,
    calibration: Calibration,
) -> Result<Vec<GraspPrediction>, ModelError> {
    let out = outputs(&file.model, session, calibration)?;
    Ok(rows(&file.model, session, &out))
}

/// Why `evaluate` could not read `session` with this model, or Ok: the label set it is
/// scored against, then its prediction of the first grasp alone. The inputs a model reads
/// (sensors, features, their names) are the session's, the same for every grasp, so one
/// grasp answers for all at a fraction of the cost (the window asks it of every open
/// session when a model is to be evaluated).
pub fn check_readable(file: &ModelFile, session: &Session) -> Result<(), ModelError> {
    let label_set = label_set_of(&file.model);
    if session.label_set(label_set).is_none() {
        return Err(no_label_set(label_set, session));
    }
    let first = Session {
        meta: session.meta.clone(),
        sensors: session.sensors.clone(),
        encoders: session.encoders.clone(),
        label_sets: session.label_sets.clone(),
        grasps: session.grasps.iter().take(1).cloned().collect(),
    };
    if first.grasps.is_empty() {
        return Err(ModelError::Mismatch("the session has no grasps".into()));
    }
    outputs(&file.model, &first, Calibration::None).map(|_| ())
}

/// Grasp `g`'s class name under label set `set`, if it has one.
fn truth_of(session: &Session, set: Option<usize>, g: usize) -> Option<String> {
    let s = set?;
    let class = session.grasps[g].labels.get(s)?;
    session.label_sets[s].classes.get(*class).cloned()
}

/// Predictions as CSV: one row per grasp.
pub fn predictions_csv(rows: &[GraspPrediction]) -> String {
    let mut out = String::new();
    csv_row(
        &mut out,
        ["grasp", "object", "trial", "truth", "predicted", "decision"].map(String::from),
    );
    for p in rows {
        csv_row(
            &mut out,
            [
                p.grasp.to_string(),
                p.object.clone(),
                p.trial.map_or(String::new(), |t| t.to_string()),
                p.truth.clone().unwrap_or_default(),
                p.predicted.clone(),
                p.decision.to_string(),
            ],
        );
    }
    out
}

/// The model's scores on `session`, which must carry the model's label set.
pub fn evaluate(
    file: &ModelFile,
    session: &Session,
    calibration: Calibration,
) -> Result<HeldOutResult, ModelError> {
    let t0 = Instant::now();
    let out = outputs(&file.model, session, calibration)?;
    let predictions = rows(&file.model, session, &out);
    let label_set = label_set_of(&file.model).to_string();
    // A model that groups grasps: its clusters by name, scored against the label set.
    let clustered =
        |clusters: usize, ids: &[usize]| -> Result<(Vec<String>, HeldOutScores), ModelError> {
            Ok((
                (0..clusters).map(cluster_name).collect(),
                cluster_scores(&label_set, session, ids, clusters)?,
            ))
        };
    let (classes, scores) = match (&file.model, &out) {
        (Model::Stability(c), _) => (
            vec![c.success_class.clone(), c.failure_class.clone()],
            stability_scores(c, session, &predictions)?,
        ),
        (Model::Sequences(m), Outputs::Steps(steps)) => {
            if session.label_set(&m.label_set).is_none() {
                return Err(no_label_set(&m.label_set, session));
            }
            let decided: Vec<usize> = steps.iter().map(|p| p.class).collect();
            let early: Vec<Vec<usize>> = steps.iter().map(|p| p.early.clone()).collect();
            let scores =
                class_scores(&m.classes, m.method().key(), &predictions, &decided, &early)?;
            (m.classes.clone(), scores)
        }
        (Model::TableOne(m), Outputs::Ids(ids))
            if matches!(m.learner, TableOneLearner::RbfSvm(_)) =>
        {
            (
                m.classes.clone(),
                class_scores(&m.classes, m.method().key(), &predictions, ids, &[])?,
            )
        }
        (Model::Classifier(m), Outputs::Ids(ids)) => {
            if session.label_set(&m.label_set).is_none() {
                return Err(no_label_set(&m.label_set, session));
            }
            (
                m.classes.clone(),
                class_scores(&m.classes, m.method.key(), &predictions, ids, &[])?,
            )
        }
        (Model::Clusters(m), Outputs::Ids(ids)) => clustered(m.clusters(), ids)?,
        (Model::TableOne(m), Outputs::Ids(ids)) => clustered(m.outputs(), ids)?,
        (Model::Sequences(_), Outputs::Decisions(_) | Outputs::Ids(_))
        | (
            Model::Clusters(_) | Model::TableOne(_) | Model::Classifier(_),
            Outputs::Decisions(_) | Outputs::Steps(_),
        ) => unreachable!("outputs() gives each model its kind of output"),
    };
    Ok(HeldOutResult {
        method: file.provenance.method,
        model: file.provenance.summary(),
        trained_on: file.provenance.session.clone(),
        tested_on: SessionRef::of(session),
        calibration,
        calibration_text: calibration.describe(),
        label_set,
        classes,
        scores,
        predictions,
        secs: t0.elapsed().as_secs_f64(),
        train_seconds: file.provenance.train_seconds,
    })
}

fn no_label_set(label_set: &str, session: &Session) -> ModelError {
    ModelError::Mismatch(format!(
        "the model predicts label set {label_set:?}; the session has {:?}",
        session
            .label_sets
            .iter()
            .map(|l| &l.name)
            .collect::<Vec<_>>()
    ))
}

fn stability_scores(
    c: &super::StabilityClassifier,
    session: &Session,
    predictions: &[GraspPrediction],
) -> Result<HeldOutScores, ModelError> {
    let Some(set) = session.label_set(&c.label_set) else {
        return Err(no_label_set(&c.label_set, session));
    };
    let mut truth = Vec::with_capacity(predictions.len());
    for p in predictions {
        let t = p.truth.as_deref().unwrap_or_default();
        if t == c.failure_class {
            truth.push(true);
        } else if t == c.success_class {
            truth.push(false);
        } else {
            return Err(ModelError::Mismatch(format!(
                "grasp {} has class {t:?} of {:?}; the model knows {:?} and {:?}",
                p.grasp, session.label_sets[set].name, c.success_class, c.failure_class
            )));
        }
    }
    let predicted: Vec<bool> = predictions.iter().map(|p| p.decision > 0.0).collect();
    let confusion = Confusion::from_predictions(&truth, &predicted);
    let (Some(wsr), Some(failure_recall), Some(success_recall)) = (
        confusion.weighted_success_rate(),
        confusion.failure_recall(),
        confusion.success_recall(),
    ) else {
        return Err(ModelError::Mismatch(format!(
            "every grasp of the session has one outcome ({} {}, {} {}): the weighted success \
             rate needs both",
            confusion.total_successes(),
            c.success_class,
            confusion.total_failures(),
            c.failure_class
        )));
    };
    Ok(HeldOutScores::Stability {
        weighted_success_rate: wsr,
        failure_recall,
        success_recall,
        confusion,
    })
}

fn cluster_scores(
    label_set: &str,
    session: &Session,
    pred: &[usize],
    clusters: usize,
) -> Result<HeldOutScores, ModelError> {
    let (truth, truth_classes) = super::recognition::labels(session, label_set)?;
    let sc = crate::cluster::scores(&truth, pred);
    let mut contingency = vec![vec![0; clusters]; truth_classes.len()];
    for (t, p) in truth.iter().zip(pred) {
        contingency[*t][*p] += 1;
    }
    Ok(HeldOutScores::Clustering {
        purity: sc.purity,
        ari: sc.ari,
        nmi: sc.nmi,
        clusters,
        effective: crate::experiments::clustering::distinct(pred),
        truth_classes,
        contingency,
    })
}

/// Accuracy, early decisions (per grasp, one class per fraction of `EARLY_FRACTIONS`;
/// none for a method that decides from the whole grasp) and the confusion counts of a
/// classifier whose classes are `classes`.
fn class_scores(
    classes: &[String],
    method: &str,
    predictions: &[GraspPrediction],
    decided: &[usize],
    early: &[Vec<usize>],
) -> Result<HeldOutScores, ModelError> {
    let mut truth = Vec::with_capacity(predictions.len());
    for p in predictions {
        let t = p.truth.as_deref().unwrap_or_default();
        let class = classes.iter().position(|c| c == t).ok_or_else(|| {
            ModelError::Mismatch(format!(
                "grasp {} is of class {t:?}, which the model has no expert for (it knows {}); \
                 teach it the class with `fit {method} SESSION --from MODEL` or fit it anew",
                p.grasp,
                classes.join(", "),
            ))
        })?;
        truth.push(class);
    }
    let n = classes.len();
    let mut confusion = vec![vec![0; n]; n];
    for (t, d) in truth.iter().zip(decided) {
        confusion[*t][*d] += 1;
    }
    let share = |right: usize| right as f64 / truth.len().max(1) as f64;
    let accuracy = share(truth.iter().zip(decided).filter(|(t, d)| t == d).count());
    let early = if early.is_empty() {
        Vec::new()
    } else {
        EARLY_FRACTIONS
            .iter()
            .enumerate()
            .map(|(i, &f)| {
                let right = truth
                    .iter()
                    .zip(early)
                    .filter(|(t, e)| e.get(i) == Some(*t))
                    .count();
                (f, share(right))
            })
            .collect()
    };
    Ok(HeldOutScores::Recognition {
        accuracy,
        early,
        confusion,
    })
}

/// DS/GS: every step of every grasp with the class distribution after it, as CSV (one
/// column per class of the model).
pub fn steps_csv(
    m: &SequenceModel,
    session: &Session,
    calibration: Calibration,
) -> Result<String, ModelError> {
    let mut out = String::new();
    let mut header = vec!["grasp".to_string(), "object".into(), "step".into()];
    header.extend(m.classes.iter().cloned());
    csv_row(&mut out, header);
    for (g, p) in m.predict(session, calibration)?.iter().enumerate() {
        for (t, row) in p.distributions.rows().into_iter().enumerate() {
            let mut cells = vec![
                g.to_string(),
                session.grasps[g].object.clone(),
                (t + 1).to_string(),
            ];
            cells.extend(row.iter().map(f64::to_string));
            csv_row(&mut out, cells);
        }
    }
    Ok(out)
}
