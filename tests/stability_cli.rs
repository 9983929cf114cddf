//! The `stability` command end to end on the sample session: a small grid, both
//! protocols, machine-readable results; bad arguments are clear errors.

mod common;

use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
}

#[test]
fn stability_writes_machine_readable_results() {
    let dir = common::temp_dir("stability-cli");
    let json = dir.join("out.json");
    let out = bin()
        .args([
            "stability",
            "--quiet",
            "--num-bases",
            "6..12:6",
            "--beta",
            "1",
            "--gamma",
            "0.5,1",
            "--json",
        ])
        .arg(&json)
        .arg(common::sample("grasp-stability.json"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("weighted success rate"), "{stdout}");
    assert!(stdout.contains("leave one object out"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["grid"]["cells"].as_array().unwrap().len(), 4);
    for key in ["best", "parsimonious"] {
        let e = &v[key];
        for score in ["weighted_success_rate", "failure_recall"] {
            for cv in ["kfold", "objects"] {
                let s = e[cv][score].as_f64().unwrap();
                assert!((0.0..=1.0).contains(&s), "{key}.{cv}.{score} = {s}");
            }
        }
        assert!(e["sparsity"].as_f64().unwrap() > 0.0);
        assert!(e["config"]["num_bases"].as_u64().is_some());
    }
    assert!(
        v["baseline"]["kfold"]["weighted_success_rate"]
            .as_f64()
            .is_some()
    );
    assert!(v["grid"]["cells"][0]["dictionary_secs"].as_f64().is_some());
    assert!(v["convention"].as_str().unwrap().contains("beta"));
    assert_eq!(
        v["analyses"]["basis_images"].as_array().unwrap().len(),
        v["parsimonious"]["config"]["num_bases"].as_u64().unwrap() as usize
    );
}

#[test]
fn bad_arguments_are_clear_errors() {
    let sample = common::sample("grasp-stability.json");
    for (args, needle) in [
        (vec!["--cv", "ten"], "--cv"),
        (vec!["--num-bases", "9..3"], "bad range"),
        (vec!["--failure-class", "dropped"], "no class"),
    ] {
        let out = bin()
            .arg("stability")
            .args(&args)
            .arg(&sample)
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}
