//! A model on a session it did not train on: every grasp's prediction and decision value,
//! the scores of the method's kind against the session's labels, and the same figures as
//! the within-session analyses, with the grasps behind each part of them. Every result
//! states where its model trained and how the new session was calibrated.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::{Calibration, Model, ModelError, ModelFile, SessionRef};
use crate::catalogue::MethodId;
use crate::experiments::links::{GraspLinks, grasps_text};
use crate::experiments::result::{AnalysisKind, AnalysisResult, HeldOut};
use crate::experiments::stability::report::confusion_map;
use crate::figures::{Axis, AxisTitle, BarGroup, Figure, csv_row};
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
    /// Grasp stability: the SVM's decision value, positive for failure.
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
    pub secs: f64,
}

/// Every grasp's prediction (labels are read only to fill `truth`).
pub fn predict(
    file: &ModelFile,
    session: &Session,
    calibration: Calibration,
) -> Result<Vec<GraspPrediction>, ModelError> {
    match &file.model {
        Model::Stability(c) => {
            let decisions = c.decisions(session, calibration)?;
            let set = session.label_set(&c.label_set);
            Ok(session
                .grasps
                .iter()
                .zip(decisions)
                .enumerate()
                .map(|(g, (grasp, decision))| GraspPrediction {
                    grasp: g,
                    object: grasp.object.clone(),
                    trial: grasp.trial,
                    truth: set.and_then(|s| {
                        let class = grasp.labels.get(s)?;
                        session.label_sets[s].classes.get(*class).cloned()
                    }),
                    predicted: if decision > 0.0 {
                        c.failure_class.clone()
                    } else {
                        c.success_class.clone()
                    },
                    decision,
                })
                .collect())
        }
    }
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
    let predictions = predict(file, session, calibration)?;
    let Model::Stability(c) = &file.model;
    let Some(set) = session.label_set(&c.label_set) else {
        return Err(ModelError::Mismatch(format!(
            "the model predicts label set {:?}; the session has {:?}",
            c.label_set,
            session
                .label_sets
                .iter()
                .map(|l| &l.name)
                .collect::<Vec<_>>()
        )));
    };
    let mut truth = Vec::with_capacity(predictions.len());
    for p in &predictions {
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
    Ok(HeldOutResult {
        method: file.provenance.method,
        model: file.provenance.summary(),
        trained_on: file.provenance.session.clone(),
        tested_on: SessionRef::of(session),
        calibration,
        calibration_text: calibration.describe(),
        label_set: c.label_set.clone(),
        classes: vec![c.success_class.clone(), c.failure_class.clone()],
        scores: HeldOutScores::Stability {
            weighted_success_rate: wsr,
            failure_recall,
            success_recall,
            confusion,
        },
        predictions,
        secs: t0.elapsed().as_secs_f64(),
    })
}

/// The held-out result as an analysis: scores, the confusion map and the share correct
/// per object, linked to the tested session's grasps.
pub fn held_out_report(r: &HeldOutResult) -> AnalysisResult {
    let HeldOutScores::Stability {
        weighted_success_rate,
        failure_recall,
        success_recall,
        confusion,
    } = &r.scores;
    let (ok, bad) = (&r.classes[0], &r.classes[1]);
    let held_out = HeldOut {
        trained_on: r.trained_on.name.clone(),
        trained_grasps: r.trained_on.grasps,
        tested_on: r.tested_on.name.clone(),
        tested_grasps: r.tested_on.grasps,
        calibration: r.calibration.to_string(),
    };
    let confusion_fig = confusion_map(
        &format!("Confusion map, held out on {}", r.tested_on.name),
        confusion,
        ok,
        bad,
    )
    .subtitle(format!(
        "weighted success rate {:.1}%, failure recall {:.1}%; calibration {}",
        100.0 * weighted_success_rate,
        100.0 * failure_recall,
        r.calibration
    ));
    let failure = |c: &str| usize::from(c == bad);
    let links = GraspLinks::from_observations(
        "confusion",
        None,
        r.predictions.iter().filter_map(|p| {
            let t = p.truth.as_deref()?;
            Some(([failure(t), failure(&p.predicted)], p.grasp))
        }),
        |[t, p], grasps, _| {
            let class = |f: usize| if f == 1 { bad } else { ok };
            format!(
                "true {}, predicted {}: {}",
                class(t),
                class(p),
                grasps_text(grasps)
            )
        },
    );
    let mut per_object: Vec<(String, usize, usize)> = Vec::new();
    for p in &r.predictions {
        let Some(t) = &p.truth else { continue };
        let i = match per_object.iter().position(|(o, _, _)| *o == p.object) {
            Some(i) => i,
            None => {
                per_object.push((p.object.clone(), 0, 0));
                per_object.len() - 1
            }
        };
        per_object[i].1 += usize::from(*t == p.predicted);
        per_object[i].2 += 1;
    }
    let objects = Figure::bars(
        format!("Share correct per object, held out on {}", r.tested_on.name),
        AxisTitle {
            title: "object".into(),
            unit: String::new(),
        },
        Axis::new("share correct", "").including(0.0, 1.0),
        per_object.iter().map(|(o, _, _)| o.clone()).collect(),
        vec![BarGroup::new(
            "grasps",
            per_object
                .iter()
                .map(|(_, right, n)| *right as f64 / *n as f64)
                .collect(),
        )],
    )
    .subtitle(held_out.text());
    let parameters = BTreeMap::from([
        ("model".to_string(), r.model.clone()),
        ("trained on".to_string(), r.trained_on.name.clone()),
        (
            "training session hash".to_string(),
            r.trained_on.hash.clone(),
        ),
        ("calibration".to_string(), r.calibration_text.clone()),
        ("label set".to_string(), r.label_set.clone()),
    ]);
    AnalysisResult {
        kind: match r.method.task() {
            crate::catalogue::Task::Stability => AnalysisKind::Stability,
            crate::catalogue::Task::Recognition => AnalysisKind::Recognition,
            crate::catalogue::Task::Clustering => AnalysisKind::Clustering,
        },
        label: format!(
            "{}, held out (calibration {})",
            r.method.title(),
            r.calibration
        ),
        session: r.tested_on.name.clone(),
        parameters,
        scores: vec![
            ("weighted success rate".into(), *weighted_success_rate),
            ("failure recall".into(), *failure_recall),
            ("success recall".into(), *success_recall),
        ],
        headline: None,
        train_seconds: 0.0,
        predict_seconds_per_sample: Some(r.secs / r.predictions.len().max(1) as f64),
        created: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
        figures: vec![
            ("confusion".into(), confusion_fig),
            ("objects".into(), objects),
        ],
        details: Vec::new(),
        links: vec![links],
        grasp_codes: Vec::new(),
        model_size: None,
        held_out: Some(held_out),
    }
}
