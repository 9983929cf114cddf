//! `paper-figures` runs an experiment headless and writes every figure with an index.

mod common;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::cli::paper_figures::{Experiment, PaperFiguresArgs, run};
use tactile_workbench::experiments::figure_id::FigureId;

#[test]
fn baselines_figures_are_written_with_an_index() {
    let out = common::temp_dir("paper-figures");
    run(PaperFiguresArgs {
        session: common::sample("object-recognition.json"),
        experiment: Experiment::Baselines,
        out_dir: out.to_path_buf(),
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
        out_dir: out.to_path_buf(),
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
    let p = tactile_workbench::project::Project::load(&project).unwrap();
    let r = &p.results[0];
    let bases = r.details_of(FigureId::BasesRaw).expect("basis details");
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
        out_dir: out.to_path_buf(),
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
    let p = tactile_workbench::project::Project::load(&project).unwrap();
    assert_eq!(p.frontiers.len(), 1);
    assert_eq!(p.frontiers[0].params.method, MethodId::SparseSvm);
    let _ = std::fs::remove_dir_all(out);
}

/// A `paper-figures` run killed while writing its figures (by a file-size limit, as in
/// tests/atomic_write_kill.rs) leaves no output folder, so never one without its index;
/// the next run writes the folder whole and removes what the killed one left.
#[cfg(unix)]
#[test]
fn a_killed_run_leaves_no_folder_without_its_index() {
    let dir = common::temp_dir("paper-figures-kill");
    let out = dir.join("figures");
    let run = |limit: &str| {
        std::process::Command::new("sh")
            .args([
                "-c",
                "ulimit -c 0; ulimit -f \"$1\"; shift; exec \"$@\"",
                "sh",
                limit,
                env!("CARGO_BIN_EXE_tactile-workbench"),
                "paper-figures",
            ])
            .arg(common::sample("object-recognition.json"))
            .args(["--experiment", "baselines", "--reps", "2", "--quiet", "-o"])
            .arg(&out)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap()
    };
    // 16 blocks of 512 bytes: the first PNG figure is larger.
    assert!(!run("16").success(), "the run should have been stopped");
    assert!(!out.exists(), "a killed run left {}", out.display());
    assert!(run("unlimited").success());
    assert!(out.join("index.md").is_file());
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["figures"], "temporary folders left");
    let _ = std::fs::remove_dir_all(dir);
}
