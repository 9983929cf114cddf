//! A sharded sweep through a real Slurm (as scripts/slurm-check.sh does): plan, sbatch the
//! job array, wait with squeue, merge, and compare with the single-machine command. Skips,
//! saying so, where `sbatch` is not on PATH or no controller answers.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_tactile-workbench");

fn run(program: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

fn tw(args: &[&str]) -> String {
    let out = Command::new(BIN)
        .args(args)
        .output()
        .expect("the program runs");
    assert!(
        out.status.success(),
        "tactile-workbench {}: {}{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_sweep_through_slurm_merges_into_the_local_result() {
    let on_path = std::env::var_os("PATH")
        .is_some_and(|p| std::env::split_paths(&p).any(|d| d.join("sbatch").is_file()));
    if !on_path {
        eprintln!(
            "skipped: sbatch is not on PATH (scripts/slurm-check.sh installs and starts Slurm)"
        );
        return;
    }
    if run("sinfo", &["-h"]).is_none() {
        eprintln!("skipped: sbatch is there but no Slurm controller answers");
        return;
    }
    let dir = common::temp_dir("sweep-slurm");
    let session = common::sample("grasp-stability.json");
    let session = session.to_str().unwrap();
    let grid = [
        "--num-bases",
        "2,4,6",
        "--beta",
        "0.5,1",
        "--gamma",
        "0.5,1",
        "--cv",
        "3",
    ];
    let local = dir.join("local.json");
    let mut args = vec![
        "stability",
        session,
        "--quiet",
        "--json",
        local.to_str().unwrap(),
    ];
    args.extend(grid);
    tw(&args);
    let plan = dir.join("plan");
    let mut args = vec!["sweep", "plan", "stability", session, "--shards", "2"];
    args.extend(grid);
    args.extend(["-o", plan.to_str().unwrap(), "--time", "10"]);
    tw(&args);
    let script = plan.join("sweep.sbatch");
    let job = run("sbatch", &["--parsable", script.to_str().unwrap()]).expect("sbatch submits");
    let job = job.trim().split(';').next().unwrap().to_string();
    let start = Instant::now();
    while run("squeue", &["-h", "-j", &job]).is_some_and(|s| !s.trim().is_empty()) {
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "job {job} still queued after 10 minutes"
        );
        std::thread::sleep(Duration::from_secs(2));
    }
    let status = tw(&["sweep", "status", plan.to_str().unwrap()]);
    assert!(
        status.contains("2 done, 0 missing, 0 failed of 2"),
        "{status}\n{}",
        logs(&plan)
    );
    let merged = dir.join("merged.json");
    let out = tw(&[
        "sweep",
        "merge",
        plan.to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
        "--quiet",
        "--expect",
        local.to_str().unwrap(),
    ]);
    assert!(out.contains("equals"), "{out}");
}

fn logs(plan: &Path) -> String {
    std::fs::read_dir(plan.join("logs"))
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
                .collect::<Vec<_>>()
                .join("\n")
        })
        .unwrap_or_default()
}
