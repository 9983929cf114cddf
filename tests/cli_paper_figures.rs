//! `paper-figures` runs an experiment headless and writes every figure with an index.

mod common;

use tactile_workbench::cli::paper_figures::{Experiment, PaperFiguresArgs, run};

#[test]
fn baselines_figures_are_written_with_an_index() {
    let out = common::temp_dir("paper-figures");
    run(PaperFiguresArgs {
        session: common::sample("object-recognition.json"),
        experiment: Experiment::Baselines,
        out_dir: out.clone(),
        reps: 2,
        seed: 3,
        width: 640,
        height: 420,
        dpi: 96.0,
    })
    .expect("paper-figures");
    let index = std::fs::read_to_string(out.join("index.md")).unwrap();
    for title in [
        "NMI against effective clusters",
        "Clustering scores at k = 10",
        "RBF SVM accuracy over C × γ",
    ] {
        assert!(index.contains(title), "index lacks {title}");
    }
    let svg = std::fs::read_to_string(out.join("01-baselines-k-10-scores.svg")).unwrap();
    assert!(svg.contains("sequential k-means") && svg.contains("SOM"));
    let csv = std::fs::read_to_string(out.join("01-baselines-k-10-scores.csv")).unwrap();
    assert!(csv.lines().count() >= 4, "{csv}");
    let png = std::fs::read(out.join("01-baselines-k-10-scores.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let _ = std::fs::remove_dir_all(out);
}
