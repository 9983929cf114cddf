//! The one loop of every experiment and every shard of a sweep: items computed in
//! parallel, in order, with progress and a cancellation check before each.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::ExperimentError;
use crate::jobs::Progress;

/// Compute every item in parallel, in order, with progress ("{what}: d/n {unit}") and a
/// cancellation check before each item: the one loop of every experiment and shard.
pub fn compute_items<I: Sync, O: Send>(
    items: &[I],
    progress: &Progress,
    what: &str,
    unit: &str,
    compute: impl Fn(&I) -> Result<O, ExperimentError> + Sync,
) -> Result<Vec<O>, ExperimentError> {
    let total = items.len();
    let done = AtomicUsize::new(0);
    items
        .par_iter()
        .map(|item| {
            progress.checkpoint()?;
            let out = compute(item)?;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set(
                d as f64 / total.max(1) as f64,
                format!("{what}: {d}/{total} {unit}"),
            );
            Ok(out)
        })
        .collect()
}
