//! Planning: the experiment's items balanced over the shards, and the plan directory
//! written (plan.json, the session's copy, the Slurm script) and read back, checked.

use std::fs;
use std::path::Path;

use serde::Deserialize;
use serde_json::Value;

use super::sbatch::{Resources, check_script_text, sbatch_script};
use super::{
    Experiment, PLAN_FILE, PLAN_TAG, Plan, PlanRequest, SBATCH_FILE, SESSION_FILE, SHARDS_DIR,
    SWEEP_VERSION, SessionRef, SweepError, format_err, io_err, json_err, read_bounded, to_value,
    with_experiment, write_json,
};
use crate::experiments::experiment::Experiment as Sweepable;
use crate::fsutil;
use crate::session::{self, Session};

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
    let items = e.items(session)?;
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
    // What enters the Slurm script, checked before anything is written.
    if let Some(p) = &request.partition {
        check_script_text("--partition", p)?;
    }
    check_script_text("--program", &request.program)?;
    let abs = std::path::absolute(dir).map_err(|e| io_err(dir, e))?;
    check_script_text("the plan folder", &abs.display().to_string())?;
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
    check_script_text("the plan folder", &abs.display().to_string())?;
    let script = sbatch_script(&plan, &abs);
    let sbatch_path = dir.join(SBATCH_FILE);
    fsutil::write_atomic(&sbatch_path, script.as_bytes()).map_err(|e| io_err(&sbatch_path, e))?;
    Ok(plan)
}

/// Read and check a plan; returns it with the content hash of plan.json.
pub fn read_plan(dir: &Path) -> Result<(Plan, String), SweepError> {
    let path = dir.join(PLAN_FILE);
    let bytes = read_bounded(&path).map_err(|e| io_err(&path, e))?;
    #[derive(Deserialize)]
    struct Header {
        format: Option<String>,
        version: Option<u64>,
    }
    let h: Header = serde_json::from_slice(&bytes).map_err(json_err(path.display().to_string()))?;
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
    let plan: Plan =
        serde_json::from_slice(&bytes).map_err(json_err(path.display().to_string()))?;
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
    // The session is the plan's own copy beside it: a file name, never a path elsewhere.
    let mut parts = Path::new(&plan.session.file).components();
    if !matches!(
        (parts.next(), parts.next()),
        (Some(std::path::Component::Normal(_)), None)
    ) {
        return Err(format_err(
            &path,
            format!(
                "`session.file`: {:?} is not a file name in the plan folder (the plan's copy \
                 of its session, {SESSION_FILE})",
                plan.session.file
            ),
        ));
    }
    Ok((plan, fsutil::content_hash(&bytes)))
}

/// The plan's copy of its session: a regular file in the plan folder (not a link out of
/// it, not a device).
pub(super) fn session_copy(dir: &Path, plan: &Plan) -> Result<std::path::PathBuf, SweepError> {
    let path = dir.join(&plan.session.file);
    let meta = fs::symlink_metadata(&path).map_err(|e| io_err(&path, e))?;
    if !meta.is_file() {
        return Err(format_err(
            &path,
            "not a session file (a plan's session is a regular file beside it)",
        ));
    }
    Ok(path)
}

/// The plan's copy of the session, refused when its content hash is not the plan's.
pub fn read_session(dir: &Path, plan: &Plan) -> Result<Session, SweepError> {
    let path = session_copy(dir, plan)?;
    let bytes = read_bounded(&path).map_err(|e| io_err(&path, e))?;
    let hash = fsutil::content_hash(&bytes);
    if hash != plan.session.hash {
        return Err(SweepError::Mismatch(format!(
            "{}: content hash {hash} is not the plan's {}: the plan was made for another session",
            path.display(),
            plan.session.hash
        )));
    }
    let text = String::from_utf8(bytes).map_err(|e| format_err(&path, e))?;
    Ok(session::native::from_str(&text, &path)?)
}
