//! Sharded sweeps: an experiment's work items split over N shards that run anywhere (a
//! Slurm job array, GNU parallel, by hand), then merged into exactly the result of the
//! single-machine run for the same seeds (timings aside).
//!
//! A plan directory holds `plan.json` (the experiment and its options, the session's
//! content hash, every item and the items of each shard), `session.json` (a copy of the
//! session in the native format) and `sweep.sbatch`. Shard I writes `shards/I.json`
//! atomically; a failed shard leaves `shards/I.failed.json` with its error instead.
//! Content hashes are SHA-256 (the `sha2` crate) of the files' bytes.
//!
//! The folder: `plan` writes and reads a plan, `shard` computes one shard, `status` tells
//! which shards are done, `merge` assembles their outputs, `compare` compares two results
//! timings aside, and `sbatch` writes the Slurm script.

mod compare;
mod merge;
mod plan;
mod sbatch;
mod shard;
mod status;

use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

pub use crate::experiments::experiment::{
    FrontierSweep, FrontierSweepItem, StabilitySweep, WorkTime,
};
pub use compare::{TIME_CHOSEN_KEYS, TIMING_KEYS, result_difference};
pub use merge::{Merged, merge};
pub use plan::{read_plan, read_session, write_plan};
pub use sbatch::{Resources, sbatch_script};
pub use shard::{ShardRun, run_shard};
pub use status::{ShardState, Status, describe, rerun_commands, status};

use crate::experiments::clustering::ClusteringParams;
use crate::experiments::experiment::Experiment as Sweepable;
use crate::experiments::recognition::RecognitionParams;
use crate::experiments::robustness::RobustnessParams;
use crate::fsutil;

pub const PLAN_TAG: &str = "tactile-workbench-sweep-plan";
pub const SHARD_TAG: &str = "tactile-workbench-sweep-shard";
pub const SWEEP_VERSION: u32 = 1;
pub const PLAN_FILE: &str = "plan.json";
pub const SESSION_FILE: &str = "session.json";
pub const SBATCH_FILE: &str = "sweep.sbatch";
pub const SHARDS_DIR: &str = "shards";

/// The experiments a sweep can shard. To add one, implement [`Sweepable`] for its
/// parameters, add a variant here and a line to `with_experiment!`.
// A plan holds one experiment: the size of the largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "experiment", rename_all = "snake_case")]
pub enum Experiment {
    Stability(StabilitySweep),
    Robustness(RobustnessParams),
    Clustering(ClusteringParams),
    Recognition(RecognitionParams),
    Frontier(FrontierSweep),
}

/// Run `$body` with `$x` bound to the experiment's parameters (a [`Sweepable`]).
macro_rules! with_experiment {
    ($e:expr, $x:ident => $body:expr) => {
        match $e {
            $crate::sweep::Experiment::Stability($x) => $body,
            $crate::sweep::Experiment::Robustness($x) => $body,
            $crate::sweep::Experiment::Clustering($x) => $body,
            $crate::sweep::Experiment::Recognition($x) => $body,
            $crate::sweep::Experiment::Frontier($x) => $body,
        }
    };
}

/// The macro, for the folder's files.
pub(crate) use with_experiment;

impl Experiment {
    pub fn name(&self) -> &'static str {
        with_experiment!(self, x => x.name())
    }
}

/// Why a sweep step failed: a file of the plan folder (its I/O, JSON or session error
/// kept), a plan or shard that does not match, the experiment's own error, a bad parameter,
/// or shards not done.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: String, message: String },
    /// A file of the plan folder, or an item or output in it, that is not the JSON it should
    /// be (`what` says which and where).
    #[error("{what}: {source}")]
    Json {
        what: String,
        #[source]
        source: serde_json::Error,
    },
    /// The plan's copy of the session does not read.
    #[error("{0}")]
    Session(#[from] crate::session::SessionError),
    #[error("{0}")]
    Mismatch(String),
    #[error("{0}")]
    Experiment(#[from] crate::experiments::ExperimentError),
    #[error("{0}")]
    Param(String),
    #[error("{0}")]
    Incomplete(String),
}

fn io_err(path: &Path, e: std::io::Error) -> SweepError {
    SweepError::Io {
        path: path.display().to_string(),
        source: e,
    }
}

fn json_err(what: impl Into<String>) -> impl FnOnce(serde_json::Error) -> SweepError {
    let what = what.into();
    move |source| SweepError::Json { what, source }
}

fn format_err(path: &Path, e: impl std::fmt::Display) -> SweepError {
    SweepError::Format {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// The session a plan was made for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionRef {
    /// The copy in the plan directory.
    pub file: String,
    pub name: String,
    /// Where the session was read from when planning.
    pub source: String,
    /// Content hash of the copy.
    pub hash: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub format: String,
    pub version: u32,
    pub experiment: Experiment,
    pub session: SessionRef,
    /// Every item, in the order of the single-machine run. Each item's seeds follow from
    /// the experiment's seed and the item itself (its repetition, its grid cell), never
    /// from the order in which items run.
    pub items: Vec<Value>,
    /// Indices into `items` of each shard.
    pub shards: Vec<Vec<usize>>,
    /// Estimated CPU-seconds of each shard's work.
    pub shard_cpu_seconds: Vec<f64>,
    pub resources: Resources,
}

impl Plan {
    pub fn shard_count(&self) -> usize {
        self.shards.len()
    }
}

/// What `write_plan` needs besides the experiment.
#[derive(Clone, Debug)]
pub struct PlanRequest {
    pub shards: usize,
    /// Where the session came from (recorded in the plan).
    pub source: String,
    /// Overrides of the estimated Slurm resources (None: estimate).
    pub time_minutes: Option<u64>,
    pub cpus: Option<usize>,
    pub mem_mb: Option<u64>,
    pub partition: Option<String>,
    /// The program the Slurm tasks run.
    pub program: String,
}

/// A finished shard.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShardFile {
    pub format: String,
    pub version: u32,
    pub shard: usize,
    /// Content hashes of the plan and the session it ran on.
    pub plan_hash: String,
    pub session_hash: String,
    /// Item indices (as in the plan) and their outputs, in the same order.
    pub items: Vec<usize>,
    /// Content hash of `outputs` as JSON, so that a hand edit or damage is caught.
    pub outputs_checksum: String,
    pub outputs: Vec<Value>,
    pub seconds: f64,
    pub threads: usize,
    pub host: String,
}

/// A shard that failed: its error, for `sweep status`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShardFailure {
    pub shard: usize,
    pub error: String,
    pub host: String,
}

fn host() -> String {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// The bytes of a plan folder's file (hashed whole, so read whole), refused unread past
/// [`fsutil::max_bytes::SWEEP`].
fn read_bounded(path: &Path) -> std::io::Result<Vec<u8>> {
    let len = fs::metadata(path)?.len();
    let max = fsutil::max_bytes::SWEEP;
    if len > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{len} bytes, more than the {} MiB a file of a sweep may hold",
                max >> 20
            ),
        ));
    }
    fs::read(path)
}

fn to_value<T: Serialize>(v: &T) -> Result<Value, SweepError> {
    serde_json::to_value(v).map_err(json_err("a value of the experiment"))
}

fn write_json(path: &Path, v: &impl Serialize) -> Result<(), SweepError> {
    let text = serde_json::to_string_pretty(v).map_err(json_err(path.display().to_string()))?;
    fsutil::write_atomic(path, text.as_bytes()).map_err(|e| io_err(path, e))
}

pub fn shard_path(dir: &Path, shard: usize) -> PathBuf {
    dir.join(SHARDS_DIR).join(format!("{shard}.json"))
}

pub fn failure_path(dir: &Path, shard: usize) -> PathBuf {
    dir.join(SHARDS_DIR).join(format!("{shard}.failed.json"))
}
