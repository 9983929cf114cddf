//! A robustness run as an analysis result: one chart per perturbation, each method's score
//! as a share of its clean score against the strength (band = ± 1 sd over repetitions,
//! the absolute score in the point labels and so in the CSV), the `fraction` line and
//! each method's break point as a vertical line.

use std::collections::BTreeMap;

use super::{Family, RobustnessResult, Scope, Sweep};
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::{AnalysisKind, AnalysisResult, now_unix};
use crate::figures::legibility::{decimals_for, value_text};
use crate::figures::{Axis, Figure, Orientation, Series, SeriesStyle};

fn scope_text(scope: Scope) -> &'static str {
    match scope {
        Scope::All => "applied to every grasp (training and test)",
        Scope::Test => "applied to the test grasps after training on clean ones",
        Scope::Training => "changes the training set; test grasps are clean",
    }
}

fn sweep_figure(r: &RobustnessResult, sweep: &Sweep) -> Option<Figure> {
    let p = sweep.perturbation;
    let (title, unit) = p.strength_title(r.params.family);
    let mut series = Vec::new();
    let mut breaks = Vec::new();
    let mut skipped = Vec::new();
    for clean in &r.clean {
        let Some(curve) = r.curve(clean.method, p) else {
            continue;
        };
        if let Some(why) = &curve.not_applicable {
            skipped.push(format!("{}: {why}", clean.method.title()));
            continue;
        }
        let c = clean.score.mean;
        let share = |v: f64| if c > 0.0 { v / c } else { f64::NAN };
        let mut x = Vec::new();
        let mut y = Vec::new();
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        let mut labels = Vec::new();
        if let Some(n) = p.neutral() {
            x.push(n);
            y.push(share(c));
            lo.push(share(c - clean.score.sd));
            hi.push(share(c + clean.score.sd));
            labels.push(format!("{c:.3}"));
        }
        for pt in &curve.points {
            x.push(pt.strength);
            y.push(share(pt.score.mean));
            lo.push(share(pt.score.mean - pt.score.sd));
            hi.push(share(pt.score.mean + pt.score.sd));
            labels.push(format!("{:.3}", pt.score.mean));
        }
        series.push(
            Series::new(clean.method.title(), x, y)
                .style(SeriesStyle::LineMarkers)
                .band(lo, hi)
                .labels(labels),
        );
        if let Some(b) = curve.break_point {
            breaks.push((clean.method.title(), b));
        }
    }
    if series.is_empty() {
        return None;
    }
    let measures: Vec<String> = r
        .clean
        .iter()
        .map(|c| format!("{} {}", c.method.title(), c.method.score_name()))
        .collect();
    let mut subtitle = format!(
        "{}; {} reps, band ± 1 sd; labels: absolute score ({})",
        scope_text(p.scope()),
        r.params.reps,
        measures.join(", ")
    );
    if !skipped.is_empty() {
        subtitle.push_str(&format!("; not applicable: {}", skipped.join("; ")));
    }
    let mut fig = Figure::chart(
        format!("Robustness to {}", p.key().replace('-', " ")),
        Axis::new(title, unit),
        Axis::new("score / clean score", "share").including(0.0, 1.0),
        series,
    )
    .subtitle(subtitle)
    .ref_line(
        Orientation::Horizontal,
        r.params.fraction,
        format!("{:.0} % of clean", 100.0 * r.params.fraction),
    );
    // Break points to the precision that tells them apart ("DS: 380", not "DS: 380.000").
    let decimals = decimals_for(&breaks.iter().map(|(_, b)| *b).collect::<Vec<_>>());
    for (method, b) in breaks {
        let text = format!("{method}: {}", value_text(b, decimals));
        fig = fig.ref_line(Orientation::Vertical, b, text);
    }
    Some(fig)
}

/// Scores, parameters and figures of a robustness run on `session`.
pub fn robustness_report(session: &str, r: &RobustnessResult) -> AnalysisResult {
    let family = match r.params.family {
        Family::Stability => "grasp stability",
        Family::Recognition => "object recognition",
    };
    let methods: Vec<&str> = r.clean.iter().map(|c| c.method.title()).collect();
    let label = format!("Robustness, {family} ({})", methods.join(", "));
    let figures = r
        .params
        .sweeps
        .iter()
        .filter_map(|sw| sweep_figure(r, sw).map(|f| (FigureId::Robustness(sw.perturbation), f)))
        .collect();
    let mut parameters = BTreeMap::new();
    parameters.insert("reps".to_string(), r.params.reps.to_string());
    parameters.insert("seed".to_string(), r.params.seed.to_string());
    parameters.insert("fraction".to_string(), r.params.fraction.to_string());
    parameters.insert("saturate".to_string(), r.params.saturate.to_string());
    match r.params.family {
        Family::Stability => {
            let st = &r.params.stability;
            parameters.insert("configuration".to_string(), st.config.to_string());
            parameters.insert("folds".to_string(), st.folds.to_string());
        }
        Family::Recognition => {
            let rc = &r.params.recognition;
            parameters.insert("features".to_string(), rc.features.name().to_string());
            parameters.insert("test fraction".to_string(), rc.test_fraction.to_string());
            parameters.insert("DU threshold".to_string(), rc.du_threshold.to_string());
            parameters.insert("GU threshold".to_string(), rc.gu_threshold.to_string());
            parameters.insert(
                "GU grasps to keep a cluster".to_string(),
                rc.gu_min_grasps.to_string(),
            );
        }
    }
    for sw in &r.params.sweeps {
        let list: Vec<String> = sw.strengths.iter().map(|s| s.to_string()).collect();
        parameters.insert(
            format!("strengths: {}", sw.perturbation.key()),
            list.join(", "),
        );
    }
    let mut scores = Vec::new();
    for c in &r.clean {
        scores.push((
            format!("{}: clean {}", c.method.title(), c.method.score_name()),
            c.score.mean,
        ));
    }
    for c in &r.curves {
        if let Some(b) = c.break_point {
            scores.push((
                format!("{}: {} break point", c.method.title(), c.perturbation.key()),
                b,
            ));
        }
    }
    AnalysisResult {
        held_out: None,
        // Perturbed copies of the methods, not a trained model.
        methods: Vec::new(),
        kind: AnalysisKind::Robustness,
        label,
        session: session.to_string(),
        parameters,
        scores,
        // Not a trained model: it stays off the speed-against-accuracy chart.
        headline: None,
        train_seconds: r.wall_seconds,
        predict_seconds_per_sample: None,
        created: now_unix(),
        figures,
        details: Vec::new(),
        links: Vec::new(),
        grasp_codes: Vec::new(),
        model_size: None,
    }
}
