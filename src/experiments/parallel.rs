//! The one loop of every experiment and every shard of a sweep: items computed in
//! parallel, in order, with progress and a cancellation check before each.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::ExperimentError;
use crate::jobs::Progress;

/// Compute every item in parallel, in order, with progress ("{what}: d/n {unit}") and a
/// cancellation check before each item: the one loop of every experiment and shard. Each
/// item gets a part of `progress` worth its `cost` (its expected seconds, or any measure
/// proportional to them), to report how far it is; the fraction done then follows the time
/// spent even when items cost unequally.
pub fn compute_items<I: Sync, O: Send>(
    items: &[I],
    progress: &Progress,
    what: &str,
    unit: &str,
    cost: impl Fn(&I) -> f64,
    compute: impl Fn(&I, &Progress) -> Result<O, ExperimentError> + Sync,
) -> Result<Vec<O>, ExperimentError> {
    let total = items.len();
    let done = AtomicUsize::new(0);
    let parts = progress.parts(&items.iter().map(cost).collect::<Vec<_>>());
    items
        .par_iter()
        .zip(&parts)
        .map(|(item, part)| {
            part.checkpoint()?;
            let out = compute(item, part)?;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            part.set(1.0, format!("{what}: {d}/{total} {unit}"));
            Ok(out)
        })
        .collect()
}

/// The wall time of items of these expected seconds on this machine's worker threads,
/// each taken in order by the first thread free (as the work-stealing pool does nearly).
pub fn expected_wall_seconds(costs: impl IntoIterator<Item = f64>) -> f64 {
    let threads = rayon::current_num_threads().max(1);
    let mut load = vec![0.0f64; threads];
    for c in costs {
        let free = (0..threads)
            .min_by(|&a, &b| load[a].total_cmp(&load[b]))
            .unwrap_or(0);
        load[free] += c.max(0.0);
    }
    load.into_iter().fold(0.0, f64::max)
}
