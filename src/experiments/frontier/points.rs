//! What every method's points share: a point from its repetitions' scores and times.

use super::*;

/// A point from its repetitions' scores and times.
pub(super) fn point(
    label: String,
    detail: String,
    knobs: Vec<(&str, f64)>,
    scores: &[f64],
    train_us: Vec<f64>,
    predict_us: Vec<f64>,
) -> FrontierPoint {
    let (score, score_se) = mean_se(scores);
    FrontierPoint {
        label,
        detail,
        knobs: knobs.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        score,
        score_se,
        reps: scores.len(),
        train_us: median(train_us),
        predict_us: median(predict_us),
    }
}

pub(super) fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}
