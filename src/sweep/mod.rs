//! Sharded sweeps: an experiment's work items split over N shards that run anywhere (a
//! Slurm job array, GNU parallel, by hand), then merged into exactly the result of the
//! single-machine run for the same seeds (timings aside).
//!
//! A plan directory holds `plan.json` (the experiment and its options, the session's
//! content hash, every item and the items of each shard), `session.json` (a copy of the
//! session in the native format) and `sweep.sbatch`. Shard I writes `shards/I.json`
//! atomically; a failed shard leaves `shards/I.failed.json` with its error instead.
//! Content hashes are SHA-256 (the `sha2` crate) of the files' bytes.

mod sbatch;

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::experiments::experiment::Experiment as Sweepable;
pub use crate::experiments::experiment::{
    FrontierSweep, FrontierSweepItem, StabilitySweep, WorkTime,
};
use crate::experiments::parallel::compute_items;
pub use sbatch::{Resources, sbatch_script};

use crate::experiments::clustering::ClusteringParams;
use crate::experiments::recognition::RecognitionParams;
use crate::experiments::result::AnalysisResult;
use crate::experiments::robustness::RobustnessParams;
use crate::fsutil;
use crate::jobs::Progress;
use crate::session::{self, Session};

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
            Experiment::Stability($x) => $body,
            Experiment::Robustness($x) => $body,
            Experiment::Clustering($x) => $body,
            Experiment::Recognition($x) => $body,
            Experiment::Frontier($x) => $body,
        }
    };
}

impl Experiment {
    pub fn name(&self) -> &'static str {
        with_experiment!(self, x => x.name())
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("{path}: {message}")]
    Format { path: String, message: String },
    #[error("{0}")]
    Mismatch(String),
    #[error("{0}")]
    Experiment(String),
    #[error("{0}")]
    Param(String),
    #[error("{0}")]
    Incomplete(String),
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> SweepError {
    SweepError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
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

fn to_value<T: Serialize>(v: &T) -> Result<Value, SweepError> {
    serde_json::to_value(v).map_err(|e| SweepError::Experiment(e.to_string()))
}

fn write_json(path: &Path, v: &impl Serialize) -> Result<(), SweepError> {
    let text = serde_json::to_string_pretty(v).map_err(|e| io_err(path, e))?;
    fsutil::write_atomic(path, text.as_bytes()).map_err(|e| io_err(path, e))
}

pub fn shard_path(dir: &Path, shard: usize) -> PathBuf {
    dir.join(SHARDS_DIR).join(format!("{shard}.json"))
}

pub fn failure_path(dir: &Path, shard: usize) -> PathBuf {
    dir.join(SHARDS_DIR).join(format!("{shard}.failed.json"))
}

// ---------------------------------------------------------------------------------------
// Planning
// ---------------------------------------------------------------------------------------

/// Split weighted items over `n` shards: heaviest first onto the lightest shard (ties:
/// lower index), then each shard's items in plan order. Deterministic.
fn balance(costs: &[f64], n: usize) -> (Vec<Vec<usize>>, Vec<f64>) {
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]).then(a.cmp(&b)));
    let mut shards = vec![Vec::new(); n];
    let mut load = vec![0.0f64; n];
    for i in order {
        let s = (0..n)
            .min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b)))
            .expect("at least one shard");
        shards[s].push(i);
        load[s] += costs[i];
    }
    for s in &mut shards {
        s.sort_unstable();
    }
    (shards, load)
}

/// A plan's items, the items of each shard and each shard's estimated CPU-seconds.
struct Split {
    items: Vec<Value>,
    shards: Vec<Vec<usize>>,
    load: Vec<f64>,
}

fn plan_items<E: Sweepable>(e: &E, session: &Session, shards: usize) -> Result<Split, SweepError> {
    let items = e
        .items(session)
        .map_err(|e| SweepError::Experiment(e.to_string()))?;
    if items.is_empty() {
        return Err(SweepError::Param("the experiment has no work items".into()));
    }
    if shards > items.len() {
        return Err(SweepError::Param(format!(
            "{shards} shards for {} work items: use at most {} shards",
            items.len(),
            items.len()
        )));
    }
    let costs: Vec<f64> = items.iter().map(|i| e.cost(session, i)).collect();
    let (split, load) = balance(&costs, shards);
    Ok(Split {
        items: items.iter().map(to_value).collect::<Result<_, _>>()?,
        shards: split,
        load,
    })
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

/// Write a plan for `experiment` on `session` into `dir` (created; it must not hold a
/// plan already): plan.json, session.json and sweep.sbatch. The workbench's "Run on a
/// cluster…" calls this with the experiment set up in a view.
pub fn write_plan(
    dir: &Path,
    session: &Session,
    experiment: Experiment,
    request: &PlanRequest,
) -> Result<Plan, SweepError> {
    if request.shards == 0 {
        return Err(SweepError::Param("--shards must be at least 1".into()));
    }
    let plan_path = dir.join(PLAN_FILE);
    if plan_path.exists() {
        return Err(SweepError::Param(format!(
            "{} already holds a plan: choose another directory or remove it",
            dir.display()
        )));
    }
    let Split {
        items,
        shards,
        load,
    } = with_experiment!(&experiment, e => plan_items(e, session, request.shards))?;
    fs::create_dir_all(dir.join(SHARDS_DIR)).map_err(|e| io_err(dir, e))?;
    fs::create_dir_all(dir.join("logs")).map_err(|e| io_err(dir, e))?;
    let session_path = dir.join(SESSION_FILE);
    let text = session::native::to_string(session);
    fsutil::write_atomic(&session_path, text.as_bytes()).map_err(|e| io_err(&session_path, e))?;
    let resources = Resources::estimate(&load, text.len() as u64, request);
    let plan = Plan {
        format: PLAN_TAG.into(),
        version: SWEEP_VERSION,
        session: SessionRef {
            file: SESSION_FILE.into(),
            name: session.meta.name.clone(),
            source: request.source.clone(),
            hash: fsutil::content_hash(text.as_bytes()),
        },
        experiment,
        items,
        shards,
        shard_cpu_seconds: load,
        resources,
    };
    write_json(&plan_path, &plan)?;
    let abs = fs::canonicalize(dir).map_err(|e| io_err(dir, e))?;
    let script = sbatch_script(&plan, &abs);
    let sbatch_path = dir.join(SBATCH_FILE);
    fsutil::write_atomic(&sbatch_path, script.as_bytes()).map_err(|e| io_err(&sbatch_path, e))?;
    Ok(plan)
}

/// Read and check a plan; returns it with the content hash of plan.json.
pub fn read_plan(dir: &Path) -> Result<(Plan, String), SweepError> {
    let path = dir.join(PLAN_FILE);
    let bytes = fs::read(&path).map_err(|e| io_err(&path, e))?;
    #[derive(Deserialize)]
    struct Header {
        format: Option<String>,
        version: Option<u64>,
    }
    let h: Header = serde_json::from_slice(&bytes).map_err(|e| format_err(&path, e))?;
    if h.format.as_deref() != Some(PLAN_TAG) {
        return Err(format_err(&path, "not a sweep plan"));
    }
    if h.version != Some(SWEEP_VERSION as u64) {
        return Err(format_err(
            &path,
            format!(
                "unsupported plan version {:?}; this build reads version {SWEEP_VERSION}",
                h.version
            ),
        ));
    }
    let plan: Plan = serde_json::from_slice(&bytes).map_err(|e| format_err(&path, e))?;
    let n = plan.items.len();
    let mut seen = vec![false; n];
    for (s, items) in plan.shards.iter().enumerate() {
        for &i in items {
            if i >= n || std::mem::replace(&mut seen[i], true) {
                return Err(format_err(
                    &path,
                    format!("`shards[{s}]`: item {i} is out of range or in two shards"),
                ));
            }
        }
    }
    if let Some(i) = seen.iter().position(|s| !s) {
        return Err(format_err(&path, format!("item {i} is in no shard")));
    }
    Ok((plan, fsutil::content_hash(&bytes)))
}

/// The plan's copy of the session, refused when its content hash is not the plan's.
pub fn read_session(dir: &Path, plan: &Plan) -> Result<Session, SweepError> {
    let path = dir.join(&plan.session.file);
    let bytes = fs::read(&path).map_err(|e| io_err(&path, e))?;
    let hash = fsutil::content_hash(&bytes);
    if hash != plan.session.hash {
        return Err(SweepError::Mismatch(format!(
            "{}: content hash {hash} is not the plan's {}: the plan was made for another session",
            path.display(),
            plan.session.hash
        )));
    }
    let text = String::from_utf8(bytes).map_err(|e| format_err(&path, e))?;
    session::native::from_str(&text, &path).map_err(|e| format_err(&path, e))
}

// ---------------------------------------------------------------------------------------
// Shards
// ---------------------------------------------------------------------------------------

/// What `run_shard` did.
#[derive(Clone, Debug, PartialEq)]
pub enum ShardRun {
    /// A valid result was there already.
    Skipped,
    Done {
        items: usize,
        seconds: f64,
    },
}

/// The shard's result if `shards/I.json` is a complete result of this plan.
fn read_shard(
    dir: &Path,
    shard: usize,
    plan: &Plan,
    plan_hash: &str,
) -> Result<Option<ShardFile>, String> {
    let path = shard_path(dir, shard);
    let bytes = match fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let f: ShardFile = serde_json::from_slice(&bytes)
        .map_err(|e| format!("{}: not a shard result ({e})", path.display()))?;
    if f.format != SHARD_TAG || f.version != SWEEP_VERSION {
        return Err(format!(
            "{}: not a shard result of this version",
            path.display()
        ));
    }
    if f.plan_hash != plan_hash || f.session_hash != plan.session.hash {
        return Err(format!(
            "{}: computed for another plan or session (hash mismatch)",
            path.display()
        ));
    }
    if f.shard != shard || f.items != plan.shards[shard] || f.outputs.len() != f.items.len() {
        return Err(format!(
            "{}: its items are not shard {shard}'s",
            path.display()
        ));
    }
    with_experiment!(&plan.experiment, e => outputs_fit(e, &f))
        .map_err(|m| format!("{}: {m}", path.display()))?;
    Ok(Some(f))
}

/// Checks that every output of a shard has the experiment's output shape, so that a shard
/// is only called done when the merge can read it.
fn outputs_fit<E: Sweepable>(_: &E, f: &ShardFile) -> Result<(), String> {
    for (item, v) in f.items.iter().zip(&f.outputs) {
        serde_json::from_value::<E::Output>(v.clone())
            .map_err(|err| format!("the output of item {item} is not of its shape ({err})"))?;
    }
    Ok(())
}

/// Checks the plan's copy of the session against the plan's content hash, without parsing
/// it.
fn check_session_copy(dir: &Path, plan: &Plan) -> Result<(), SweepError> {
    let path = dir.join(&plan.session.file);
    let bytes = fs::read(&path).map_err(|e| io_err(&path, e))?;
    let hash = fsutil::content_hash(&bytes);
    if hash != plan.session.hash {
        return Err(SweepError::Mismatch(format!(
            "{}: content hash {hash} is not the plan's {}: the session copy was changed or \
             replaced since the plan was made",
            path.display(),
            plan.session.hash
        )));
    }
    Ok(())
}

/// Temporary files a killed run of the shard left behind.
fn partial_files(dir: &Path, shard: usize) -> Vec<PathBuf> {
    let prefix = format!(".{shard}.json.");
    fs::read_dir(dir.join(SHARDS_DIR))
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".tmp"))
                })
                .collect()
        })
        .unwrap_or_default()
}

fn compute_shard<E: Sweepable>(
    e: &E,
    session: &Session,
    items: &[Value],
    progress: &Progress,
) -> Result<Vec<Value>, SweepError> {
    let items: Vec<E::Item> = items
        .iter()
        .enumerate()
        .map(|(i, v)| {
            serde_json::from_value(v.clone())
                .map_err(|err| SweepError::Experiment(format!("plan item {i}: {err}")))
        })
        .collect::<Result<_, _>>()?;
    progress.set(0.0, format!("{}: preparing", e.name()));
    let prep = e
        .prepare(session, progress)
        .map_err(|e| SweepError::Experiment(e.to_string()))?;
    progress.set(0.0, format!("{}: 0/{} items", e.name(), items.len()));
    let outputs = compute_items(&items, progress, e.name(), "items", |item| {
        e.compute(session, &prep, item, progress)
    })
    .map_err(|e| SweepError::Experiment(e.to_string()))?;
    outputs.iter().map(to_value).collect()
}

/// Run shard `shard` of the plan in `dir` and write `shards/I.json` atomically. A shard
/// already done is skipped; a plan or session whose hash does not match is refused; a
/// failure leaves `shards/I.failed.json` with its error.
pub fn run_shard(dir: &Path, shard: usize, progress: &Progress) -> Result<ShardRun, SweepError> {
    let (plan, plan_hash) = read_plan(dir)?;
    if shard >= plan.shard_count() {
        return Err(SweepError::Param(format!(
            "shard {shard} does not exist: the plan has shards 0 to {}",
            plan.shard_count() - 1
        )));
    }
    match read_shard(dir, shard, &plan, &plan_hash) {
        Ok(Some(_)) => return Ok(ShardRun::Skipped),
        Ok(None) => {}
        // A damaged or stale result is computed again.
        Err(_) => {}
    }
    let session = read_session(dir, &plan)?;
    let shards_dir = dir.join(SHARDS_DIR);
    fs::create_dir_all(&shards_dir).map_err(|e| io_err(&shards_dir, e))?;
    for p in partial_files(dir, shard) {
        let _ = fs::remove_file(p);
    }
    let start = Instant::now();
    let items: Vec<Value> = plan.shards[shard]
        .iter()
        .map(|&i| plan.items[i].clone())
        .collect();
    let outputs =
        with_experiment!(&plan.experiment, e => compute_shard(e, &session, &items, progress));
    let outputs = match outputs {
        Ok(o) => o,
        Err(err) => {
            let failure = ShardFailure {
                shard,
                error: err.to_string(),
                host: host(),
            };
            let _ = write_json(&failure_path(dir, shard), &failure);
            return Err(err);
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    let file = ShardFile {
        format: SHARD_TAG.into(),
        version: SWEEP_VERSION,
        shard,
        plan_hash,
        session_hash: plan.session.hash.clone(),
        items: plan.shards[shard].clone(),
        outputs,
        seconds,
        threads: rayon::current_num_threads(),
        host: host(),
    };
    write_json(&shard_path(dir, shard), &file)?;
    let _ = fs::remove_file(failure_path(dir, shard));
    Ok(ShardRun::Done {
        items: file.items.len(),
        seconds,
    })
}

// ---------------------------------------------------------------------------------------
// Status and merge
// ---------------------------------------------------------------------------------------

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
            Err(reason) => ShardState::Failed { reason },
            Ok(None) => {
                let failure = fs::read(failure_path(dir, i))
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

/// A merged sweep: the single-machine result (as JSON) and the result as the workbench
/// keeps it (None for frontiers, kept as their JSON list).
pub struct Merged {
    pub experiment: Experiment,
    pub session: Session,
    pub result: Value,
    pub analysis: Option<AnalysisResult>,
    pub time: WorkTime,
}

fn merge_with<E: Sweepable>(
    e: &E,
    session: &Session,
    items: &[Value],
    outputs: Vec<Value>,
    time: WorkTime,
    progress: &Progress,
) -> Result<(Value, Option<AnalysisResult>), SweepError> {
    fn parse<T: serde::de::DeserializeOwned>(i: usize, v: Value) -> Result<T, SweepError> {
        serde_json::from_value(v).map_err(|err| SweepError::Experiment(format!("item {i}: {err}")))
    }
    let items: Vec<E::Item> = items
        .iter()
        .enumerate()
        .map(|(i, v)| parse(i, v.clone()))
        .collect::<Result<_, _>>()?;
    let outputs: Vec<E::Output> = outputs
        .into_iter()
        .enumerate()
        .map(|(i, v)| parse(i, v))
        .collect::<Result<_, _>>()?;
    progress.set(0.0, format!("{}: merging", e.name()));
    let result = e
        .assemble(session, &items, outputs, time, progress)
        .map_err(|e| SweepError::Experiment(e.to_string()))?;
    let analysis = e.analysis(session, &result);
    Ok((to_value(&result)?, analysis))
}

/// Merge every shard of the plan in `dir` into the single-machine result. Refuses while a
/// shard is missing or failed, naming them and the commands to rerun them.
pub fn merge(dir: &Path, progress: &Progress) -> Result<Merged, SweepError> {
    let st = status(dir)?;
    let not_done = st.not_done();
    if !not_done.is_empty() {
        let mut msg = format!(
            "{} of {} shards are not done:\n",
            not_done.len(),
            st.shards.len()
        );
        for &i in &not_done {
            msg.push_str(&format!("  shard {i}: {}\n", describe(&st.shards[i])));
        }
        msg.push_str("rerun them with:\n");
        for c in rerun_commands(dir, &st.plan.resources.program, &not_done) {
            msg.push_str(&format!("  {c}\n"));
        }
        return Err(SweepError::Incomplete(msg.trim_end().into()));
    }
    let (plan, plan_hash) = read_plan(dir)?;
    let session = read_session(dir, &plan)?;
    let mut outputs: Vec<Option<Value>> = vec![None; plan.items.len()];
    let mut time = WorkTime {
        seconds: 0.0,
        threads: 0,
    };
    for s in 0..plan.shard_count() {
        let f = read_shard(dir, s, &plan, &plan_hash)
            .map_err(SweepError::Incomplete)?
            .ok_or_else(|| {
                SweepError::Incomplete(format!("shard {s} vanished during the merge"))
            })?;
        time.seconds += f.seconds;
        time.threads = time.threads.max(f.threads);
        for (i, v) in f.items.into_iter().zip(f.outputs) {
            outputs[i] = Some(v);
        }
    }
    let outputs: Vec<Value> = outputs
        .into_iter()
        .map(|o| o.expect("read_plan checked every item is in a shard"))
        .collect();
    let (result, analysis) = with_experiment!(&plan.experiment, e => merge_with(e, &session, &plan.items, outputs, time, progress))?;
    Ok(Merged {
        experiment: plan.experiment,
        session,
        result,
        analysis,
        time,
    })
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
