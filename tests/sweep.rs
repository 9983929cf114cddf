//! Sharded sweeps on the bundled samples: merging the shards gives exactly the
//! single-machine result (timings aside) for the stability grid, robustness, clustering,
//! recognition and the frontiers; a killed shard, a rerun, a corrupted shard file and a plan from another
//! session or plan are handled.

mod common;
use common::TempDir;

use std::fs;
use std::path::Path;

use serde_json::Value;
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::clustering::{ClusteringParams, run_clustering};
use tactile_workbench::experiments::frontier::{Frontier, FrontierParams, run_frontier};
use tactile_workbench::experiments::recognition::{RecognitionParams, run_recognition};
use tactile_workbench::experiments::robustness::{
    Family, Perturbation, RobustnessParams, Sweep, run_robustness,
};
use tactile_workbench::experiments::stability::{
    self, CvScheme, DataOptions, GridSpec, StabilityData, StabilityOptions,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::{self, Session};
use tactile_workbench::sweep::{
    self, Experiment, FrontierSweep, PlanRequest, ShardRun, ShardState, StabilitySweep, SweepError,
    result_difference,
};

fn sample(name: &str) -> Session {
    session::load(&common::sample(name)).expect("sample session")
}

fn request(shards: usize) -> PlanRequest {
    PlanRequest {
        shards,
        source: "sample".into(),
        time_minutes: None,
        cpus: None,
        mem_mb: None,
        partition: None,
        program: "tactile-workbench".into(),
    }
}

/// A small grid on the grasp-stability sample: 3 × 2 dictionaries, 2 gammas, 3 folds.
fn stability_sweep() -> StabilitySweep {
    let mut options = StabilityOptions {
        grid: Some(GridSpec {
            num_bases: vec![2, 4, 6],
            beta: vec![0.5, 1.0],
            gamma: vec![0.5, 1.0],
        }),
        selection_cv: CvScheme::KFold { k: 3 },
        kfold: CvScheme::KFold { k: 3 },
        objects: CvScheme::LeaveObjectsOut { folds: Some(3) },
        ..StabilityOptions::default()
    };
    options.settings.dictionary.max_iter = 20;
    options.settings.cv_seed = 3;
    options.settings.dictionary.seed = 3;
    StabilitySweep {
        data: DataOptions::default(),
        options,
    }
}

fn local_stability(s: &Session, sw: &StabilitySweep) -> Value {
    let data = StabilityData::from_session(s, &sw.data).unwrap();
    let r = stability::run(&data, &sw.options, &Progress::new()).unwrap();
    serde_json::to_value(&r).unwrap()
}

/// Plan into a fresh folder, run every shard (in reverse order: the order must not
/// matter) and merge.
fn sharded(tag: &str, s: &Session, e: Experiment, shards: usize) -> (TempDir, Value) {
    let dir = common::temp_dir(tag).child("plan");
    let plan = sweep::write_plan(&dir, s, e, &request(shards)).unwrap();
    assert_eq!(plan.shard_count(), shards);
    for i in (0..shards).rev() {
        let r = sweep::run_shard(&dir, i, &Progress::new()).unwrap();
        assert!(matches!(r, ShardRun::Done { .. }), "{r:?}");
    }
    let merged = sweep::merge(&dir, &Progress::new()).unwrap();
    (dir, merged.result)
}

fn assert_same(merged: &Value, local: &Value) {
    if let Some(d) = result_difference(merged, local) {
        panic!("merged and local results differ at {d}");
    }
}

#[test]
fn merged_stability_grid_equals_the_local_run() {
    let s = sample("grasp-stability.json");
    let sw = stability_sweep();
    let local = local_stability(&s, &sw);
    let (dir, merged) = sharded("sweep-stability", &s, Experiment::Stability(sw), 4);
    assert_same(&merged, &local);
    // Something to compare: 12 cells, and the sbatch script asks for 4 array tasks.
    assert_eq!(merged["grid"]["cells"].as_array().unwrap().len(), 12);
    let script = fs::read_to_string(dir.join(sweep::SBATCH_FILE)).unwrap();
    assert!(script.contains("#SBATCH --array=0-3\n"), "{script}");
    assert!(script.contains("sweep run"), "{script}");
}

#[test]
fn the_comparison_sees_a_changed_score_but_not_a_timing() {
    let a: Value =
        serde_json::json!({"grid": {"secs": 1.0, "cells": [{"wsr": 0.5, "cv_secs": 2.0}]}});
    let mut b = a.clone();
    b["grid"]["secs"] = 9.0.into();
    b["grid"]["cells"][0]["cv_secs"] = 7.0.into();
    assert_eq!(result_difference(&a, &b), None);
    b["grid"]["cells"][0]["wsr"] = 0.5000001.into();
    let d = result_difference(&a, &b).expect("a difference");
    assert!(d.starts_with(".grid.cells[0].wsr"), "{d}");
}

#[test]
fn merged_robustness_equals_the_local_run() {
    let s = sample("grasp-stability.json");
    let mut p = RobustnessParams::defaults(Family::Stability);
    p.reps = 2;
    p.seed = 5;
    p.stability.config.num_bases = 6;
    p.stability.folds = 3;
    p.stability.settings.dictionary.max_iter = 20;
    p.sweeps = vec![
        Sweep {
            perturbation: Perturbation::Noise,
            strengths: vec![0.5, 2.0],
        },
        Sweep {
            perturbation: Perturbation::DeadTaxels,
            strengths: vec![0.3],
        },
    ];
    let local = serde_json::to_value(run_robustness(&s, &p, &Progress::new()).unwrap()).unwrap();
    let (_, merged) = sharded("sweep-robustness", &s, Experiment::Robustness(p), 3);
    assert_same(&merged, &local);
    assert_eq!(merged["curves"].as_array().unwrap().len(), 4);
}

#[test]
fn merged_clustering_and_recognition_equal_the_local_runs() {
    let s = sample("object-recognition.json");
    let mut c = ClusteringParams {
        thresholds: vec![0.2, 0.6],
        reps: 2,
        seed: 4,
        baseline_max_k: 4,
        ..ClusteringParams::default()
    };
    c.ds.gp.capacity = 15;
    c.ds.gp.tau = 4;
    let local = serde_json::to_value(run_clustering(&s, &c, &Progress::new()).unwrap()).unwrap();
    let (_, merged) = sharded("sweep-clustering", &s, Experiment::Clustering(c), 3);
    assert_same(&merged, &local);
    assert_eq!(merged["runs"].as_array().unwrap().len(), 4);

    let mut r = RecognitionParams {
        reps: 2,
        seed: 2,
        ..RecognitionParams::default()
    };
    r.gs.gp.capacity = 15;
    r.gs.gp.tau = 4;
    let local = serde_json::to_value(run_recognition(&s, &r, &Progress::new()).unwrap()).unwrap();
    let (_, merged) = sharded("sweep-recognition", &s, Experiment::Recognition(r), 2);
    assert_same(&merged, &local);
}

/// The merged frontiers equal the local ones, timings aside; the sizes chosen by time
/// (the recommended one, the Pareto fronts) follow the rule on the merged points' own
/// means, SEs and times.
fn assert_same_frontiers(merged: &Value, local: &[Frontier]) {
    assert_same(merged, &serde_json::to_value(local).unwrap());
    let merged: Vec<Frontier> = serde_json::from_value(merged.clone()).unwrap();
    assert_eq!(merged.len(), local.len());
    for f in &merged {
        let axis = f.params.cost;
        let top = f.points.iter().map(|p| p.score).fold(f64::MIN, f64::max);
        let bar = top - f.points[f.best].score_se;
        let rec = &f.points[f.recommended];
        assert!(rec.score >= bar, "{}: {} below {bar}", f.label(), rec.label);
        assert!(
            f.points
                .iter()
                .filter(|p| p.score >= bar)
                .all(|p| p.cost(axis) >= rec.cost(axis)),
            "{}: a cheaper point is within one SE",
            f.label()
        );
    }
}

#[test]
fn merged_frontiers_equal_the_local_runs() {
    let s = sample("object-recognition.json");
    let frontiers = vec![
        FrontierParams {
            reps: 2,
            seed: 5,
            capacities: vec![2, 5],
            taus: vec![1],
            ..FrontierParams::for_method(MethodId::Ds)
        },
        FrontierParams {
            reps: 2,
            seed: 5,
            thresholds: vec![0.3, 0.6],
            expert_capacity: Some(15),
            expert_tau: Some(4),
            ..FrontierParams::for_method(MethodId::Du)
        },
        FrontierParams {
            reps: 3,
            seed: 5,
            ks: vec![2, 4],
            ..FrontierParams::for_method(MethodId::KMeans)
        },
        FrontierParams {
            reps: 3,
            seed: 5,
            ks: vec![4],
            ..FrontierParams::for_method(MethodId::Som)
        },
        FrontierParams {
            reps: 2,
            seed: 5,
            svm_c: vec![1.0, 10.0],
            svm_gamma: vec![0.01],
            ..FrontierParams::for_method(MethodId::RbfSvm)
        },
    ];
    let local: Vec<Frontier> = frontiers
        .iter()
        .map(|p| run_frontier(&s, p, &Progress::new()).unwrap())
        .collect();
    let (_, merged) = sharded(
        "sweep-frontier",
        &s,
        Experiment::Frontier(FrontierSweep { frontiers }),
        4,
    );
    assert_same_frontiers(&merged, &local);

    let s = sample("grasp-stability.json");
    let sparse = vec![FrontierParams {
        reps: 2,
        num_bases: vec![2, 4],
        beta: vec![1.0],
        gamma: vec![0.5, 1.0],
        ..FrontierParams::for_method(MethodId::SparseSvm)
    }];
    let local = vec![run_frontier(&s, &sparse[0], &Progress::new()).unwrap()];
    let (_, merged) = sharded(
        "sweep-frontier-sparse",
        &s,
        Experiment::Frontier(FrontierSweep { frontiers: sparse }),
        2,
    );
    assert_same_frontiers(&merged, &local);
}

/// A plan of the small stability grid in `tag`, its shards not run.
fn planned(tag: &str, shards: usize) -> (TempDir, Session, StabilitySweep) {
    let s = sample("grasp-stability.json");
    let sw = stability_sweep();
    let dir = common::temp_dir(tag).child("plan");
    sweep::write_plan(
        &dir,
        &s,
        Experiment::Stability(sw.clone()),
        &request(shards),
    )
    .unwrap();
    (dir, s, sw)
}

fn states(dir: &Path) -> Vec<ShardState> {
    sweep::status(dir).unwrap().shards
}

#[test]
fn a_killed_shard_is_missing_until_rerun_and_a_rerun_skips_a_done_shard() {
    let (dir, s, sw) = planned("sweep-killed", 2);
    sweep::run_shard(&dir, 0, &Progress::new()).unwrap();
    let done = fs::read(sweep::shard_path(&dir, 0)).unwrap();
    // Shard 1 was killed while writing: only its temporary file is there, half written.
    let partial = dir.join("shards").join(".1.json.4242.tmp");
    fs::write(&partial, &done[..done.len() / 2]).unwrap();
    let st = states(&dir);
    assert!(matches!(st[0], ShardState::Done { .. }), "{st:?}");
    assert_eq!(st[1], ShardState::Missing { partial: true });
    let err = sweep::merge(&dir, &Progress::new()).err().expect("refused");
    let msg = err.to_string();
    assert!(matches!(err, SweepError::Incomplete(_)), "{msg}");
    assert!(msg.contains("shard 1: missing"), "{msg}");
    assert!(
        msg.contains("sweep run") && msg.contains("--shard 1"),
        "{msg}"
    );
    assert!(msg.contains("sbatch --array=1 "), "{msg}");
    // A rerun of the done shard does nothing; of the killed one, completes it.
    assert_eq!(
        sweep::run_shard(&dir, 0, &Progress::new()).unwrap(),
        ShardRun::Skipped
    );
    assert_eq!(fs::read(sweep::shard_path(&dir, 0)).unwrap(), done);
    assert!(matches!(
        sweep::run_shard(&dir, 1, &Progress::new()).unwrap(),
        ShardRun::Done { .. }
    ));
    assert!(!partial.exists(), "the partial file is cleaned up");
    let merged = sweep::merge(&dir, &Progress::new()).unwrap();
    assert_same(&merged.result, &local_stability(&s, &sw));
}

#[test]
fn a_corrupted_shard_file_is_failed_until_rerun() {
    let (dir, _, _) = planned("sweep-corrupt", 2);
    for i in 0..2 {
        sweep::run_shard(&dir, i, &Progress::new()).unwrap();
    }
    let path = sweep::shard_path(&dir, 1);
    let good = fs::read_to_string(&path).unwrap();
    fs::write(&path, &good[..good.len() - 10]).unwrap();
    let st = states(&dir);
    match &st[1] {
        ShardState::Failed { reason } => assert!(reason.contains("not a shard result"), "{reason}"),
        other => panic!("expected failed, got {other:?}"),
    }
    let msg = sweep::merge(&dir, &Progress::new())
        .err()
        .expect("refused")
        .to_string();
    assert!(msg.contains("shard 1: failed"), "{msg}");
    // Changed numbers with valid JSON are caught too: another plan's hash.
    let edited = good.replacen("\"plan_hash\": \"sha256:", "\"plan_hash\": \"sha256:0", 1);
    fs::write(&path, edited).unwrap();
    assert!(matches!(states(&dir)[1], ShardState::Failed { .. }));
    assert!(matches!(
        sweep::run_shard(&dir, 1, &Progress::new()).unwrap(),
        ShardRun::Done { .. }
    ));
    assert!(matches!(states(&dir)[1], ShardState::Done { .. }));
    assert!(sweep::merge(&dir, &Progress::new()).is_ok());
}

#[test]
fn a_plan_from_another_session_refuses_to_run_and_merge() {
    let (dir, _, _) = planned("sweep-other-session", 2);
    sweep::run_shard(&dir, 0, &Progress::new()).unwrap();
    // The session copy is replaced by another session.
    let other = sample("object-recognition.json");
    fs::write(dir.join("session.json"), session::native::to_string(&other)).unwrap();
    let err = sweep::run_shard(&dir, 1, &Progress::new()).expect_err("refused");
    assert!(matches!(err, SweepError::Mismatch(_)), "{err}");
    assert!(err.to_string().contains("another session"), "{err}");
    assert!(!sweep::shard_path(&dir, 1).exists());
    // A shard of another plan is not taken either.
    let (dir2, _, _) = planned("sweep-other-plan", 2);
    fs::copy(sweep::shard_path(&dir, 0), sweep::shard_path(&dir2, 0)).unwrap();
    let fresh = fs::read_to_string(dir2.join("plan.json")).unwrap();
    fs::write(
        dir2.join("plan.json"),
        fresh.replace("\"source\": \"sample\"", "\"source\": \"elsewhere\""),
    )
    .unwrap();
    match &states(&dir2)[0] {
        ShardState::Failed { reason } => assert!(reason.contains("hash mismatch"), "{reason}"),
        other => panic!("expected failed, got {other:?}"),
    }
}

#[test]
fn a_plan_refuses_more_shards_than_items_and_an_existing_plan() {
    let (dir, s, sw) = planned("sweep-refuse", 2);
    let again = sweep::write_plan(&dir, &s, Experiment::Stability(sw.clone()), &request(2));
    assert!(
        again
            .err()
            .unwrap()
            .to_string()
            .contains("already holds a plan")
    );
    let other = common::temp_dir("sweep-refuse-many").child("plan");
    let many = sweep::write_plan(&other, &s, Experiment::Stability(sw), &request(7));
    let msg = many.err().unwrap().to_string();
    assert!(msg.contains("7 shards for 6 work items"), "{msg}");
}

/// `sweep status` checks the session copy against the plan's hash: a copy changed after
/// the shards ran is an error naming the file, not "done".
#[test]
fn status_refuses_a_changed_session_copy() {
    let (dir, _, _) = planned("sweep-status-session", 1);
    sweep::run_shard(&dir, 0, &Progress::new()).unwrap();
    assert!(matches!(states(&dir)[0], ShardState::Done { .. }));
    let copy = dir.join("session.json");
    let text = fs::read_to_string(&copy).unwrap();
    fs::write(&copy, format!("{text}\n")).unwrap();
    let err = sweep::status(&dir).err().expect("refused");
    let msg = err.to_string();
    assert!(matches!(err, SweepError::Mismatch(_)), "{msg}");
    assert!(
        msg.contains(&copy.display().to_string()) && msg.contains("content hash"),
        "{msg}"
    );
}

/// A shard whose output has the wrong shape (valid JSON, right hashes and items) is failed,
/// naming its file, and the merge's refusal names it too.
#[test]
fn a_shard_output_of_the_wrong_shape_is_failed_naming_the_file() {
    let (dir, _, _) = planned("sweep-shape", 2);
    for i in 0..2 {
        sweep::run_shard(&dir, i, &Progress::new()).unwrap();
    }
    let path = sweep::shard_path(&dir, 1);
    let mut shard: Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    shard["outputs"][0] = Value::String("not an output".into());
    // As a writer of the wrong shape would leave it: its checksum agrees with its outputs.
    let outputs = serde_json::to_vec(&shard["outputs"]).unwrap();
    shard["outputs_checksum"] = tactile_workbench::fsutil::content_hash(&outputs).into();
    fs::write(&path, serde_json::to_string(&shard).unwrap()).unwrap();
    let file = path.display().to_string();
    match &states(&dir)[1] {
        ShardState::Failed { reason } => assert!(
            reason.contains(&file) && reason.contains("not of its shape"),
            "{reason}"
        ),
        other => panic!("expected failed, got {other:?}"),
    }
    let msg = sweep::merge(&dir, &Progress::new())
        .err()
        .expect("refused")
        .to_string();
    assert!(
        msg.contains("shard 1: failed") && msg.contains(&file),
        "{msg}"
    );
}

/// Sets the first `num_bases` found in `v` to `to`; whether one was found.
fn set_num_bases(v: &mut Value, to: u64) -> bool {
    match v {
        Value::Object(map) => {
            if let Some(n) = map.get_mut("num_bases").filter(|n| n.is_u64()) {
                *n = Value::from(to);
                return true;
            }
            map.values_mut().any(|x| set_num_bases(x, to))
        }
        Value::Array(items) => items.iter_mut().any(|x| set_num_bases(x, to)),
        _ => false,
    }
}

/// Size parameters are bounded before anything is allocated for them: a plan whose item
/// claims 10¹² bases, and `stability --num-bases 50000`, are errors naming the parameter
/// and its limit (they aborted the process on a failed allocation).
#[test]
fn absurd_sizes_are_refused_naming_the_parameter_and_its_limit() {
    let (dir, _, _) = planned("sweep-absurd", 1);
    let plan_path = dir.join("plan.json");
    let mut plan: Value = serde_json::from_str(&fs::read_to_string(&plan_path).unwrap()).unwrap();
    assert!(set_num_bases(&mut plan["items"], 1_000_000_000_000));
    fs::write(&plan_path, serde_json::to_string(&plan).unwrap()).unwrap();
    let run = |args: &[&str], path: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .args(args)
            .arg(path)
            .output()
            .unwrap()
    };
    let r = run(&["sweep", "run", "--shard", "0"], &dir);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success(), "{err}");
    assert!(
        err.contains("num_bases` 1000000000000 is above its limit of 4096"),
        "{err}"
    );
    assert!(!sweep::shard_path(&dir, 0).exists());
    let r = run(
        &["stability", "--num-bases", "50000"],
        &common::sample("grasp-stability.json"),
    );
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success(), "{err}");
    assert!(
        err.contains("--num-bases 50000 is above its limit of 4096"),
        "{err}"
    );
}

/// The first number in `v` (depth first), changed by one.
fn nudge_a_number(v: &mut Value) -> bool {
    match v {
        Value::Number(n) => {
            *v = (n.as_f64().unwrap_or(0.0) + 1.0).into();
            true
        }
        Value::Array(items) => items.iter_mut().any(nudge_a_number),
        Value::Object(fields) => fields.values_mut().any(nudge_a_number),
        _ => false,
    }
}

/// A shard's outputs carry their checksum: a number edited by hand is caught by `sweep
/// merge` and `sweep status`, naming the file, and never merged.
#[test]
fn a_shard_edited_by_hand_is_caught_by_its_checksum() {
    let (dir, _, _) = planned("sweep-edited", 2);
    for i in 0..2 {
        sweep::run_shard(&dir, i, &Progress::new()).unwrap();
    }
    let path = sweep::shard_path(&dir, 1);
    let mut shard: Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    assert!(nudge_a_number(&mut shard["outputs"]));
    fs::write(&path, serde_json::to_string_pretty(&shard).unwrap()).unwrap();
    let file = path.display().to_string();
    match &states(&dir)[1] {
        ShardState::Failed { reason } => {
            assert!(
                reason.contains(&file) && reason.contains("checksum"),
                "{reason}"
            )
        }
        other => panic!("expected failed, got {other:?}"),
    }
    let merged = dir.join("merged.json");
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args(["sweep", "merge", "--quiet"])
        .arg(&*dir)
        .arg("-o")
        .arg(&merged)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success(), "{err}");
    assert!(err.contains(&file) && err.contains("checksum"), "{err}");
    assert!(!merged.exists());
}

/// A plan's copy of the session that is not JSON (its hash made to match, as if the plan
/// had been made for it): the sweep's error is the session's, whose source is the parser's.
#[test]
fn a_malformed_session_copy_keeps_the_import_error_as_the_source() {
    use std::error::Error;
    let (dir, _, _) = planned("sweep-bad-session", 1);
    let copy = dir.join("session.json");
    let bad = b"{\"format\": \"tactile-workbench-session\", \"version\": 1, \"session\": {";
    fs::write(&copy, bad).unwrap();
    let (mut plan, _) = sweep::read_plan(&dir).unwrap();
    plan.session.hash = tactile_workbench::fsutil::content_hash(bad);
    let err = sweep::read_session(&dir, &plan).expect_err("a truncated session is refused");
    let msg = err.to_string();
    assert!(msg.contains(&copy.display().to_string()), "{msg}");
    let session = err
        .source()
        .and_then(|s| s.downcast_ref::<tactile_workbench::session::SessionError>())
        .unwrap_or_else(|| panic!("the session's error is the source: {err:?}"));
    let json = session
        .source()
        .and_then(|s| s.downcast_ref::<serde_json::Error>())
        .unwrap_or_else(|| panic!("the parser's error is the session error's source: {session:?}"));
    assert!(json.is_eof(), "{json}");
}
