//! A held-out result as an analysis result: its scores, the confusion map (or the
//! contingency map of a clustering) linked to the tested session's grasps, and per task the
//! share correct per object, the accuracy of early decisions or the grasps per cluster.

use crate::experiments::figure_id::FigureId;
use std::collections::BTreeMap;

use super::held_out::{HeldOutResult, HeldOutScores};
use crate::experiments::links::{GraspLinks, grasps_text};
use crate::experiments::result::{AnalysisKind, AnalysisResult, HeldOut};
use crate::experiments::stability::report::confusion_map;
use crate::figures::{Axis, AxisTitle, BarGroup, ColorScale, Figure, FigureKind, Heatmap, Series};

/// The held-out result as an analysis: scores, the confusion map (linked to the tested
/// session's grasps) and, per kind, the share correct per object (stability) or the
/// accuracy of early decisions (recognition).
pub fn held_out_report(r: &HeldOutResult) -> AnalysisResult {
    let held_out = HeldOut {
        trained_on: r.trained_on.name.clone(),
        trained_grasps: r.trained_on.grasps,
        tested_on: r.tested_on.name.clone(),
        tested_grasps: r.tested_on.grasps,
        calibration: r.calibration.to_string(),
    };
    let (scores, confusion_fig, second) = scores_and_figures(r, &held_out);
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
        scores,
        // No headline: a held-out score is never joined to cross-validated ones.
        headline: None,
        train_seconds: r.train_seconds,
        predict_seconds_per_sample: Some(r.secs / r.predictions.len().max(1) as f64),
        created: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
        figures: vec![(FigureId::Confusion, confusion_fig), second],
        details: Vec::new(),
        links: vec![confusion_links(r)],
        grasp_codes: Vec::new(),
        model_size: None,
        held_out: Some(held_out),
        methods: vec![r.method],
    }
}

/// Confusion cell [true class, predicted class or cluster] → the tested grasps in it.
fn confusion_links(r: &HeldOutResult) -> GraspLinks {
    let class_of = |name: &str| r.classes.iter().position(|c| c == name);
    // Rows: the true classes (the model's own, or for clusters the session's).
    let rows = match &r.scores {
        HeldOutScores::Clustering { truth_classes, .. } => truth_classes,
        _ => &r.classes,
    };
    let row_of = |name: &str| rows.iter().position(|c| c == name);
    GraspLinks::from_observations(
        FigureId::Confusion,
        None,
        r.predictions.iter().filter_map(|p| {
            let t = row_of(p.truth.as_deref()?)?;
            Some(([t, class_of(&p.predicted)?], p.grasp))
        }),
        |[t, p], grasps, _| {
            format!(
                "true {}, predicted {}: {}",
                rows[t],
                r.classes[p],
                grasps_text(grasps)
            )
        },
    )
}

/// The task's named scores, its confusion map and its second figure with that figure's
/// name.
fn scores_and_figures(
    r: &HeldOutResult,
    held_out: &HeldOut,
) -> (Vec<(String, f64)>, Figure, (FigureId, Figure)) {
    let title = format!("Confusion map, held out on {}", r.tested_on.name);
    match &r.scores {
        HeldOutScores::Stability {
            weighted_success_rate,
            failure_recall,
            success_recall,
            confusion,
        } => {
            let fig =
                confusion_map(&title, confusion, &r.classes[0], &r.classes[1]).subtitle(format!(
                    "weighted success rate {:.1}%, failure recall {:.1}%; calibration {}",
                    100.0 * weighted_success_rate,
                    100.0 * failure_recall,
                    r.calibration
                ));
            let scores = vec![
                ("weighted success rate".into(), *weighted_success_rate),
                ("failure recall".into(), *failure_recall),
                ("success recall".into(), *success_recall),
            ];
            (scores, fig, (FigureId::Objects, per_object(r, held_out)))
        }
        HeldOutScores::Recognition {
            accuracy,
            early,
            confusion,
        } => {
            let fig = class_confusion(&title, confusion, &r.classes).subtitle(format!(
                "accuracy {:.1}%; calibration {}",
                100.0 * accuracy,
                r.calibration
            ));
            let second = if early.is_empty() {
                (FigureId::Objects, per_object(r, held_out))
            } else {
                (FigureId::Early, early_classification(r, early, held_out))
            };
            (vec![("accuracy".into(), *accuracy)], fig, second)
        }
        HeldOutScores::Clustering {
            purity,
            ari,
            nmi,
            clusters,
            effective,
            truth_classes,
            contingency,
        } => {
            let mut fig = class_confusion(&title, contingency, &r.classes).subtitle(format!(
                "purity {purity:.2}, ARI {ari:.2}, NMI {nmi:.2}; {effective} of {clusters} clusters hold grasps; calibration {}",
                r.calibration
            ));
            if let FigureKind::Heatmap(h) = &mut fig.kind {
                h.rows = truth_classes.clone();
                h.y.title = format!("true {}", r.label_set);
                h.x.title = "cluster".into();
            }
            let sizes = cluster_sizes(r, *clusters, contingency, held_out);
            (
                vec![
                    ("purity".into(), *purity),
                    ("ARI".into(), *ari),
                    ("NMI".into(), *nmi),
                ],
                fig,
                (FigureId::Clusters, sizes),
            )
        }
    }
}

/// Accuracy of the decisions from the start of each grasp, per share observed.
fn early_classification(r: &HeldOutResult, early: &[(f64, f64)], held_out: &HeldOut) -> Figure {
    Figure::chart(
        format!("Early classification, held out on {}", r.tested_on.name),
        Axis::new("share of the grasp observed", "").including(0.0, 1.0),
        Axis::new("accuracy", "").including(0.0, 1.0),
        vec![Series::new(
            r.method.title(),
            early.iter().map(|(f, _)| *f).collect(),
            early.iter().map(|(_, a)| *a).collect(),
        )],
    )
    .subtitle(held_out.text())
}

/// How many tested grasps fall in each of the model's clusters.
fn cluster_sizes(
    r: &HeldOutResult,
    clusters: usize,
    contingency: &[Vec<usize>],
    held_out: &HeldOut,
) -> Figure {
    Figure::bars(
        format!("Grasps per cluster, held out on {}", r.tested_on.name),
        AxisTitle {
            title: "cluster".into(),
            unit: String::new(),
        },
        Axis::new("grasps", ""),
        r.classes.clone(),
        vec![BarGroup::new(
            "grasps",
            (0..clusters)
                .map(|c| contingency.iter().map(|row| row[c]).sum::<usize>() as f64)
                .collect(),
        )],
    )
    .subtitle(held_out.text())
}

/// The share of each true class decided as each class.
fn class_confusion(title: &str, counts: &[Vec<usize>], classes: &[String]) -> Figure {
    let values = counts
        .iter()
        .map(|row| {
            let total: usize = row.iter().sum();
            row.iter()
                .map(|&c| {
                    if total == 0 {
                        f64::NAN
                    } else {
                        c as f64 / total as f64
                    }
                })
                .collect()
        })
        .collect();
    let mut heat = Heatmap {
        x: AxisTitle {
            title: "predicted".into(),
            unit: String::new(),
        },
        y: AxisTitle {
            title: "true class".into(),
            unit: String::new(),
        },
        columns: classes.to_vec(),
        rows: classes.to_vec(),
        values,
        colors: ColorScale::viridis("share of the true class", ""),
        annotate: true,
        marked: Vec::new(),
    };
    heat.colors.limits = Some([0.0, 1.0]);
    Figure::new(title, FigureKind::Heatmap(heat))
}

/// The share of each object's grasps decided right.
fn per_object(r: &HeldOutResult, held_out: &HeldOut) -> Figure {
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
    Figure::bars(
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
    .subtitle(held_out.text())
}
