//! The state of every shard of a plan, and the commands that rerun those not done.

use std::path::Path;

use super::plan::read_plan;
use super::shard::{check_session_copy, partial_files, read_shard};
use super::{Plan, SBATCH_FILE, ShardFailure, SweepError, failure_path};

#[derive(Clone, Debug, PartialEq)]
pub enum ShardState {
    Done {
        seconds: f64,
        host: String,
    },
    /// Not run yet, or still running; `partial` when a temporary file of an interrupted
    /// (or running) write is there.
    Missing {
        partial: bool,
    },
    Failed {
        reason: String,
    },
}

pub struct Status {
    pub plan: Plan,
    pub shards: Vec<ShardState>,
}

impl Status {
    pub fn done(&self) -> usize {
        self.shards
            .iter()
            .filter(|s| matches!(s, ShardState::Done { .. }))
            .count()
    }

    /// Shards not done, in order.
    pub fn not_done(&self) -> Vec<usize> {
        (0..self.shards.len())
            .filter(|&i| !matches!(self.shards[i], ShardState::Done { .. }))
            .collect()
    }
}

/// The state of every shard of the plan in `dir`.
pub fn status(dir: &Path) -> Result<Status, SweepError> {
    let (plan, plan_hash) = read_plan(dir)?;
    check_session_copy(dir, &plan)?;
    let shards = (0..plan.shard_count())
        .map(|i| match read_shard(dir, i, &plan, &plan_hash) {
            Ok(Some(f)) => ShardState::Done {
                seconds: f.seconds,
                host: f.host,
            },
            Err(e) => ShardState::Failed {
                reason: e.to_string(),
            },
            Ok(None) => {
                let failure = super::read_bounded(&failure_path(dir, i))
                    .ok()
                    .and_then(|b| serde_json::from_slice::<ShardFailure>(&b).ok());
                match failure {
                    Some(f) => ShardState::Failed {
                        reason: format!("{} (on {})", f.error, f.host),
                    },
                    None => ShardState::Missing {
                        partial: !partial_files(dir, i).is_empty(),
                    },
                }
            }
        })
        .collect();
    Ok(Status { plan, shards })
}

/// The commands that rerun `shards` of the plan in `dir`, by hand and with Slurm.
pub fn rerun_commands(dir: &Path, program: &str, shards: &[usize]) -> Vec<String> {
    let list: Vec<String> = shards.iter().map(|s| s.to_string()).collect();
    let mut out: Vec<String> = shards
        .iter()
        .map(|s| format!("{program} sweep run {} --shard {s}", dir.display()))
        .collect();
    out.push(format!(
        "sbatch --array={} {}",
        list.join(","),
        dir.join(SBATCH_FILE).display()
    ));
    out
}

/// A shard's state in words.
pub fn describe(s: &ShardState) -> String {
    match s {
        ShardState::Done { seconds, host } => format!("done ({seconds:.1} s on {host})"),
        ShardState::Missing { partial: false } => "missing".into(),
        ShardState::Missing { partial: true } => {
            "missing (a partial file of an interrupted or running write is there)".into()
        }
        ShardState::Failed { reason } => format!("failed: {reason}"),
    }
}
