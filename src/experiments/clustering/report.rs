//! Unsupervised OIESGP results as analysis results with the second paper's figures: purity,
//! ARI and NMI against the novelty threshold (Fig. 11), clusters and effective clusters
//! (Fig. 12), NMI against effective clusters with k-means and SOM (Fig. 13) and the scores
//! at 10 effective clusters (Table IV).

use super::{ClusteringResult, ClusteringRun, EffectivePoint, UnsupervisedLearner};
use crate::cluster::order_agreement::CHOSEN_THRESHOLD;
use crate::cluster::{KMEANS_NAME, SOM_NAME};
use crate::experiments::figure_id::FigureId;
use crate::experiments::links::{GraspLinks, grasps_text};
use crate::experiments::result::{
    AnalysisKind, AnalysisResult, FigureDetails, MeanSd, common_parameters, features_text,
    now_unix, with_band,
};
use crate::figures::{
    Axis, AxisTitle, BarGroup, ColorScale, Figure, FigureKind, Heatmap, Orientation, Series,
};

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
    let min_grasps = match p.learner {
        UnsupervisedLearner::Du => p.du_min_grasps,
        UnsupervisedLearner::Gu => p.gu_min_grasps,
    };
    let label = clustering_label(r, learner, min_grasps);
    let th: Vec<f64> = r.sweep.iter().map(|s| s.threshold).collect();
    let reps = p.reps;
    let mut figures = vec![
        (
            FigureId::ScoresVsThreshold,
            scores_vs_threshold(r, &th, &label),
        ),
        (
            FigureId::ClustersVsThreshold,
            clusters_vs_threshold(r, &th, &label),
        ),
        (
            FigureId::NmiVsEffective,
            nmi_vs_effective(r, learner, &label),
        ),
    ];
    let (at_10, mut scores) = scores_at_10(r, learner);
    figures.extend(at_10.map(|f| (FigureId::ScoresAt10, f)));
    let headline = r
        .at_10
        .as_ref()
        .map(|pt| (format!("{learner} NMI at 10"), pt.nmi.mean));
    let runs = r.runs.len().max(1) as f64;
    let mean_step_us = r.runs.iter().map(|x| x.learn_step_us).sum::<f64>() / runs;
    scores.push(("learning step (µs)".into(), mean_step_us));
    if let (Some(c), Some(at)) = (&r.threshold_choice, r.at_choice()) {
        scores.push((CHOSEN_THRESHOLD.into(), c.threshold));
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
        held_out: None,
        methods: vec![r.params.learner.method()],
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

/// The learner and features, and how many grasps keep a cluster when that is not every
/// cluster of DU.
fn clustering_label(r: &ClusteringResult, learner: &str, min_grasps: usize) -> String {
    let mut label = format!("{learner}, {}", features_text(r.params.features));
    if r.params.learner == UnsupervisedLearner::Gu || min_grasps > 1 {
        label += &match min_grasps {
            1 => ", every cluster kept".to_string(),
            n => format!(", clusters kept from {n} grasps"),
        };
    }
    label
}

/// Purity, ARI and NMI against the threshold (Fig. 11), with the label-free agreement
/// curve when a threshold was chosen without labels.
fn scores_vs_threshold(r: &ClusteringResult, th: &[f64], label: &str) -> Figure {
    let mut score_series = vec![
        with_band(
            "purity",
            th.to_vec(),
            &r.sweep.iter().map(|s| &s.purity).collect::<Vec<_>>(),
        ),
        with_band(
            "ARI",
            th.to_vec(),
            &r.sweep.iter().map(|s| &s.ari).collect::<Vec<_>>(),
        ),
        with_band(
            "NMI",
            th.to_vec(),
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
    chosen_threshold(
        Figure::chart(
            "Purity, ARI and NMI against the novelty threshold",
            Axis::new("novelty threshold", ""),
            Axis::new("score", "").including(0.0, 1.0),
            score_series,
        )
        .subtitle(format!(
            "{label}; mean ± sd over {} seeded orders",
            r.params.reps
        )),
        r,
    )
}

/// Clusters created and effective clusters against the threshold (Fig. 12).
fn clusters_vs_threshold(r: &ClusteringResult, th: &[f64], label: &str) -> Figure {
    chosen_threshold(
        Figure::chart(
            "Clusters against the novelty threshold",
            Axis::new("novelty threshold", ""),
            Axis::new("number of clusters", ""),
            vec![
                with_band(
                    "clusters created",
                    th.to_vec(),
                    &r.sweep.iter().map(|s| &s.clusters).collect::<Vec<_>>(),
                ),
                with_band(
                    "effective clusters",
                    th.to_vec(),
                    &r.sweep.iter().map(|s| &s.effective).collect::<Vec<_>>(),
                ),
            ],
        )
        .subtitle(format!(
            "{label}; effective = clusters used when every sample is re-assigned"
        )),
        r,
    )
}

/// NMI against effective clusters, beside sequential k-means and the SOM (Fig. 13).
fn nmi_vs_effective(r: &ClusteringResult, learner: &str, label: &str) -> Figure {
    let mut nmi = vec![effective_series(learner, &r.by_effective)];
    if !r.kmeans.is_empty() {
        nmi.push(effective_series(KMEANS_NAME, &r.kmeans));
    }
    if !r.som.is_empty() {
        nmi.push(effective_series(SOM_NAME, &r.som));
    }
    Figure::chart(
        "NMI against effective clusters",
        Axis::new("effective clusters", ""),
        Axis::new("normalised mutual information", ""),
        nmi,
    )
    .subtitle(format!(
        "{label} against k-means and SOM on the Table I features"
    ))
}

/// The scores at 10 effective clusters of the learner, k-means and the SOM (Table IV): their
/// bars (None when no run used 10 clusters) and their named values.
fn scores_at_10(r: &ClusteringResult, learner: &str) -> (Option<Figure>, Vec<(String, f64)>) {
    let mut scores = Vec::new();
    let mut groups = Vec::new();
    for (name, point) in [
        (learner, &r.at_10),
        (KMEANS_NAME, &r.kmeans_at_10),
        (SOM_NAME, &r.som_at_10),
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
    let figure = (!groups.is_empty()).then(|| {
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
        .subtitle("runs whose re-assignment used 10 clusters; mean ± sd")
    });
    (figure, scores)
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
    let figure = FigureId::ScoresVsThreshold;
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
        figure,
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
    name: FigureId,
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

#[cfg(test)]
mod tests {
    use super::*;

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
            features_used: None,
            feature_choice: None,
        };
        let (details, links) = clustering_details(&r);
        let FigureKind::Heatmap(h) = &details[0].items[0].1.kind else {
            panic!("a heatmap");
        };
        assert_eq!(h.columns, ["3", "1", "2"]);
        let l = &links[0];
        assert_eq!((l.figure, l.detail), (FigureId::ScoresVsThreshold, Some(0)));
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
}
