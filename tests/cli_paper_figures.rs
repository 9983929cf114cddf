//! `paper-figures` runs an experiment headless and writes every figure with an index.

mod common;

use tactile_workbench::cli::paper_figures::{Experiment, PaperFiguresArgs, run};
use tactile_workbench::experiments::frontier::FrontierMethod;

#[test]
fn baselines_figures_are_written_with_an_index() {
    let out = common::temp_dir("paper-figures");
    run(PaperFiguresArgs {
        session: common::sample("object-recognition.json"),
        experiment: Experiment::Baselines,
        out_dir: out.clone(),
        reps: 2,
        seed: 3,
        preset: None,
        width: 640,
        height: 420,
        dpi: 96.0,
        project: None,
        quiet: true,
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

#[test]
fn stability_figures_and_project_regenerate_the_first_paper() {
    let out = common::temp_dir("paper-figures-stability");
    let project = out.join("project.json");
    run(PaperFiguresArgs {
        session: common::sample("grasp-stability.json"),
        experiment: Experiment::Stability,
        out_dir: out.clone(),
        reps: 1,
        seed: 0,
        preset: None,
        width: 640,
        height: 420,
        dpi: 96.0,
        project: Some(project.clone()),
        quiet: true,
    })
    .expect("paper-figures");
    let index = std::fs::read_to_string(out.join("index.md")).unwrap();
    for title in [
        "Weighted success rate against the number of bases",
        "Basis images",
        "Basis usage per label",
        "Coefficient differential",
        "A patch and its reconstruction",
    ] {
        assert!(index.contains(title), "index lacks {title}");
    }
    // The project re-opens with the figures and the per-basis details.
    let p = tactile_workbench::experiments::report::Project::load(&project).unwrap();
    let r = &p.results[0];
    let bases = r.details_of("bases-raw").expect("basis details");
    assert_eq!(
        bases.items.len(),
        r.parameters["num_bases"].parse::<usize>().unwrap()
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn a_frontier_project_carries_its_frontiers() {
    let out = common::temp_dir("paper-figures-frontier");
    let project = out.join("project.json");
    run(PaperFiguresArgs {
        session: common::sample("grasp-stability.json"),
        experiment: Experiment::Frontier,
        out_dir: out.clone(),
        reps: 2,
        seed: 0,
        preset: None,
        width: 640,
        height: 420,
        dpi: 96.0,
        project: Some(project.clone()),
        quiet: true,
    })
    .expect("paper-figures");
    // The workbench shows a project's frontiers in its speed view: they must be in it.
    let p = tactile_workbench::experiments::report::Project::load(&project).unwrap();
    assert_eq!(p.frontiers.len(), 1);
    assert_eq!(p.frontiers[0].params.method, FrontierMethod::SparseSvm);
    let _ = std::fs::remove_dir_all(out);
}
