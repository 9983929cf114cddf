//! Supervised and unsupervised OIESGP results as analysis results with the second paper's
//! figures: accuracy as trials progress (Fig. 6), the confusion matrix (Fig. 7), early
//! classification (Fig. 9), lengthscale relevance; purity, ARI and NMI against the novelty
//! threshold (Fig. 11), clusters and effective clusters (Fig. 12), NMI against effective
//! clusters with k-means and SOM (Fig. 13) and the scores at 10 effective clusters (Table IV).

use std::collections::BTreeMap;

use super::clustering::{ClusteringResult, ClusteringRun, EffectivePoint, UnsupervisedLearner};
use super::links::{GraspLinks, grasps_text};
use super::recognition::{MeanSd, RecognitionResult, SupervisedLearner};
use super::report::{AnalysisKind, AnalysisResult, FigureDetails, ModelSize, now_unix};
use crate::features::sequence::FeatureSet;
use crate::figures::{
    Axis, AxisTitle, BarGroup, ColorScale, ErrorDisplay, ErrorRange, Figure, FigureKind, Heatmap,
    Orientation, Series, SeriesStyle,
};

fn with_band(name: &str, x: Vec<f64>, stats: &[&MeanSd]) -> Series {
    let y = stats.iter().map(|s| s.mean).collect();
    let mut s = Series::new(name, x, y).style(SeriesStyle::LineMarkers);
    s.error = Some(ErrorRange {
        display: ErrorDisplay::Band,
        lower: stats.iter().map(|s| s.mean - s.sd).collect(),
        upper: stats.iter().map(|s| s.mean + s.sd).collect(),
    });
    s
}

/// The parameters every OIESGP result lists.
fn common_parameters(
    learner: &str,
    features: FeatureSet,
    reps: usize,
    seed: u64,
) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("learner".to_string(), learner.to_string()),
        ("features".to_string(), features_text(features).to_string()),
        ("repetitions".to_string(), reps.to_string()),
        ("seed".to_string(), seed.to_string()),
    ])
}

pub fn features_text(f: FeatureSet) -> &'static str {
    match f {
        FeatureSet::All => "all features",
        FeatureSet::Tactile => "tactile features",
        FeatureSet::Encoder => "encoder features",
    }
}

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
    let mut figures = Vec::new();

    let x: Vec<f64> = (1..=s.trial_sets.len()).map(|i| i as f64).collect();
    let stats: Vec<&MeanSd> = s.trial_sets.iter().collect();
    let test_from = (1.0 - p.test_fraction) * s.trial_sets.len() as f64 + 0.5;
    figures.push((
        "accuracy-by-trials".to_string(),
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
        .subtitle(format!("{label}; mean ± sd over {reps} seeded orders")),
    ));

    let n = r.classes.len();
    let mut confusion = vec![vec![0.0; n]; n];
    for (t, row) in s.confusion.iter().enumerate() {
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
    figures.push((
        "confusion".to_string(),
        Figure::new("Confusion matrix", FigureKind::Heatmap(heat))
            .subtitle(format!("{label}; every predicted grasp, {reps} orders")),
    ));

    if !s.early.is_empty() {
        let x: Vec<f64> = p
            .early_fractions
            .iter()
            .take(s.early.len())
            .copied()
            .collect();
        let stats: Vec<&MeanSd> = s.early.iter().collect();
        figures.push((
            "early-classification".to_string(),
            Figure::chart(
                "Early classification",
                Axis::new("share of the sequence seen", ""),
                Axis::new("accuracy on the final 20%", "").including(0.0, 1.0),
                vec![with_band(learner, x, &stats)],
            )
            .subtitle(label.clone()),
        ));
    }

    if !s.lengthscales.is_empty() && !r.feature_names.is_empty() {
        // Relevance = 1 / lengthscale: a short lengthscale means the class model's output
        // changes quickly with that feature.
        let values: Vec<Vec<f64>> = s
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
        figures.push((
            "lengthscales".to_string(),
            Figure::new(
                "Feature relevance from the learned lengthscales",
                FigureKind::Heatmap(heat),
            )
            .subtitle(format!("{label}; mean over {reps} orders")),
        ));
    }

    // Confusion cell [true, predicted] → its grasps over every repetition, the grasps
    // predicted so most often first.
    let class = |c: usize| r.classes.get(c).map_or("?", String::as_str);
    let confusion_links = GraspLinks::from_observations(
        "confusion",
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
    );

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
        links: vec![confusion_links],
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

fn effective_series(name: &str, points: &[EffectivePoint]) -> Series {
    let x: Vec<f64> = points.iter().map(|p| p.effective as f64).collect();
    let stats: Vec<&MeanSd> = points.iter().map(|p| &p.nmi).collect();
    with_band(name, x, &stats)
}

/// Scores, timings and figures of an unsupervised threshold sweep on `session`.
pub fn clustering_report(session: &str, r: &ClusteringResult) -> AnalysisResult {
    let p = &r.params;
    let learner = match p.learner {
        UnsupervisedLearner::Du => "DU",
        UnsupervisedLearner::Gu => "GU",
    };
    let mut label = format!("{learner}, {}", features_text(p.features));
    let min_grasps = match p.learner {
        UnsupervisedLearner::Du => p.du_min_grasps,
        UnsupervisedLearner::Gu => p.gu_min_grasps,
    };
    if p.learner == UnsupervisedLearner::Gu || min_grasps > 1 {
        label += &match min_grasps {
            1 => ", every cluster kept".to_string(),
            n => format!(", clusters kept from {n} grasps"),
        };
    }
    let th: Vec<f64> = r.sweep.iter().map(|s| s.threshold).collect();
    let reps = p.reps;
    let mut score_series = vec![
        with_band(
            "purity",
            th.clone(),
            &r.sweep.iter().map(|s| &s.purity).collect::<Vec<_>>(),
        ),
        with_band(
            "ARI",
            th.clone(),
            &r.sweep.iter().map(|s| &s.ari).collect::<Vec<_>>(),
        ),
        with_band(
            "NMI",
            th.clone(),
            &r.sweep.iter().map(|s| &s.nmi).collect::<Vec<_>>(),
        ),
    ];
    if let Some(c) = &r.threshold_choice {
        let agreement: Vec<MeanSd> = c
            .curve
            .iter()
            .map(|a| MeanSd {
                mean: a.agreement,
                sd: a.sd,
            })
            .collect();
        score_series.push(with_band(
            "agreement across orders (no labels)",
            c.curve.iter().map(|a| a.threshold).collect(),
            &agreement.iter().collect::<Vec<_>>(),
        ));
    }
    let mut figures = vec![
        (
            "scores-vs-threshold".to_string(),
            chosen_threshold(
                Figure::chart(
                    "Purity, ARI and NMI against the novelty threshold",
                    Axis::new("novelty threshold", ""),
                    Axis::new("score", "").including(0.0, 1.0),
                    score_series,
                )
                .subtitle(format!("{label}; mean ± sd over {reps} seeded orders")),
                r,
            ),
        ),
        (
            "clusters-vs-threshold".to_string(),
            chosen_threshold(
                Figure::chart(
                    "Clusters against the novelty threshold",
                    Axis::new("novelty threshold", ""),
                    Axis::new("number of clusters", ""),
                    vec![
                        with_band(
                            "clusters created",
                            th.clone(),
                            &r.sweep.iter().map(|s| &s.clusters).collect::<Vec<_>>(),
                        ),
                        with_band(
                            "effective clusters",
                            th.clone(),
                            &r.sweep.iter().map(|s| &s.effective).collect::<Vec<_>>(),
                        ),
                    ],
                )
                .subtitle(format!(
                    "{label}; effective = clusters used when every sample is re-assigned"
                )),
                r,
            ),
        ),
    ];
    let mut nmi = vec![effective_series(learner, &r.by_effective)];
    if !r.kmeans.is_empty() {
        nmi.push(effective_series("sequential k-means", &r.kmeans));
    }
    if !r.som.is_empty() {
        nmi.push(effective_series("SOM", &r.som));
    }
    figures.push((
        "nmi-vs-effective".to_string(),
        Figure::chart(
            "NMI against effective clusters",
            Axis::new("effective clusters", ""),
            Axis::new("normalised mutual information", ""),
            nmi,
        )
        .subtitle(format!(
            "{label} against k-means and SOM on the Table I features"
        )),
    ));
    let mut scores = Vec::new();
    let mut groups = Vec::new();
    for (name, point) in [
        (learner, &r.at_10),
        ("sequential k-means", &r.kmeans_at_10),
        ("SOM", &r.som_at_10),
    ] {
        if let Some(pt) = point {
            groups.push(
                BarGroup::new(name, vec![pt.purity.mean, pt.ari.mean, pt.nmi.mean]).errors(vec![
                    pt.purity.sd,
                    pt.ari.sd,
                    pt.nmi.sd,
                ]),
            );
            scores.push((format!("{name} purity at 10"), pt.purity.mean));
            scores.push((format!("{name} ARI at 10"), pt.ari.mean));
            scores.push((format!("{name} NMI at 10"), pt.nmi.mean));
        }
    }
    if !groups.is_empty() {
        figures.push((
            "scores-at-10".to_string(),
            Figure::bars(
                "Scores at 10 effective clusters",
                AxisTitle {
                    title: "score".into(),
                    unit: String::new(),
                },
                Axis::new("value", "").including(0.0, 1.0),
                vec!["purity".into(), "ARI".into(), "NMI".into()],
                groups,
            )
            .subtitle("runs whose re-assignment used 10 clusters; mean ± sd"),
        ));
    }
    let headline = r
        .at_10
        .as_ref()
        .map(|pt| (format!("{learner} NMI at 10"), pt.nmi.mean));
    let runs = r.runs.len().max(1) as f64;
    let mean_step_us = r.runs.iter().map(|x| x.learn_step_us).sum::<f64>() / runs;
    scores.push(("learning step (µs)".into(), mean_step_us));
    if let (Some(c), Some(at)) = (&r.threshold_choice, r.at_choice()) {
        scores.push(("threshold chosen without labels".into(), c.threshold));
        scores.push((
            "effective clusters at the label-free threshold".into(),
            at.effective.mean,
        ));
        scores.push(("NMI at the label-free threshold".into(), at.nmi.mean));
    }
    let mut parameters = common_parameters(learner, p.features, reps, p.seed);
    parameters.extend([(
        "thresholds".to_string(),
        format!(
            "{} from {:.2} to {:.2}",
            th.len(),
            th.first().unwrap_or(&0.0),
            th.last().unwrap_or(&0.0)
        ),
    )]);
    parameters.insert("grasps to keep a cluster".into(), min_grasps.to_string());
    let (details, links) = clustering_details(r);
    AnalysisResult {
        kind: AnalysisKind::Clustering,
        label,
        session: session.to_string(),
        parameters,
        scores,
        headline,
        train_seconds: r.wall_seconds / (r.sweep.len().max(1) * reps.max(1)) as f64,
        predict_seconds_per_sample: None,
        created: now_unix(),
        figures,
        details,
        links,
        grasp_codes: Vec::new(),
        model_size: None,
    }
}

/// `f` with the threshold chosen without labels marked, if one was chosen.
fn chosen_threshold(f: Figure, r: &ClusteringResult) -> Figure {
    match &r.threshold_choice {
        Some(c) => f.ref_line(
            Orientation::Vertical,
            c.threshold,
            format!(
                "chosen without labels: {} ({})",
                c.threshold,
                c.criterion.text()
            ),
        ),
        None => f,
    }
}

/// The clustering of the first order at every threshold, selected by the threshold marker
/// on Fig. 11: true classes against clusters, counted in grasps; with the grasps behind
/// each cell.
fn clustering_details(r: &ClusteringResult) -> (Vec<FigureDetails>, Vec<GraspLinks>) {
    let figure = "scores-vs-threshold";
    let (items, links): (Vec<(f64, Figure)>, Vec<GraspLinks>) = r
        .runs
        .iter()
        .filter_map(|run| {
            let a = run.assignment.as_ref()?;
            (a.len() == r.labels.len() && !a.is_empty()).then_some((run, a))
        })
        .enumerate()
        .map(|(i, (run, a))| {
            let (f, links) = contingency(r, run, a, figure, i);
            ((run.threshold, f), links)
        })
        .unzip();
    if items.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let details = vec![FigureDetails {
        figure: figure.into(),
        selector: "novelty threshold".into(),
        items,
    }];
    (details, links)
}

fn contingency_row(r: &ClusteringResult, l: usize) -> String {
    r.class_names
        .get(l)
        .cloned()
        .unwrap_or_else(|| format!("class {}", l + 1))
}

/// The class × cluster contingency of one run's assignment (session order), and its links
/// as item `detail` of figure `name`'s details: every grasp in its class's row and its
/// cluster's column.
fn contingency(
    r: &ClusteringResult,
    run: &ClusteringRun,
    assignment: &[usize],
    name: &str,
    detail: usize,
) -> (Figure, GraspLinks) {
    let classes = r
        .class_names
        .len()
        .max(r.labels.iter().max().map_or(0, |m| m + 1));
    let mut clusters: Vec<usize> = assignment.to_vec();
    clusters.sort_unstable();
    clusters.dedup();
    let mut counts = vec![vec![0.0_f64; clusters.len()]; classes];
    for (&l, a) in r.labels.iter().zip(assignment) {
        if let Ok(c) = clusters.binary_search(a) {
            counts[l][c] += 1.0;
        }
    }
    // Order the clusters by their majority class, so a good clustering reads as a diagonal.
    let majority = |c: usize| {
        (0..classes)
            .max_by(|&x, &y| counts[x][c].total_cmp(&counts[y][c]).then(y.cmp(&x)))
            .unwrap_or(0)
    };
    let mut order: Vec<usize> = (0..clusters.len()).collect();
    order.sort_by_key(|&c| (majority(c), clusters[c]));
    let values: Vec<Vec<f64>> = counts
        .iter()
        .map(|row| order.iter().map(|&c| row[c]).collect())
        .collect();
    let mut column_of = vec![0; clusters.len()];
    for (j, &c) in order.iter().enumerate() {
        column_of[c] = j;
    }
    let cells = r
        .labels
        .iter()
        .zip(assignment)
        .enumerate()
        .filter_map(|(g, (&l, a))| {
            let c = clusters.binary_search(a).ok()?;
            Some(([l, column_of[c]], g))
        });
    let links = GraspLinks::from_observations(name, Some(detail), cells, |[l, j], grasps, _| {
        format!(
            "{} in cluster {}: {}",
            contingency_row(r, l),
            clusters[order[j]] + 1,
            grasps_text(grasps)
        )
    });
    let rows = (0..classes).map(|l| contingency_row(r, l)).collect();
    let figure = Figure::new(
        format!("Clustering at novelty threshold {}", run.threshold),
        FigureKind::Heatmap(Heatmap {
            x: AxisTitle {
                title: "cluster (by creation)".into(),
                unit: String::new(),
            },
            y: AxisTitle {
                title: "true class".into(),
                unit: String::new(),
            },
            columns: order
                .iter()
                .map(|&c| (clusters[c] + 1).to_string())
                .collect(),
            rows,
            values,
            colors: ColorScale::viridis("grasps", ""),
            annotate: true,
            marked: Vec::new(),
        }),
    )
    .subtitle(format!(
        "first order: {} clusters created, {} effective; purity {:.3}, ARI {:.3}, NMI {:.3}",
        run.clusters, run.effective, run.purity, run.ari, run.nmi
    ));
    (figure, links)
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
        let Some((_, f)) = r.figures.iter().find(|(n, _)| n == "accuracy-by-trials") else {
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
            kind,
            label: label.into(),
            session: session.into(),
            parameters: BTreeMap::new(),
            scores: vec![("SVM accuracy".into(), 0.97)],
            headline: None,
            train_seconds: 1.0,
            predict_seconds_per_sample: None,
            created: 0,
            figures: vec![("accuracy-by-trials".into(), curve)],
            details: Vec::new(),
            links: Vec::new(),
            grasp_codes: Vec::new(),
            model_size: None,
        }
    }

    #[test]
    fn contingency_links_follow_the_clusters_reordered_by_majority_class() {
        use crate::experiments::clustering::ClusteringParams;
        // Cluster 0 holds class 1, cluster 1 class 2, cluster 2 class 0: the columns show
        // clusters 3, 1, 2.
        let labels = vec![0, 1, 1, 2, 0, 2, 0];
        let assignment = vec![2, 0, 0, 1, 2, 1, 0];
        let run = ClusteringRun {
            threshold: 0.5,
            rep: 0,
            clusters: 3,
            effective: 3,
            purity: 0.0,
            ari: 0.0,
            nmi: 0.0,
            learn_step_us: 0.0,
            assign_step_us: 0.0,
            assignment: Some(assignment.clone()),
        };
        let r = ClusteringResult {
            params: ClusteringParams::default(),
            runs: vec![run],
            sweep: Vec::new(),
            by_effective: Vec::new(),
            kmeans: Vec::new(),
            som: Vec::new(),
            at_10: None,
            kmeans_at_10: None,
            som_at_10: None,
            som_setup: Default::default(),
            wall_seconds: 0.0,
            threshold_choice: None,
            labels: labels.clone(),
            class_names: vec!["a".into(), "b".into(), "c".into()],
        };
        let (details, links) = clustering_details(&r);
        let FigureKind::Heatmap(h) = &details[0].items[0].1.kind else {
            panic!("a heatmap");
        };
        assert_eq!(h.columns, ["3", "1", "2"]);
        let l = &links[0];
        assert_eq!(
            (l.figure.as_str(), l.detail),
            ("scores-vs-threshold", Some(0))
        );
        let mut all: Vec<usize> = Vec::new();
        for item in &l.items {
            let [row, col] = item.at;
            assert_eq!(item.grasps.len() as f64, h.values[row][col]);
            for &g in &item.grasps {
                assert_eq!(labels[g], row);
                assert_eq!((assignment[g] + 1).to_string(), h.columns[col]);
            }
            all.extend(&item.grasps);
        }
        all.sort_unstable();
        assert_eq!(all, (0..labels.len()).collect::<Vec<_>>());
        assert_eq!(l.item([0, 1]).unwrap().text, "a in cluster 1: 1 grasp");
        assert_eq!(l.item([0, 0]).unwrap().grasps, vec![0, 4]);
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
