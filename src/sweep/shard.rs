//! One shard run: its items computed and written as `shards/I.json`, or its failure
//! recorded; and a shard's result read back and checked against the plan.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::Value;

use super::plan::{read_plan, read_session, session_copy};
use super::{
    Plan, SHARD_TAG, SHARDS_DIR, SWEEP_VERSION, ShardFailure, ShardFile, SweepError, failure_path,
    format_err, host, io_err, json_err, read_bounded, shard_path, to_value, with_experiment,
    write_json,
};
use crate::experiments::experiment::Experiment as Sweepable;
use crate::experiments::parallel::compute_items;
use crate::fsutil;
use crate::jobs::Progress;
use crate::session::Session;

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
pub(super) fn read_shard(
    dir: &Path,
    shard: usize,
    plan: &Plan,
    plan_hash: &str,
) -> Result<Option<ShardFile>, SweepError> {
    let path = shard_path(dir, shard);
    let bytes = match read_bounded(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_err(&path, e)),
    };
    let f: ShardFile = serde_json::from_slice(&bytes)
        .map_err(json_err(format!("{}: not a shard result", path.display())))?;
    if f.format != SHARD_TAG || f.version != SWEEP_VERSION {
        return Err(format_err(&path, "not a shard result of this version"));
    }
    if f.plan_hash != plan_hash || f.session_hash != plan.session.hash {
        return Err(SweepError::Mismatch(format!(
            "{}: computed for another plan or session (hash mismatch)",
            path.display()
        )));
    }
    if outputs_checksum(&f.outputs)? != f.outputs_checksum {
        return Err(SweepError::Mismatch(format!(
            "{}: its outputs do not match their checksum: the file was edited or damaged; run \
             shard {shard} again",
            path.display()
        )));
    }
    if f.shard != shard || f.items != plan.shards[shard] || f.outputs.len() != f.items.len() {
        return Err(SweepError::Mismatch(format!(
            "{}: its items are not shard {shard}'s",
            path.display()
        )));
    }
    with_experiment!(&plan.experiment, e => outputs_fit(e, &f, &path))?;
    Ok(Some(f))
}

/// The content hash of a shard's outputs as JSON: the same for the outputs as computed and
/// as read back (a number reads back to the same value and prints the same), different
/// once one is edited.
fn outputs_checksum(outputs: &[Value]) -> Result<String, SweepError> {
    let bytes = serde_json::to_vec(outputs).map_err(json_err("a shard's outputs"))?;
    Ok(fsutil::content_hash(&bytes))
}

/// Checks that every output of a shard has the experiment's output shape, so that a shard
/// is only called done when the merge can read it.
fn outputs_fit<E: Sweepable>(_: &E, f: &ShardFile, path: &Path) -> Result<(), SweepError> {
    for (item, v) in f.items.iter().zip(&f.outputs) {
        serde_json::from_value::<E::Output>(v.clone()).map_err(json_err(format!(
            "{}: the output of item {item} is not of its shape",
            path.display()
        )))?;
    }
    Ok(())
}

/// Checks the plan's copy of the session against the plan's content hash, without parsing
/// it.
pub(super) fn check_session_copy(dir: &Path, plan: &Plan) -> Result<(), SweepError> {
    let path = session_copy(dir, plan)?;
    let bytes = read_bounded(&path).map_err(|e| io_err(&path, e))?;
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
pub(super) fn partial_files(dir: &Path, shard: usize) -> Vec<PathBuf> {
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
        .map(|(i, v)| serde_json::from_value(v.clone()).map_err(json_err(format!("plan item {i}"))))
        .collect::<Result<_, _>>()?;
    progress.set(0.0, format!("{}: preparing", e.name()));
    let prep = e.prepare(session, progress)?;
    progress.set(0.0, format!("{}: 0/{} items", e.name(), items.len()));
    // A shard's items are weighed alike: its progress is a count of them.
    let outputs = compute_items(
        &items,
        progress,
        e.name(),
        "items",
        |_| 1.0,
        |item, part| e.compute(session, &prep, item, part),
    )?;
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
        outputs_checksum: outputs_checksum(&outputs)?,
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
