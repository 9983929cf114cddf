//! Every method of the registry (`catalogue::classifiers!`) reaches every protocol through
//! its trait alone: `fit`, `evaluate` and `predict` on the command line, the model file, a
//! frontier (and the same frontier sharded by a sweep), and a robustness sweep. The
//! simulated object-recognition sample has ten objects: chance is 0.1, and a method that
//! learned anything scores well above it.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::frontier::{FrontierParams, run_frontier};
use tactile_workbench::experiments::robustness::{
    Family, Perturbation, RobustnessParams, Sweep, run_robustness,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::{self, Session};
use tactile_workbench::sweep::{self, Experiment, FrontierSweep, PlanRequest};

/// Chance on ten objects plus a wide margin.
const BAR: f64 = 0.1 + 0.4;

fn registered() -> Vec<MethodId> {
    MethodId::all()
        .filter(|m| m.classifier().is_some())
        .collect()
}

fn sample() -> Session {
    session::load(&common::sample("object-recognition.json")).expect("sample session")
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(out: &Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn fit_evaluate_and_predict_on_the_command_line() {
    let dir = common::temp_dir("registered-cli");
    let sample = common::sample("object-recognition.json");
    let (train, test) = (dir.join("train.json"), dir.join("test.json"));
    ok(&run(&[
        "subset",
        s(&sample),
        "--trials",
        "1..15",
        "-o",
        s(&train),
    ]));
    ok(&run(&[
        "subset",
        s(&sample),
        "--trials",
        "16..20",
        "-o",
        s(&test),
    ]));
    for m in registered() {
        let model = dir.join(format!("{}.json", m.key()));
        ok(&run(&[
            "fit",
            m.key(),
            s(&train),
            "-o",
            s(&model),
            "--seed",
            "3",
        ]));
        let loaded = tactile_workbench::models::load(&model).unwrap();
        assert_eq!(loaded.provenance.method, m);
        let json = dir.join(format!("{}-eval.json", m.key()));
        ok(&run(&[
            "evaluate",
            s(&model),
            s(&test),
            "--json",
            s(&json),
            "-q",
        ]));
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let acc = r["accuracy"].as_f64().unwrap();
        assert!(acc >= BAR, "{}: held-out accuracy {acc}", m.key());
        let csv = dir.join(format!("{}.csv", m.key()));
        ok(&run(&["predict", s(&model), s(&test), "-o", s(&csv)]));
        let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
        assert_eq!(rows, 1 + 50, "{}: a header and the 50 test grasps", m.key());
        // A size knob that is no number, and an unknown knob, are refused by name.
        let knob = m.info().size_knobs[0].name;
        let bad = run(&[
            "fit",
            m.key(),
            s(&train),
            "-o",
            s(&model),
            &format!("--{knob}"),
            "-1",
        ]);
        assert!(!bad.status.success());
        assert!(String::from_utf8_lossy(&bad.stderr).contains(knob));
    }
}

#[test]
fn frontier_and_its_sharded_sweep_agree() {
    let s = sample();
    for m in registered() {
        let c = m.classifier().unwrap();
        let p = FrontierParams {
            reps: 2,
            sizes: c.sizes().into_iter().take(2).collect(),
            ..FrontierParams::for_method(m)
        };
        let local = run_frontier(&s, &p, &Progress::new()).unwrap();
        assert_eq!(local.points.len(), 2, "{}", m.key());
        let best = &local.points[local.best];
        assert!(
            best.score >= BAR,
            "{}: best size scores {}",
            m.key(),
            best.score
        );
        let dir = common::temp_dir(&format!("registered-sweep-{}", m.key())).child("plan");
        let request = PlanRequest {
            shards: 2,
            source: "sample".into(),
            time_minutes: None,
            cpus: None,
            mem_mb: None,
            partition: None,
            program: "tactile-workbench".into(),
        };
        let e = Experiment::Frontier(FrontierSweep {
            frontiers: vec![p.clone()],
        });
        sweep::write_plan(&dir, &s, e, &request).unwrap();
        for i in 0..2 {
            sweep::run_shard(&dir, i, &Progress::new()).unwrap();
        }
        let merged = sweep::merge(&dir, &Progress::new()).unwrap().result;
        let scores = |v: &serde_json::Value| -> Vec<f64> {
            v["points"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p["score"].as_f64().unwrap())
                .collect()
        };
        let merged = &merged.as_array().unwrap()[0];
        assert_eq!(
            scores(merged),
            scores(&serde_json::to_value(&local).unwrap()),
            "{}",
            m.key()
        );
    }
}

#[test]
fn robustness_curves_start_at_the_clean_score_and_fall_under_dead_taxels() {
    let s = sample();
    for m in registered() {
        let mut p = RobustnessParams::defaults(Family::Recognition);
        p.methods = vec![m];
        p.reps = 2;
        p.recognition.features = m.classifier().unwrap().features();
        p.sweeps = vec![Sweep {
            perturbation: Perturbation::DeadTaxels,
            strengths: vec![0.0, 1.0],
        }];
        let r = run_robustness(&s, &p, &Progress::new()).unwrap();
        let clean = r.clean_score(m).unwrap();
        assert!(clean >= BAR, "{}: clean {clean}", m.key());
        let curve = r.curve(m, Perturbation::DeadTaxels).unwrap();
        let at = |i: usize| curve.points[i].score.mean;
        assert!(
            (at(0) - clean).abs() < 1e-9,
            "{}: strength 0 is clean",
            m.key()
        );
        // Every taxel dead leaves no touch to tell objects by: near chance.
        assert!(
            at(1) < clean - 0.2,
            "{}: all taxels dead {} vs clean {clean}",
            m.key(),
            at(1)
        );
    }
}
