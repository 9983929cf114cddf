//! How far the window's time estimates are from the runs they estimate.
//!
//! Every form's run, as the window starts it (`Room::run`: the same work and the same cost
//! model), on the sample sessions, BTS3 palm-down and iCub (the real datasets are skipped
//! when absent), on a fresh machine (no measured correction yet). For each run:
//!
//! - the first estimate: what the form says before Run;
//! - the estimate a fifth of the way through: elapsed time plus the time left the progress
//!   bar shows when a fifth of the run's actual time has passed;
//! - the actual time.
//!
//! The targets (issue "Figures that read at every tile size", item 6): the first within 2×
//! of the actual time, the one at a fifth within 1.5×.
//!
//! Run: `cargo bench --profile dev --bench estimates [-- WORDS]`: only the runs whose
//! "dataset run" line holds every word (`-- icub frontier`).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tactile_workbench::app::View;
use tactile_workbench::app::results::Analyses;
use tactile_workbench::app::views::Rooms;
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::clustering::UnsupervisedLearner;
use tactile_workbench::experiments::recognition::SupervisedLearner;
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::{self, Session};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The sessions measured: the samples always, the real datasets when present.
fn sessions() -> Vec<(&'static str, Arc<Session>)> {
    let datasets = root().join("../shared/datasets");
    let mut out = Vec::new();
    for (name, path) in [
        (
            "sample stability",
            root().join("sample-sessions/grasp-stability.json"),
        ),
        (
            "sample recognition",
            root().join("sample-sessions/object-recognition.json"),
        ),
        ("BTS3", datasets.join("bts3/biotac-palmdown-grasps.csv")),
        ("iCub", datasets.join("icub-grasp")),
    ] {
        if !path.exists() {
            eprintln!("{name}: {} is absent, skipped", path.display());
            continue;
        }
        match session::open(&path) {
            Ok(s) => out.push((name, Arc::new(s))),
            Err(e) => eprintln!("{name}: {e}"),
        }
    }
    out
}

/// The forms measured: each analysis view at its defaults, and the choices that make a
/// run of another timed kind (the other learner, a grid, the frontier of each family).
fn variants() -> Vec<(String, View, Rooms)> {
    let mut out = Vec::new();
    for view in [
        View::Stability,
        View::Recognition,
        View::Clustering,
        View::Baselines,
        View::Robustness,
    ] {
        out.push((view.title().to_string(), view, Rooms::default()));
    }
    let mut gs = Rooms::default();
    gs.recognition.form.learner = SupervisedLearner::Gs;
    out.push(("Recognition GS".into(), View::Recognition, gs));
    let mut gu = Rooms::default();
    gu.clustering.form.learner = UnsupervisedLearner::Gu;
    gu.clustering.form.thresholds =
        tactile_workbench::app::views::clustering::ClusteringForm::suggested_thresholds(
            UnsupervisedLearner::Gu,
        );
    out.push(("Clustering GU".into(), View::Clustering, gu));
    let mut grid = Rooms::default();
    grid.stability.form.grid = true;
    out.push(("Grasp stability grid".into(), View::Stability, grid));
    for method in [MethodId::Ds, MethodId::SparseSvm] {
        let mut f = Rooms::default();
        f.speed.frontier.method = method;
        out.push((format!("Frontier {}", method.key()), View::SpeedAccuracy, f));
    }
    out
}

struct Measured {
    first: f64,
    at_fifth: Option<f64>,
    actual: f64,
}

/// Run `work` as the window would, watching its progress bar.
fn measure(
    run: tactile_workbench::app::views::Run,
    analyses: &Analyses,
) -> Result<Measured, String> {
    let first = run.estimate.expected(&analyses.timings);
    let progress = Progress::new();
    progress.set_expected(first);
    let p = progress.clone();
    let work = run.work;
    let worker = std::thread::spawn(move || work(&p).map(|_| ()).map_err(|e| format!("{e:?}")));
    // (elapsed, elapsed + time left) as the bar shows them, every few milliseconds.
    let mut seen = Vec::new();
    while !worker.is_finished() {
        if let Some(left) = progress.eta_secs() {
            let now = progress.elapsed_secs();
            seen.push((now, now + left));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let actual = progress.elapsed_secs();
    let at_fifth = seen
        .iter()
        .take_while(|(t, _)| *t <= 0.2 * actual)
        .last()
        .map(|&(_, total)| total);
    worker
        .join()
        .map_err(|_| "the run panicked".to_string())??;
    Ok(Measured {
        first,
        at_fifth,
        actual,
    })
}

fn ratio(estimate: f64, actual: f64) -> f64 {
    (estimate / actual).max(actual / estimate)
}

fn main() {
    let words: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .map(|a| a.to_lowercase())
        .collect();
    let analyses = Analyses::default();
    println!("| session | run | first estimate | actual | × | estimate at 1/5 | × | targets |");
    println!("|---|---|---:|---:|---:|---:|---:|---|");
    let (mut met, mut missed) = (0, 0);
    for (name, session) in sessions() {
        for (what, view, mut rooms) in variants() {
            let line = format!("{name} {what}").to_lowercase();
            if !words.iter().all(|w| line.contains(w.as_str())) {
                continue;
            }
            let Some(run) = rooms.get(view).run(&session, &analyses) else {
                continue;
            };
            match measure(run, &analyses) {
                Ok(m) => {
                    let first = ratio(m.first, m.actual);
                    let fifth = m.at_fifth.map(|e| ratio(e, m.actual));
                    let ok = first <= 2.0 && fifth.is_some_and(|f| f <= 1.5);
                    if ok {
                        met += 1;
                    } else {
                        missed += 1;
                    }
                    println!(
                        "| {name} | {what} | {:.1} s | {:.1} s | {first:.2} | {} | {} | {} |",
                        m.first,
                        m.actual,
                        m.at_fifth.map_or("–".into(), |e| format!("{e:.1} s")),
                        fifth.map_or("–".into(), |f| format!("{f:.2}")),
                        if ok { "met" } else { "missed" }
                    );
                }
                Err(e) => println!("| {name} | {what} | failed: {e} | | | | | |"),
            }
        }
    }
    println!("\n{met} runs met both targets, {missed} missed one.");
}
