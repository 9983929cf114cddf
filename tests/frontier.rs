//! Speed–accuracy frontiers on the sample sessions: the recommended size is within one
//! standard error of the best and no cheaper size is; the Pareto fronts hold exactly the
//! non-dominated sizes; the same seed gives the same scores; the `frontier` command writes
//! them as JSON and `paper-figures --experiment frontier` exports their figures.

mod common;

use std::process::Command;

use tactile_workbench::experiments::frontier::{
    CostAxis, Frontier, FrontierMethod, FrontierParams, run_frontier,
};
use tactile_workbench::experiments::frontier_report::frontier_figures;
use tactile_workbench::jobs::Progress;
use tactile_workbench::session;

/// The recommendation rule checked by brute force, independently of `recommend`.
fn check_rule(f: &Frontier) {
    let pts = &f.points;
    let top = pts.iter().map(|p| p.score).fold(f64::MIN, f64::max);
    assert_eq!(
        pts[f.best].score, top,
        "the best has the highest mean score"
    );
    let bar = top - pts[f.best].score_se;
    let rec = &pts[f.recommended];
    assert!(
        rec.score >= bar,
        "recommended {} scores {} < best − SE = {bar}",
        rec.label,
        rec.score
    );
    let axis = f.params.cost;
    for p in pts.iter().filter(|p| p.score >= bar) {
        assert!(
            p.cost(axis) >= rec.cost(axis),
            "{} is within one SE ({} ≥ {bar}) and cheaper ({} < {} µs) than the recommended {}",
            p.label,
            p.score,
            p.cost(axis),
            rec.cost(axis),
            rec.label
        );
    }
    for (front, axis) in [
        (&f.pareto_prediction, CostAxis::Prediction),
        (&f.pareto_training, CostAxis::Training),
    ] {
        for (i, p) in pts.iter().enumerate() {
            let dominated = pts.iter().any(|q| {
                q.cost(axis) <= p.cost(axis)
                    && q.score >= p.score
                    && (q.cost(axis) < p.cost(axis) || q.score > p.score)
            });
            assert_eq!(
                front.contains(&i),
                !dominated,
                "{} on the {axis:?} front",
                p.label
            );
        }
    }
    for p in pts {
        assert!(
            p.score_se > 0.0 || p.score == 1.0,
            "{}: SE over reps",
            p.label
        );
        assert!(p.train_us > 0.0 && p.predict_us > 0.0, "{}: timed", p.label);
        assert_eq!(p.reps, f.params.reps);
    }
}

#[test]
fn gs_frontier_on_the_recognition_sample_recommends_by_the_one_se_rule() {
    let s = session::load(&common::sample("object-recognition.json")).unwrap();
    let params = FrontierParams {
        reps: 3,
        capacities: vec![2, 10, 50],
        taus: vec![1, 15],
        ..FrontierParams::for_method(FrontierMethod::Gs)
    };
    let f = run_frontier(&s, &params, &Progress::new()).unwrap();
    assert_eq!(f.points.len(), 6);
    assert_eq!(f.unit, "step");
    assert_eq!(f.points[f.paper_default.unwrap()].label, "50·15");
    check_rule(&f);
    // Chance on the sample's classes is far below what any size reaches.
    assert!(f.points[f.best].score > 0.5, "{}", f.points[f.best].score);
    let again = run_frontier(&s, &params, &Progress::new()).unwrap();
    let scores = |f: &Frontier| f.points.iter().map(|p| p.score).collect::<Vec<_>>();
    assert_eq!(scores(&f), scores(&again), "seeded");
    let figures = frontier_figures(&[f]);
    assert_eq!(figures.len(), 2);
    for (_, fig) in &figures {
        fig.validate().unwrap();
    }
}

#[test]
fn sparse_coding_frontier_keeps_the_best_beta_gamma_per_num_bases() {
    let s = session::load(&common::sample("grasp-stability.json")).unwrap();
    let params = FrontierParams {
        reps: 3,
        num_bases: vec![2, 6, 29],
        beta: vec![1.0],
        gamma: vec![0.5, 1.0],
        ..FrontierParams::for_method(FrontierMethod::SparseSvm)
    };
    let f = run_frontier(&s, &params, &Progress::new()).unwrap();
    assert_eq!(f.unit, "grasp");
    let ks: Vec<f64> = f
        .points
        .iter()
        .map(|p| p.knob("num_bases").unwrap())
        .collect();
    assert_eq!(ks, vec![2.0, 6.0, 29.0]);
    assert_eq!(f.paper_default, Some(2));
    for p in &f.points {
        assert!([0.5, 1.0].contains(&p.knob("gamma").unwrap()));
    }
    check_rule(&f);
    // Two balanced classes: chance is 0.5.
    assert!(f.points[f.best].score > 0.6, "{}", f.points[f.best].score);
}

#[test]
fn the_frontier_command_writes_json_and_rejects_unknown_methods() {
    let dir = common::temp_dir("frontier-cli");
    let json = dir.join("f.json");
    let bin = env!("CARGO_BIN_EXE_tactile-workbench");
    let out = Command::new(bin)
        .args([
            "frontier",
            "--method",
            "ds",
            "--reps",
            "2",
            "--capacities",
            "2,5",
            "--taus",
            "1",
            "--json",
        ])
        .arg(&json)
        .arg(common::sample("object-recognition.json"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("RECOMMENDED"), "{stdout}");
    let back: Vec<Frontier> =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(back.len(), 1);
    assert_eq!(back[0].points.len(), 2);
    // `recognition --frontier` runs the recommended size and says so.
    let rec = &back[0].points[back[0].recommended];
    let out = Command::new(bin)
        .args([
            "recognition",
            "--learner",
            "ds",
            "--reps",
            "2",
            "--frontier",
        ])
        .arg(&json)
        .arg(common::sample("object-recognition.json"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let expected = format!(
        "capacity {}, tau {} (recommended)",
        rec.knob("capacity").unwrap(),
        rec.knob("tau").unwrap()
    );
    assert!(stdout.contains(&expected), "{expected} in {stdout}");
    let out = Command::new(bin)
        .args([
            "recognition",
            "--learner",
            "gs",
            "--reps",
            "2",
            "--frontier",
        ])
        .arg(&json)
        .arg(common::sample("object-recognition.json"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("holds no GS frontier on all features"),
        "{err}"
    );
    let out = Command::new(bin)
        .args(["frontier", "--method", "svm"])
        .arg(common::sample("object-recognition.json"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`svm` is not ds, gs or sparse-svm"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}
