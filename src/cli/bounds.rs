//! Stated maxima of the size parameters given on the command line or in a sweep plan,
//! checked before anything is allocated for them: an absurd value is an error naming the
//! parameter and its limit, never an allocation that aborts the process.
//!
//! The limits lie far beyond the papers' settings (dictionaries of 2–60 bases, BV budgets
//! up to 100, lags up to 30, 50 repetitions) and well within memory: the largest square
//! matrix they allow (`num_bases` or a budget of 4096) takes 128 MB.

use anyhow::bail;

/// A sparse-coding dictionary size (its Gram matrix is `num_bases`²).
pub const MAX_NUM_BASES: usize = 4096;
/// A DS/GS/DU/GU expert's basis-vector budget (its kernel matrix is `capacity`²).
pub const MAX_CAPACITY: usize = 4096;
/// A recursive kernel's lags.
pub const MAX_TAU: usize = 1000;
/// Repetitions (seeded orders, folds or perturbations) and repeated timings.
pub const MAX_REPS: usize = 100_000;
/// Clusters (k-means centres, SOM units), folds and similar counts.
pub const MAX_K: usize = 100_000;

/// Checks one size parameter against its stated maximum.
pub fn at_most(name: &str, value: usize, max: usize) -> anyhow::Result<()> {
    if value > max {
        bail!("{name} {value} is above its limit of {max}");
    }
    Ok(())
}

/// Checks a count of clusters or units against the grasps that must fill them (each needs
/// at least one), naming the parameter and the session's size.
pub fn at_most_grasps(name: &str, values: &[usize], grasps: usize) -> anyhow::Result<()> {
    if let Some(k) = values.iter().find(|&&k| k > grasps) {
        bail!("{name} {k} is above the session's {grasps} grasps (each cluster needs one)");
    }
    Ok(())
}

/// Checks every value of a list parameter.
pub fn all_at_most(name: &str, values: &[usize], max: usize) -> anyhow::Result<()> {
    values.iter().try_for_each(|&v| at_most(name, v, max))
}

/// The size parameters a sweep plan may hold, by JSON key, with their maxima.
const PLAN_KEYS: &[(&str, usize)] = &[
    ("num_bases", MAX_NUM_BASES),
    ("capacity", MAX_CAPACITY),
    ("capacities", MAX_CAPACITY),
    ("budget", MAX_CAPACITY),
    ("tau", MAX_TAU),
    ("taus", MAX_TAU),
    ("reps", MAX_REPS),
    ("k", MAX_K),
    ("ks", MAX_K),
];

/// Checks every size parameter of a sweep plan's JSON (its experiment and items) against
/// its maximum, naming the path of the first one above it.
pub fn check_plan_sizes(value: &serde_json::Value, at: &str) -> Result<(), String> {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let path = format!("{at}.{key}");
                if let Some(&(_, max)) = PLAN_KEYS.iter().find(|(k, _)| k == key) {
                    let numbers: Vec<&Value> = match v {
                        Value::Array(items) => items.iter().collect(),
                        other => vec![other],
                    };
                    for n in numbers {
                        if let Some(x) = n.as_u64()
                            && x > max as u64
                        {
                            return Err(format!("`{path}` {x} is above its limit of {max}"));
                        }
                    }
                }
                check_plan_sizes(v, &path)?;
            }
            Ok(())
        }
        Value::Array(items) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| check_plan_sizes(v, &format!("{at}[{i}]"))),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_sizes_are_found_at_any_depth() {
        let plan = serde_json::json!({
            "experiment": {"Stability": {"options": {"grid": {"num_bases": [5, 10]}}}},
            "items": [{"num_bases": 10}, {"num_bases": 1_000_000_000_000u64}]
        });
        let e = check_plan_sizes(&plan, "plan.json").unwrap_err();
        assert_eq!(
            e,
            "`plan.json.items[1].num_bases` 1000000000000 is above its limit of 4096"
        );
        let ok = serde_json::json!({"items": [{"num_bases": 4096, "tau": 15, "beta": 1e9}]});
        assert!(check_plan_sizes(&ok, "p").is_ok());
        assert!(
            at_most("--num-bases", 50_000, MAX_NUM_BASES)
                .unwrap_err()
                .to_string()
                .contains("--num-bases 50000 is above its limit of 4096")
        );
    }
}
