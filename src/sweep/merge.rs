//! The merge: every shard's outputs, in plan order, assembled into the single-machine
//! result.

use std::path::Path;

use serde_json::Value;

use super::plan::{read_plan, read_session};
use super::shard::read_shard;
use super::status::{describe, rerun_commands, status};
use super::{Experiment, SweepError, WorkTime, to_value, with_experiment};
use crate::experiments::experiment::Experiment as Sweepable;
use crate::experiments::result::AnalysisResult;
use crate::jobs::Progress;
use crate::session::Session;

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
        serde_json::from_value(v).map_err(super::json_err(format!("item {i}")))
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
    let result = e.assemble(session, &items, outputs, time, progress)?;
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
        let f = read_shard(dir, s, &plan, &plan_hash)?.ok_or_else(|| {
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
