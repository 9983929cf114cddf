//! The Slurm job-array script of a plan and the resources it asks for.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Plan, PlanRequest, SBATCH_FILE, SweepError};

/// What each array task asks Slurm for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resources {
    /// Wall-time limit of a task.
    pub time_minutes: u64,
    pub cpus: usize,
    pub mem_mb: u64,
    pub partition: Option<String>,
    /// The program the tasks run (`tactile-workbench` as installed on the cluster).
    pub program: String,
}

/// Default CPUs per task.
const CPUS: usize = 2;
/// The time limit is this many times the estimate (the cost model is rough and cluster
/// cores differ), and never under `MIN_MINUTES`.
const TIME_MARGIN: f64 = 3.0;
const MIN_MINUTES: u64 = 10;

impl Resources {
    /// From the estimated CPU-seconds of each shard and the session's size in bytes,
    /// unless the request sets them.
    pub fn estimate(shard_cpu_seconds: &[f64], session_bytes: u64, r: &PlanRequest) -> Self {
        let cpus = r.cpus.unwrap_or(CPUS).max(1);
        let worst = shard_cpu_seconds.iter().copied().fold(0.0, f64::max);
        let minutes = (TIME_MARGIN * worst / cpus as f64 / 60.0).ceil() as u64;
        // The session in memory is a few times its JSON; each worker holds its own
        // copies of the features and a model.
        let mem_mb = 512 + (4 + cpus as u64) * session_bytes.div_ceil(1 << 20);
        Resources {
            time_minutes: r.time_minutes.unwrap_or(minutes.max(MIN_MINUTES)),
            cpus,
            mem_mb: r.mem_mb.unwrap_or(mem_mb),
            partition: r.partition.clone(),
            program: r.program.clone(),
        }
    }

    /// `D-HH:MM:SS` as Slurm reads it.
    pub fn time_text(&self) -> String {
        let m = self.time_minutes;
        format!("{}-{:02}:{:02}:00", m / (24 * 60), m / 60 % 24, m % 60)
    }
}

/// `s` as one word of the shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// `s` as one value of an `#SBATCH` line: sbatch reads double quotes and backslash escapes
/// there, and an unquoted `#` or space would end the value.
fn directive_value(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', r"\\").replace('"', r#"\""#))
}

/// Refuse a value bound for the script that holds a control character: a newline would
/// end its line and start another `#SBATCH` line or a command of the job. `field` names
/// the option in the error.
pub(super) fn check_script_text(field: &str, value: &str) -> Result<(), SweepError> {
    match value.chars().find(|c| c.is_control()) {
        Some(c) => Err(SweepError::Param(format!(
            "{field}: {value:?} holds the control character {c:?}, which would change the \
             Slurm script: refused"
        ))),
        None => Ok(()),
    }
}

/// The job-array script: one array task per shard, each running `sweep run` on its shard;
/// logs go to `logs/` of the plan directory `dir` (absolute, as tasks start elsewhere).
pub fn sbatch_script(plan: &Plan, dir: &Path) -> String {
    let r = &plan.resources;
    let n = plan.shard_count();
    let dir_text = dir.display().to_string();
    let mut s = String::new();
    s.push_str("#!/bin/bash\n");
    s.push_str(&format!(
        "# A {} sweep of {} items on session {:?}, in {n} shards.\n",
        plan.experiment.name(),
        plan.items.len(),
        plan.session.name
    ));
    s.push_str(&format!(
        "# Submit: sbatch {}   (rerun some shards: sbatch --array=3,7 {})\n",
        dir.join(SBATCH_FILE).display(),
        dir.join(SBATCH_FILE).display()
    ));
    s.push_str(&format!(
        "#SBATCH --job-name=tw-{}\n",
        plan.experiment.name()
    ));
    s.push_str(&format!("#SBATCH --array=0-{}\n", n - 1));
    s.push_str(&format!("#SBATCH --time={}\n", r.time_text()));
    s.push_str("#SBATCH --ntasks=1\n");
    s.push_str(&format!("#SBATCH --cpus-per-task={}\n", r.cpus));
    s.push_str(&format!("#SBATCH --mem={}M\n", r.mem_mb));
    if let Some(p) = &r.partition {
        s.push_str(&format!("#SBATCH --partition={}\n", directive_value(p)));
    }
    s.push_str(&format!("#SBATCH --chdir={}\n", directive_value(&dir_text)));
    s.push_str("#SBATCH --output=logs/%A_%a.out\n");
    s.push_str("set -euo pipefail\n");
    s.push_str(&format!(
        "exec {} sweep run {} --shard \"$SLURM_ARRAY_TASK_ID\" --threads \"${{SLURM_CPUS_PER_TASK:-{}}}\"\n",
        quote(&r.program),
        quote(&dir_text),
        r.cpus
    ));
    s
}
