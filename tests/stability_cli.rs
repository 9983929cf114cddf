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
            "10..11:1",
            "--beta",
            "0.5,1",
            "--gamma",
            "0.25",
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
    // Independent bars: every weighted success rate beats chance (0.5) by 0.10, four
    // standard errors on 540 grasps with 135 failures, and every failure recall beats
    // chance by as much (its standard error on 135 failures is about 0.04 at 0.5). The
    // recorded scores themselves are the pipeline test's regression check.
    for key in ["best", "parsimonious", "baseline"] {
        for cv in ["kfold", "objects"] {
            let got = v[key][cv]["weighted_success_rate"].as_f64().unwrap();
            assert!(got >= 0.6, "{key}.{cv}: weighted success rate {got:.4}");
            let got = v[key][cv]["failure_recall"].as_f64().unwrap();
            assert!(got >= 0.6, "{key}.{cv}: failure recall {got:.4}");
        }
    }
    for key in ["best", "parsimonious"] {
        assert!(v[key]["sparsity"].as_f64().unwrap() > 0.0);
    }
    // The recommended cell never has more bases than the best.
    let bases = |key: &str| v[key]["config"]["num_bases"].as_u64().unwrap();
    assert!(bases("parsimonious") <= bases("best"));
    assert!((10..=11).contains(&bases("best")));
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
