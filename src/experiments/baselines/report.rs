//! The offline baselines (sequential k-means, SOM, RBF SVM on the Table I features) as an
//! analysis result with its figures: NMI against effective clusters (the baselines of the
//! second paper's Fig. 13), the scores at k clusters (Table IV) and the SVM's C × γ map.

use crate::catalogue::MethodId;
use crate::cluster::{KMEANS_NAME, SOM_NAME};
use crate::experiments::figure_id::FigureId;
use std::collections::BTreeMap;

use super::{BaselinesResult, ScoreSummary};
use crate::experiments::result::{AnalysisKind, AnalysisResult, distinct_sorted, now_unix};
use crate::figures::{
    Axis, AxisTitle, BarGroup, ColorScale, ErrorDisplay, ErrorRange, Figure, FigureKind, Heatmap,
    Series, SeriesStyle,
};

fn nmi_series(name: &str, points: &[(f64, &ScoreSummary)]) -> Series {
    let x: Vec<f64> = points
        .iter()
        .map(|(_, s)| s.effective_clusters_mean)
        .collect();
    let y: Vec<f64> = points.iter().map(|(_, s)| s.mean.nmi).collect();
    let lo: Vec<f64> = points.iter().map(|(_, s)| s.mean.nmi - s.sd.nmi).collect();
    let hi: Vec<f64> = points.iter().map(|(_, s)| s.mean.nmi + s.sd.nmi).collect();
    let mut s = Series::new(name, x, y).style(SeriesStyle::LineMarkers);
    s.error = Some(ErrorRange {
        display: ErrorDisplay::Band,
        lower: lo,
        upper: hi,
    });
    s
}

/// Scores, timings and figures of a baselines run on `session`.
pub fn baselines_report(session: &str, r: &BaselinesResult, train_seconds: f64) -> AnalysisResult {
    let k = r.params.k;
    let mut figures = Vec::new();
    if !r.sweep.is_empty() {
        let km: Vec<(f64, &ScoreSummary)> =
            r.sweep.iter().map(|p| (p.k as f64, &p.kmeans)).collect();
        let som: Vec<(f64, &ScoreSummary)> = r.sweep.iter().map(|p| (p.k as f64, &p.som)).collect();
        figures.push((
            FigureId::NmiVsClusters,
            Figure::chart(
                "NMI against effective clusters",
                Axis::new("effective clusters", ""),
                Axis::new("normalised mutual information", ""),
                vec![nmi_series(KMEANS_NAME, &km), nmi_series(SOM_NAME, &som)],
            )
            .subtitle(format!(
                "Table I features, {} orders each; band: ± 1 sd",
                r.params.orders
            )),
        ));
    }
    let bars = |s: &ScoreSummary, name: &str| {
        BarGroup::new(name, vec![s.mean.purity, s.mean.ari, s.mean.nmi]).errors(vec![
            s.sd.purity,
            s.sd.ari,
            s.sd.nmi,
        ])
    };
    figures.push((
        FigureId::Scores,
        Figure::bars(
            format!("Clustering scores at k = {k}"),
            AxisTitle {
                title: "score".into(),
                unit: String::new(),
            },
            Axis::new("value", "").including(0.0, 1.0),
            vec!["purity".into(), "ARI".into(), "NMI".into()],
            vec![bars(&r.kmeans, KMEANS_NAME), bars(&r.som, SOM_NAME)],
        )
        .subtitle(format!("mean ± sd over {} seeded orders", r.params.orders)),
    ));
    let mut scores = vec![
        ("k-means purity".to_string(), r.kmeans.mean.purity),
        ("k-means ARI".to_string(), r.kmeans.mean.ari),
        ("k-means NMI".to_string(), r.kmeans.mean.nmi),
        ("SOM purity".to_string(), r.som.mean.purity),
        ("SOM ARI".to_string(), r.som.mean.ari),
        ("SOM NMI".to_string(), r.som.mean.nmi),
    ];
    let mut headline = Some(("k-means NMI".to_string(), r.kmeans.mean.nmi));
    if let Some(svm) = &r.svm {
        let cs: Vec<f64> = distinct_sorted(svm.grid.iter().map(|c| c.c));
        let gs: Vec<f64> = distinct_sorted(svm.grid.iter().map(|c| c.gamma));
        let mut values = vec![vec![f64::NAN; gs.len()]; cs.len()];
        let mut marked = Vec::new();
        for cell in &svm.grid {
            let (Some(i), Some(j)) = (
                cs.iter().position(|&c| c == cell.c),
                gs.iter().position(|&g| g == cell.gamma),
            ) else {
                continue;
            };
            values[i][j] = cell.accuracy_mean;
            if cell.c == svm.best.c && cell.gamma == svm.best.gamma {
                marked.push([i, j]);
            }
        }
        let mut heat = Heatmap {
            x: AxisTitle {
                title: "RBF width γ".into(),
                unit: String::new(),
            },
            y: AxisTitle {
                title: "C".into(),
                unit: String::new(),
            },
            columns: gs.iter().map(|g| format!("{g}")).collect(),
            rows: cs.iter().map(|c| format!("{c}")).collect(),
            values,
            colors: ColorScale::viridis("accuracy", ""),
            annotate: true,
            marked,
        };
        heat.colors.limits = None;
        figures.push((
            FigureId::SvmGrid,
            Figure::new("RBF SVM accuracy over C × γ", FigureKind::Heatmap(heat)).subtitle(
                format!(
                    "{}-fold CV × {} repeats; best marked (chosen on the same folds: optimistic)",
                    svm.folds, svm.repeats
                ),
            ),
        ));
        scores.push(("SVM accuracy".to_string(), svm.best.accuracy_mean));
        headline = Some(("SVM accuracy".to_string(), svm.best.accuracy_mean));
    }
    let parameters = BTreeMap::from([
        ("k".to_string(), k.to_string()),
        ("orders".to_string(), r.params.orders.to_string()),
        ("seed".to_string(), r.params.seed.to_string()),
        ("features".to_string(), format!("Table I ({})", r.features)),
        (
            "normalisation".to_string(),
            format!("{:?}", r.params.normalisation),
        ),
    ]);
    AnalysisResult {
        held_out: None,
        methods: [MethodId::KMeans, MethodId::Som]
            .into_iter()
            .chain(r.svm.as_ref().map(|_| MethodId::RbfSvm))
            .collect(),
        kind: AnalysisKind::Baselines,
        label: format!("baselines, k = {k}"),
        session: session.to_string(),
        parameters,
        scores,
        headline,
        train_seconds,
        predict_seconds_per_sample: None,
        created: now_unix(),
        figures,
        details: Vec::new(),
        links: Vec::new(),
        grasp_codes: Vec::new(),
        model_size: None,
    }
}
