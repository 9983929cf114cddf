//! `fit`, `evaluate`, `predict` and `subset` end to end on the grasp-stability sample: a
//! model trained on some objects is tested on the others; outputs are never an input.

mod common;

use std::path::Path;
use std::process::{Command, Output};

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
fn a_model_fitted_on_some_objects_is_evaluated_on_the_others() {
    let dir = common::temp_dir("models-cli");
    let sample = common::sample("grasp-stability.json");
    let session: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sample).unwrap()).unwrap();
    let mut objects: Vec<String> = session["session"]["grasps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["object"].as_str().unwrap().to_string())
        .collect();
    objects.dedup();
    let (train_objects, test_objects) = objects.split_at(objects.len() * 2 / 3);
    let train = dir.join("train.json");
    let test = dir.join("test.json");
    for (file, part) in [(&train, train_objects), (&test, test_objects)] {
        let stdout = ok(&run(&[
            "subset",
            s(&sample),
            "--objects",
            &part.join(","),
            "-o",
            s(file),
        ]));
        assert!(
            stdout.contains(&format!("objects {}", part.join(", "))),
            "{stdout}"
        );
    }
    let model = dir.join("model.json");
    let stdout = ok(&run(&[
        "fit",
        "raw-svm",
        s(&train),
        "-o",
        s(&model),
        "--quiet",
    ]));
    assert!(stdout.contains("raw linear SVM"), "{stdout}");
    let text = std::fs::read_to_string(&model).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(m["format"], "tactile-workbench-model");
    assert_eq!(m["version"], 1);
    assert_eq!(m["provenance"]["session"]["name"], "train");
    assert!(
        m["provenance"]["session"]["hash"]
            .as_str()
            .unwrap()
            .starts_with("sha256:")
    );

    let json = dir.join("held-out.json");
    let figures = dir.join("figures");
    ok(&run(&[
        "evaluate",
        s(&model),
        s(&test),
        "--calibration",
        "none",
        "--json",
        s(&json),
        "--figures",
        s(&figures),
    ]));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let wsr = r["weighted_success_rate"].as_f64().unwrap();
    // New objects of the same simulated hand: above chance (0.5) by a clear margin.
    assert!(wsr > 0.6, "held-out weighted success rate {wsr}");
    assert_eq!(r["calibration"], "none");
    let test_grasps = r["tested_on"]["grasps"].as_u64().unwrap() as usize;
    assert_eq!(r["predictions"].as_array().unwrap().len(), test_grasps);
    assert!(figures.join("index.md").exists());
    let names: Vec<String> = std::fs::read_dir(&figures)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    for kind in ["confusion.svg", "confusion.png", "objects.csv"] {
        assert!(
            names.iter().any(|n| n.ends_with(kind)),
            "{kind} in {names:?}"
        );
    }

    let csv = dir.join("predictions.csv");
    ok(&run(&["predict", s(&model), s(&test), "-o", s(&csv)]));
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(rows.lines().count(), test_grasps + 1);
    assert!(rows.starts_with("grasp,object,trial,truth,predicted,decision"));

    // An output that is an input is refused before any work, and the input survives.
    let out = run(&["predict", s(&model), s(&test), "-o", s(&model)]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read_to_string(&model).unwrap(), text);
    // A model file that is not one names the file.
    let out = run(&["evaluate", s(&test), s(&test)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("test.json"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn baselines_save_each_baseline_fitted_with_the_runs_settings() {
    let dir = common::temp_dir("models-cli-baselines");
    let sample = common::sample("object-recognition.json");
    let (train, test) = (dir.join("train.json"), dir.join("test.json"));
    for (file, trials) in [(&train, "1..15"), (&test, "16..20")] {
        ok(&run(&[
            "subset",
            s(&sample),
            "--trials",
            trials,
            "-o",
            s(file),
        ]));
    }
    let model = dir.join("table-one.json");
    let json = dir.join("baselines.json");
    let stdout = ok(&run(&[
        "baselines",
        s(&train),
        "--orders",
        "3",
        "--no-sweep",
        "--cv-repeats",
        "1",
        "--json",
        s(&json),
        "--save-model",
        s(&model),
    ]));
    let run_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for (key, scores) in [("kmeans", "kmeans"), ("som", "som"), ("rbf-svm", "svm")] {
        let path = dir.join(format!("table-one.{key}.json"));
        assert!(stdout.contains(s(&path)), "{stdout}");
        let file: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let p = &file["provenance"];
        assert_eq!(p["method"], key.replace('-', "_"));
        // Selected by the run's own scores.
        let first = &p["selection"][0];
        let want = if key == "rbf-svm" {
            &run_json[scores]["best"]["accuracy_mean"]
        } else {
            &run_json[scores]["mean"]["purity"]
        };
        assert_eq!(&first["value"], want, "{key}");
        // Tested on the later trials: the RBF SVM well above the 1-in-10 chance, the
        // clusterers scored.
        let eval = ok(&run(&["evaluate", s(&path), s(&test)]));
        let score = if key == "rbf-svm" {
            "accuracy"
        } else {
            "purity"
        };
        assert!(eval.contains(score), "{eval}");
    }
    let svm = dir.join("svm-eval.json");
    ok(&run(&[
        "evaluate",
        s(&dir.join("table-one.rbf-svm.json")),
        s(&test),
        "--json",
        s(&svm),
    ]));
    let held: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&svm).unwrap()).unwrap();
    assert!(held["accuracy"].as_f64().unwrap() > 0.5, "{held}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn more_clusters_than_grasps_are_refused_by_name_before_any_work() {
    let sample = common::sample("object-recognition.json");
    for args in [
        vec![
            "baselines",
            s(&sample),
            "--k",
            "500",
            "--som-rows",
            "1",
            "--som-cols",
            "500",
        ],
        vec!["baselines", s(&sample), "--k-sweep", "5,300"],
        vec![
            "fit",
            "kmeans",
            s(&sample),
            "--k",
            "300",
            "-o",
            "never.json",
        ],
    ] {
        let out = run(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        let flag = if args.contains(&"--k-sweep") {
            "--k-sweep 300"
        } else {
            "--k "
        };
        assert!(
            err.contains(flag) && err.contains("above the session's 200 grasps"),
            "{args:?}: {err}"
        );
    }
    assert!(!Path::new("never.json").exists());
}
