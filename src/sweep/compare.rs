//! Two results compared with their timings aside: a merged sweep against the
//! single-machine run.

use serde_json::Value;

/// Keys of timings (seconds, microseconds, thread counts) in the experiments' results:
/// they differ between any two runs of the same work.
pub const TIMING_KEYS: &[&str] = &[
    "secs",
    "dictionary_secs",
    "coding_secs",
    "cv_secs",
    "threads",
    "wall_seconds",
    "setup_seconds",
    "task_seconds",
    "cpu_seconds",
    "learn_step_us",
    "predict_seconds",
    "train_seconds",
    "predict_step_us",
    "train_step_us",
    "assign_step_us",
    "train_us",
    "predict_us",
];

/// Keys of a frontier (an object holding `points` and `recommended`) chosen by its times:
/// the cheapest size within one SE of the best, the Pareto fronts, and the best among
/// equal scores. Two runs of the same work may time near-equal sizes in another order.
pub const TIME_CHOSEN_KEYS: &[&str] = &[
    "best",
    "recommended",
    "pareto_training",
    "pareto_prediction",
];

/// The first difference between two results, timings aside (None: they are equal).
pub fn result_difference(a: &Value, b: &Value) -> Option<String> {
    fn walk(a: &Value, b: &Value, at: &str) -> Option<String> {
        match (a, b) {
            (Value::Object(x), Value::Object(y)) => {
                let frontier = x.contains_key("points") && x.contains_key("recommended");
                let skip = |k: &str| {
                    TIMING_KEYS.contains(&k) || (frontier && TIME_CHOSEN_KEYS.contains(&k))
                };
                for (k, va) in x {
                    if skip(k) {
                        continue;
                    }
                    let here = format!("{at}.{k}");
                    let diff = match y.get(k) {
                        Some(vb) => walk(va, vb, &here),
                        None => Some(format!("{here}: only in the first")),
                    };
                    if diff.is_some() {
                        return diff;
                    }
                }
                y.keys()
                    .find(|k| !x.contains_key(*k) && !skip(k))
                    .map(|k| format!("{at}.{k}: only in the second"))
            }
            (Value::Array(x), Value::Array(y)) => {
                if x.len() != y.len() {
                    return Some(format!("{at}: {} against {} entries", x.len(), y.len()));
                }
                x.iter()
                    .zip(y)
                    .enumerate()
                    .find_map(|(i, (va, vb))| walk(va, vb, &format!("{at}[{i}]")))
            }
            _ if a == b => None,
            _ => Some(format!("{at}: {a} against {b}")),
        }
    }
    walk(a, b, "")
}
