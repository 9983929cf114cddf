//! The researcher's inputs and target for the OIESGP protocols: `recognition` runs by
//! default on a one-sensor session without encoders, and `--target` chooses the label set
//! whose classes are learned and scored (a planted label set where the answer is known).

mod common;

use std::process::Command;

use tactile_workbench::experiments::clustering::{ClusteringParams, run_clustering};
use tactile_workbench::experiments::recognition::{
    RecognitionParams, SupervisedLearner, run_recognition,
};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::{LabelSet, Session, save, simulate};

/// The simulated recognition session cut to one fingertip, no encoders and 4 grasps of each
/// of its 10 objects.
fn one_sensor_session() -> Session {
    let mut s = simulate::object_recognition(2);
    s.meta.name = "one fingertip".into();
    s.sensors.truncate(1);
    s.encoders.clear();
    let per_object = simulate::RECOGNITION_GRASPS;
    s.grasps = s
        .grasps
        .into_iter()
        .enumerate()
        .filter(|(g, _)| g % per_object < 4)
        .map(|(_, mut g)| {
            for f in &mut g.frames {
                f.taxels.truncate(1);
                f.encoders.clear();
            }
            g
        })
        .collect();
    s
}

/// The session with a planted label set `name` giving grasp g the class `class(object)`.
fn planted(mut s: Session, name: &str, classes: usize, class: impl Fn(usize) -> usize) -> Session {
    let object = s.label_set("object").unwrap();
    s.label_sets.push(LabelSet {
        name: name.into(),
        classes: (0..classes).map(|c| format!("{name} {c}")).collect(),
    });
    for g in &mut s.grasps {
        let c = class(g.labels[object]);
        g.labels.push(c);
    }
    s
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
}

#[test]
fn recognition_runs_by_default_on_one_sensor_without_encoders() {
    let dir = common::temp_dir("recognition-inputs");
    let path = dir.join("one-fingertip.json");
    save(&one_sensor_session(), &path).unwrap();
    let out = bin()
        .args(["recognition", "--quiet", "--reps", "1", "--tau", "3"])
        .arg(&path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The default chooses the inputs by cross validation; `all` is the moments here.
    assert!(stdout.contains("auto chose"), "{stdout}");
    assert!(stdout.contains("target object"), "{stdout}");
    let out = bin()
        .args(["recognition", "--quiet", "--reps", "1", "--tau", "3"])
        .args(["--features", "all"])
        .arg(&path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("all features (moments)"), "{stdout}");
    // An explicit family the session lacks, or a label set it lacks, is a clear error.
    for (args, says) in [
        (["--features", "encoders"], "no joint encoders"),
        (
            ["--target", "colour"],
            "no label set `colour`; its label sets: object",
        ),
    ] {
        let out = bin()
            .args(["recognition", "--quiet", "--reps", "1"])
            .args(args)
            .arg(&path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(says), "{stderr}");
    }
}

#[test]
fn the_target_label_set_holds_the_classes_learned_and_scored() {
    // Objects 2k and 2k + 1 form pair k: five classes, each grasp's known.
    let s = planted(one_sensor_session(), "pair", 5, |object| object / 2);
    let pair = s.label_set("pair").unwrap();
    let p = RecognitionParams {
        learner: SupervisedLearner::Ds,
        features: FeatureSet::ALL,
        reps: 1,
        label_set: "pair".into(),
        ..RecognitionParams::default()
    };
    let r = run_recognition(&s, &p, &Progress::new()).unwrap();
    assert_eq!(r.classes, s.label_sets[pair].classes);
    assert_eq!(r.summary.confusion.len(), 5);
    // Every grasp but the five taught first is predicted, against its pair.
    let predictions = &r.repetitions[0].predictions;
    assert_eq!(predictions.len(), s.grasps.len() - 5);
    for q in predictions {
        assert_eq!(q.truth, s.grasps[q.grasp].labels[pair]);
    }
}

#[test]
fn clusters_are_scored_against_the_target() {
    // One class holding every grasp: every clustering is pure (purity 1, first principles);
    // against the ten objects the same clusterings are not.
    let s = planted(one_sensor_session(), "one", 1, |_| 0);
    let run = |target: &str| {
        let p = ClusteringParams {
            thresholds: vec![0.2, 0.6],
            reps: 1,
            baseline_max_k: 3,
            label_set: target.into(),
            ..ClusteringParams::default()
        };
        run_clustering(&s, &p, &Progress::new()).unwrap()
    };
    let one = run("one");
    assert_eq!(one.labels, vec![0; s.grasps.len()]);
    assert!(!one.runs.is_empty() && !one.kmeans.is_empty());
    assert!(one.runs.iter().all(|r| r.purity == 1.0));
    assert!(one.kmeans.iter().all(|k| k.purity.mean == 1.0));
    let object = run("object");
    assert!(object.runs.iter().any(|r| r.purity < 1.0));
}
