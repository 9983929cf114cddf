//! Figures of speed–accuracy frontiers: score against time (log axis), one colour per
//! method, each size with its standard-error bar, each method's Pareto front as a line, and
//! the recommended and paper-default sizes marked with short labels; for the clusterers
//! also score against the effective clusters each size leaves.

use super::{CostAxis, Frontier};
use crate::figures::{Axis, Figure, Rgb, Series, SeriesStyle, series_color};

/// One chart per time axis (prediction first: it defines "cheapest" by default), and one
/// of score against effective clusters when a frontier is of a clusterer (DU, GU, k-means,
/// SOM), named for export; none without frontiers.
pub fn frontier_figures(frontiers: &[Frontier]) -> Vec<(String, Figure)> {
    if frontiers.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<(String, Figure)> = [
        (CostAxis::Prediction, "frontier-prediction"),
        (CostAxis::Training, "frontier-training"),
    ]
    .into_iter()
    .map(|(axis, name)| (name.to_string(), frontier_chart(frontiers, axis)))
    .collect();
    if let Some(chart) = clusters_chart(frontiers) {
        out.push(("frontier-clusters".into(), chart));
    }
    out
}

/// Score against the mean effective clusters of every size, for the frontiers that count
/// them (in the colours of the time charts); None when none does.
fn clusters_chart(frontiers: &[Frontier]) -> Option<Figure> {
    let mut series = Vec::new();
    let (mut rx, mut ry, mut rl) = (Vec::new(), Vec::new(), Vec::new());
    let mut names = Vec::new();
    for (i, f) in frontiers.iter().enumerate() {
        let Some(eff) = f
            .points
            .iter()
            .map(|p| p.knob("effective"))
            .collect::<Option<Vec<f64>>>()
        else {
            continue;
        };
        let name = f.short_label();
        // Joined in the order of the clusters they leave, so the line reads left to right.
        let mut order: Vec<usize> = (0..eff.len()).collect();
        order.sort_by(|&a, &b| eff[a].total_cmp(&eff[b]).then(a.cmp(&b)));
        let pts = |k: usize| &f.points[order[k]];
        series.push(
            Series::new(
                name.clone(),
                order.iter().map(|&k| eff[k]).collect(),
                (0..order.len()).map(|k| pts(k).score).collect(),
            )
            .style(SeriesStyle::LineMarkers)
            .error_bars(
                (0..order.len())
                    .map(|k| pts(k).score - pts(k).score_se)
                    .collect(),
                (0..order.len())
                    .map(|k| pts(k).score + pts(k).score_se)
                    .collect(),
            )
            .color(series_color(i)),
        );
        rx.push(eff[f.recommended]);
        ry.push(f.points[f.recommended].score);
        rl.push(format!("{name} · {}", f.points[f.recommended].label));
        names.push(name);
    }
    if series.is_empty() {
        return None;
    }
    series.push(
        Series::new("recommended", rx, ry)
            .style(SeriesStyle::Markers)
            .labels(rl)
            .color(Rgb(0, 0, 0)),
    );
    let mut scores: Vec<&str> = frontiers
        .iter()
        .filter(|f| f.points.iter().all(|p| p.knob("effective").is_some()))
        .map(|f| f.score_name.as_str())
        .collect();
    scores.dedup();
    Some(
        Figure::chart(
            "Score against effective clusters, by model size",
            Axis::new("effective clusters (mean over the orders)", ""),
            Axis::new(scores.join(" / "), ""),
            series,
        )
        .subtitle(format!(
            "{} on {}; mean ± SE over the orders; recommended: the cheapest within one SE of the best",
            names.join(", "),
            frontiers[0].session
        )),
    )
}

fn frontier_chart(frontiers: &[Frontier], axis: CostAxis) -> Figure {
    let mut units: Vec<&str> = frontiers.iter().map(|f| f.unit.as_str()).collect();
    units.dedup();
    let per = units.join(" or ");
    let (title, x) = match axis {
        CostAxis::Prediction => (
            "Score against prediction time, by model size",
            Axis::new(format!("prediction time per {per}"), "µs"),
        ),
        CostAxis::Training => (
            "Score against training time, by model size",
            Axis::new(format!("training time per {per}"), "µs"),
        ),
    };
    let mut scores: Vec<&str> = frontiers.iter().map(|f| f.score_name.as_str()).collect();
    scores.dedup();
    let mut series = Vec::new();
    let mut marked: [(Vec<f64>, Vec<f64>, Vec<String>); 2] = Default::default();
    for (i, f) in frontiers.iter().enumerate() {
        let color = series_color(i);
        let name = f.short_label();
        let x_of = |k: usize| f.points[k].cost(axis);
        let y_of = |k: usize| f.points[k].score;
        let all: Vec<usize> = (0..f.points.len()).collect();
        series.push(
            Series::new(
                name.clone(),
                all.iter().map(|&k| x_of(k)).collect(),
                all.iter().map(|&k| y_of(k)).collect(),
            )
            .style(SeriesStyle::Markers)
            .error_bars(
                f.points.iter().map(|p| p.score - p.score_se).collect(),
                f.points.iter().map(|p| p.score + p.score_se).collect(),
            )
            .color(color),
        );
        let front = match axis {
            CostAxis::Prediction => &f.pareto_prediction,
            CostAxis::Training => &f.pareto_training,
        };
        series.push(
            Series::new(
                format!("{name} Pareto front"),
                front.iter().map(|&k| x_of(k)).collect(),
                front.iter().map(|&k| y_of(k)).collect(),
            )
            .color(color)
            .part_of(name.clone()),
        );
        let rec = f.recommended;
        marked[0].0.push(x_of(rec));
        marked[0].1.push(y_of(rec));
        marked[0]
            .2
            .push(format!("{name} · {}", f.points[rec].label));
        if let Some(d) = f.paper_default.filter(|&d| d != rec) {
            marked[1].0.push(x_of(d));
            marked[1].1.push(y_of(d));
            marked[1].2.push(format!("paper · {}", f.points[d].label));
        }
    }
    let [(rx, ry, rl), (px, py, pl)] = marked;
    series.push(
        Series::new("recommended", rx, ry)
            .style(SeriesStyle::Markers)
            .labels(rl)
            .color(Rgb(0, 0, 0)),
    );
    if !px.is_empty() {
        series.push(
            Series::new("paper default", px, py)
                .style(SeriesStyle::Markers)
                .labels(pl)
                .color(Rgb(0x88, 0x88, 0x88)),
        );
    }
    // The subtitle speaks of the time on this chart's axis; the recommendation's own
    // criterion is named only where it is another time.
    let cheapest = match (axis, frontiers[0].params.cost) {
        (a, c) if a == c => "the cheapest".to_string(),
        (_, CostAxis::Prediction) => "the cheapest by prediction time (not shown)".to_string(),
        (_, CostAxis::Training) => "the cheapest by training time (not shown)".to_string(),
    };
    Figure::chart(title, x.log(), Axis::new(scores.join(" / "), ""), series).subtitle(format!(
        "{} on {}; mean ± SE over repetitions; recommended: {cheapest} within one SE of the best",
        frontiers
            .iter()
            .map(|f| f.short_label())
            .collect::<Vec<_>>()
            .join(", "),
        frontiers[0].session
    ))
}
