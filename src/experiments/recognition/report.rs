//! Supervised OIESGP results as analysis results with the second paper's figures: accuracy
//! as trials progress (Fig. 6), the confusion matrix (Fig. 7), early classification (Fig. 9),
//! lengthscale relevance; and the comparison of a session's models on one accuracy chart.

use super::{RecognitionResult, SupervisedLearner};
use crate::experiments::figure_id::FigureId;
use crate::experiments::links::{GraspLinks, grasps_text};
use crate::experiments::result::{
    AnalysisKind, AnalysisResult, MeanSd, ModelSize, common_parameters, features_text, now_unix,
    with_band,
};
use crate::figures::{Axis, AxisTitle, ColorScale, Figure, FigureKind, Heatmap, Orientation};

/// Scores, timings and figures of a supervised run on `session`.
pub fn recognition_report(session: &str, r: &RecognitionResult) -> AnalysisResult {
    let p = &r.params;
    let learner = match p.learner {
        SupervisedLearner::Ds => "DS",
        SupervisedLearner::Gs => "GS",
    };
    let noise = if p.taxel_noise_variance > 0.0 {
        format!(", noise σ² = {}", p.taxel_noise_variance)
    } else {
        String::new()
    };
    let label = format!("{learner}, {}{noise}", features_text(p.features));
    let s = &r.summary;
    let reps = r.repetitions.len();
    let mut figures = vec![
        (
            FigureId::AccuracyByTrials,
            accuracy_by_trials(r, learner, &label),
        ),
        (FigureId::Confusion, confusion_matrix(r, &label)),
    ];
    if !s.early.is_empty() {
        figures.push((
            FigureId::EarlyClassification,
            early_classification(r, learner, &label),
        ));
    }
    if !s.lengthscales.is_empty() && !r.feature_names.is_empty() {
        figures.push((FigureId::Lengthscales, lengthscale_relevance(r, &label)));
    }

    let mean_train: f64 =
        r.repetitions.iter().map(|x| x.train_seconds).sum::<f64>() / reps.max(1) as f64;
    let mut parameters = common_parameters(learner, p.features, reps, p.seed);
    parameters.extend([
        (
            "taxel noise variance".to_string(),
            p.taxel_noise_variance.to_string(),
        ),
        ("test fraction".to_string(), p.test_fraction.to_string()),
    ]);
    AnalysisResult {
        held_out: None,
        methods: vec![p.learner.method()],
        kind: AnalysisKind::Recognition,
        label,
        session: session.to_string(),
        parameters,
        scores: vec![
            ("accuracy (all)".into(), s.all.mean),
            ("accuracy (all) sd".into(), s.all.sd),
            ("accuracy (final 20%)".into(), s.final_20.mean),
            ("accuracy (final 20%) sd".into(), s.final_20.sd),
            ("prediction step (µs)".into(), s.predict_step_us),
            ("training step (µs)".into(), s.train_step_us),
        ],
        headline: Some(("accuracy (final 20%)".into(), s.final_20.mean)),
        train_seconds: mean_train,
        predict_seconds_per_sample: Some(s.predict_step_us * 1e-6),
        created: now_unix(),
        figures,
        details: Vec::new(),
        links: vec![confusion_links(r)],
        grasp_codes: Vec::new(),
        model_size: Some(ModelSize {
            knobs: {
                let gp = match p.learner {
                    SupervisedLearner::Ds => &p.ds.gp,
                    SupervisedLearner::Gs => &p.gs.gp,
                };
                format!("capacity {}, tau {}", gp.capacity, gp.tau)
            },
            reason: p.size_reason,
        }),
    }
}

/// Accuracy per set of trials, mean ± sd over the orders (Fig. 6).
fn accuracy_by_trials(r: &RecognitionResult, learner: &str, label: &str) -> Figure {
    let (p, s) = (&r.params, &r.summary);
    let x: Vec<f64> = (1..=s.trial_sets.len()).map(|i| i as f64).collect();
    let stats: Vec<&MeanSd> = s.trial_sets.iter().collect();
    let test_from = (1.0 - p.test_fraction) * s.trial_sets.len() as f64 + 0.5;
    Figure::chart(
        "Accuracy as trials progress",
        Axis::new(
            format!("set of trials (order cut into {} parts)", p.trial_sets),
            "",
        ),
        Axis::new("accuracy", "").including(0.0, 1.0),
        vec![with_band(learner, x, &stats)],
    )
    .ref_line(Orientation::Vertical, test_from, "test only from here")
    .subtitle(format!(
        "{label}; mean ± sd over {} seeded orders",
        r.repetitions.len()
    ))
}

/// The share of each true class predicted as each class, over every order (Fig. 7).
fn confusion_matrix(r: &RecognitionResult, label: &str) -> Figure {
    let n = r.classes.len();
    let mut confusion = vec![vec![0.0; n]; n];
    for (t, row) in r.summary.confusion.iter().enumerate() {
        let total: usize = row.iter().sum();
        for (c, &k) in row.iter().enumerate() {
            if t < n && c < n {
                confusion[t][c] = if total > 0 {
                    k as f64 / total as f64
                } else {
                    f64::NAN
                };
            }
        }
    }
    let mut heat = Heatmap {
        x: AxisTitle {
            title: "predicted class".into(),
            unit: String::new(),
        },
        y: AxisTitle {
            title: "true class".into(),
            unit: String::new(),
        },
        columns: r.classes.clone(),
        rows: r.classes.clone(),
        values: confusion,
        colors: ColorScale::viridis("share of the true class", ""),
        annotate: true,
        marked: Vec::new(),
    };
    heat.colors.limits = Some([0.0, 1.0]);
    Figure::new("Confusion matrix", FigureKind::Heatmap(heat)).subtitle(format!(
        "{label}; every predicted grasp, {} orders",
        r.repetitions.len()
    ))
}

/// Accuracy on the final 20% against the share of each sequence seen (Fig. 9).
fn early_classification(r: &RecognitionResult, learner: &str, label: &str) -> Figure {
    let s = &r.summary;
    let x: Vec<f64> = r
        .params
        .early_fractions
        .iter()
        .take(s.early.len())
        .copied()
        .collect();
    let stats: Vec<&MeanSd> = s.early.iter().collect();
    Figure::chart(
        "Early classification",
        Axis::new("share of the sequence seen", ""),
        Axis::new("accuracy on the final 20%", "").including(0.0, 1.0),
        vec![with_band(learner, x, &stats)],
    )
    .subtitle(label.to_string())
}

/// Each class model's relevance of each feature, from its mean learned lengthscales.
fn lengthscale_relevance(r: &RecognitionResult, label: &str) -> Figure {
    // Relevance = 1 / lengthscale: a short lengthscale means the class model's output
    // changes quickly with that feature.
    let values: Vec<Vec<f64>> = r
        .summary
        .lengthscales
        .iter()
        .map(|row| {
            row.iter()
                .map(|&l| if l > 0.0 { (1.0 / l).log10() } else { f64::NAN })
                .collect()
        })
        .collect();
    let heat = Heatmap {
        x: AxisTitle {
            title: "feature".into(),
            unit: String::new(),
        },
        y: AxisTitle {
            title: "class model".into(),
            unit: String::new(),
        },
        columns: r.feature_names.clone(),
        rows: r.classes.iter().take(values.len()).cloned().collect(),
        values,
        colors: ColorScale::viridis("relevance log10(1 / lengthscale)", ""),
        annotate: false,
        marked: Vec::new(),
    };
    Figure::new(
        "Feature relevance from the learned lengthscales",
        FigureKind::Heatmap(heat),
    )
    .subtitle(format!("{label}; mean over {} orders", r.repetitions.len()))
}

/// Confusion cell [true, predicted] → its grasps over every repetition, the grasps
/// predicted so most often first.
fn confusion_links(r: &RecognitionResult) -> GraspLinks {
    let n = r.classes.len();
    let class = |c: usize| r.classes.get(c).map_or("?", String::as_str);
    GraspLinks::from_observations(
        FigureId::Confusion,
        None,
        r.repetitions
            .iter()
            .flat_map(|rep| &rep.predictions)
            .filter(|x| x.truth < n && x.predicted < n)
            .map(|x| ([x.truth, x.predicted], x.grasp)),
        |[t, p], grasps, predictions| {
            format!(
                "true {}, predicted {}: {predictions} prediction{} of {}",
                class(t),
                class(p),
                if predictions == 1 { "" } else { "s" },
                grasps_text(grasps)
            )
        },
    )
}

/// Fig. 6 across models: the accuracy-as-trials-progress curve of every recognition result
/// on `session` in one chart, with the offline RBF SVM's cross-validated accuracy (from a
/// baselines result on the same session) as a reference line. None with fewer than two
/// curves and no baseline: the result's own chart already shows one curve.
pub fn accuracy_comparison(results: &[AnalysisResult], session: &str) -> Option<Figure> {
    let mine = || results.iter().filter(|r| r.session == session);
    let mut axes = None;
    let mut test_from = None;
    let mut series = Vec::new();
    for r in mine().filter(|r| r.kind == AnalysisKind::Recognition) {
        let Some(f) = r.figure(FigureId::AccuracyByTrials) else {
            continue;
        };
        let FigureKind::Chart(c) = &f.kind else {
            continue;
        };
        let Some(s) = c.series.first() else {
            continue;
        };
        // Curves are comparable only over the same cut of the order into sets of trials.
        let (x, _) = axes.get_or_insert_with(|| (c.x.clone(), c.y.clone()));
        if x.title != c.x.title {
            continue;
        }
        let vertical = c
            .ref_lines
            .iter()
            .find(|l| l.orientation == Orientation::Vertical);
        test_from = test_from.or(vertical.map(|l| l.value));
        let mut s = s.clone();
        s.name = r.label.clone();
        s.error = None;
        s.color = None;
        series.push(s);
    }
    let svm = mine()
        .filter(|r| r.kind == AnalysisKind::Baselines)
        .find_map(|r| r.score("SVM accuracy"));
    let (x, y) = axes?;
    if series.len() < 2 && svm.is_none() {
        return None;
    }
    let mut f = Figure::chart("Accuracy as trials progress, compared", x, y, series).subtitle(
        format!("every recognition result on {session}; mean over orders"),
    );
    if let Some(t) = test_from {
        f = f.ref_line(Orientation::Vertical, t, "test only from here");
    }
    if let Some(a) = svm {
        f = f.ref_line(
            Orientation::Horizontal,
            a,
            format!("offline RBF SVM (cross-validated) {a:.3}"),
        );
    }
    Some(f)
}

/// The cross-model comparisons of every session among `results`, named for export.
pub fn comparison_figures(results: &[AnalysisResult]) -> Vec<(String, Figure)> {
    let mut sessions: Vec<&str> = results.iter().map(|r| r.session.as_str()).collect();
    sessions.sort_unstable();
    sessions.dedup();
    sessions
        .into_iter()
        .filter_map(|s| {
            let slug: String = s
                .chars()
                .map(|c| {
                    if c.is_alphanumeric() {
                        c.to_ascii_lowercase()
                    } else {
                        '-'
                    }
                })
                .collect();
            Some((
                format!("accuracy-compared-{slug}"),
                accuracy_comparison(results, s)?,
            ))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn result(kind: AnalysisKind, label: &str, session: &str) -> AnalysisResult {
        let curve = Figure::chart(
            "Accuracy as trials progress",
            Axis::new("set of trials (order cut into 10 parts)", ""),
            Axis::new("accuracy", ""),
            vec![with_band(
                "DS",
                vec![1.0, 2.0],
                &[
                    &MeanSd { mean: 0.5, sd: 0.1 },
                    &MeanSd { mean: 0.9, sd: 0.0 },
                ],
            )],
        )
        .ref_line(Orientation::Vertical, 8.5, "test only from here");
        AnalysisResult {
            held_out: None,
            methods: Vec::new(),
            kind,
            label: label.into(),
            session: session.into(),
            parameters: BTreeMap::new(),
            scores: vec![("SVM accuracy".into(), 0.97)],
            headline: None,
            train_seconds: 1.0,
            predict_seconds_per_sample: None,
            created: 0,
            figures: vec![(FigureId::AccuracyByTrials, curve)],
            details: Vec::new(),
            links: Vec::new(),
            grasp_codes: Vec::new(),
            model_size: None,
        }
    }

    #[test]
    fn the_comparison_overlays_a_sessions_models_and_the_offline_svm() {
        let ds = result(AnalysisKind::Recognition, "DS, all features", "a");
        let gs = result(AnalysisKind::Recognition, "GS, all features", "a");
        let other = result(AnalysisKind::Recognition, "GS, all features", "b");
        let svm = result(AnalysisKind::Baselines, "baselines", "a");
        assert!(accuracy_comparison(&[ds.clone(), other.clone()], "a").is_none());
        let f = accuracy_comparison(&[ds.clone(), gs, other.clone(), svm], "a").unwrap();
        let FigureKind::Chart(c) = &f.kind else {
            panic!("a chart");
        };
        let names: Vec<&str> = c.series.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["DS, all features", "GS, all features"]);
        assert!(c.series.iter().all(|s| s.error.is_none()));
        assert_eq!(c.ref_lines.len(), 2);
        assert_eq!(c.ref_lines[1].value, 0.97);
        assert!(f.validate().is_ok());
        let named = comparison_figures(&[ds, other]);
        assert!(
            named.is_empty(),
            "one curve per session is not a comparison"
        );
    }
}
