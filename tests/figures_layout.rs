//! Every figure the experiments make stays legible at tile size: rendered at 300 × 200
//! (a tile of the workbench) and at the journal-column preset, no two texts overprint,
//! every numeric axis and colour bar shows at least three tick labels, every category axis
//! shows at least three of its names (all of them when it has fewer), and the legend
//! covers no data point. One check, run on every figure of both sample sessions.

mod common;

use common::legibility::{legibility_problems, sizes};
use tactile_workbench::cli::paper_figures::{Experiment, PaperFiguresArgs, figures};
use tactile_workbench::figures::{Axis, Figure, FigureSet, RenderOptions, Series, layout_of};

fn check_all(set: &FigureSet) {
    assert!(!set.entries.is_empty());
    let mut report = Vec::new();
    // The speed charts' time axes are this run's measured times: any span must read, as
    // `every_log_time_span_reads_at_every_size` checks over a grid of spans.
    for e in &set.entries {
        for (size, opts) in sizes() {
            for p in legibility_problems(&e.figure, &opts) {
                report.push(format!("{} at {size}: {p}", e.name));
            }
        }
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
}

fn experiment_figures(session: &str, experiment: Experiment, reps: usize) -> FigureSet {
    figures(&PaperFiguresArgs {
        session: common::sample(session),
        experiment,
        out_dir: std::env::temp_dir(),
        reps,
        seed: 1,
        preset: None,
        width: 300,
        height: 200,
        dpi: 96.0,
        project: None,
        quiet: true,
    })
    .expect("the experiment runs")
}

#[test]
fn recognition_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "object-recognition.json",
        Experiment::Recognition,
        1,
    ));
}

#[test]
fn clustering_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "object-recognition.json",
        Experiment::Clustering,
        1,
    ));
}

#[test]
fn baselines_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "object-recognition.json",
        Experiment::Baselines,
        1,
    ));
}

#[test]
fn stability_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "grasp-stability.json",
        Experiment::Stability,
        1,
    ));
}

#[test]
fn robustness_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "grasp-stability.json",
        Experiment::RobustnessStability,
        1,
    ));
    check_all(&experiment_figures(
        "object-recognition.json",
        Experiment::RobustnessRecognition,
        1,
    ));
}

#[test]
fn frontier_figures_read_at_tile_size() {
    check_all(&experiment_figures(
        "grasp-stability.json",
        Experiment::Frontier,
        2,
    ));
    check_all(&experiment_figures(
        "object-recognition.json",
        Experiment::Frontier,
        2,
    ));
}

fn chart(x: Vec<f64>, y: Vec<f64>) -> Figure {
    Figure::chart(
        "absurd",
        Axis::new("x", ""),
        Axis::new("y", ""),
        vec![Series::new("s", x, y)],
    )
}

/// Values spanning more than f64 can subtract are refused with the axis named (before the
/// fix, the tick loop ran for minutes).
#[test]
fn an_unbounded_range_is_refused() {
    let err = layout_of(
        &chart(vec![-1e308, 1e308], vec![0.0, 1.0]),
        &RenderOptions::default(),
    )
    .expect_err("a span of 2e308 cannot be drawn");
    assert!(err.to_string().contains("\"x\""), "{err}");
}

/// A range far narrower than its magnitude (1e20 … 1e20 + 65536, below f64's resolution
/// there) still gets a handful of ticks, not billions.
#[test]
fn a_range_below_resolution_gets_few_ticks() {
    let layout = layout_of(
        &chart(vec![0.0, 1.0], vec![1e20, 1e20 + 65536.0]),
        &RenderOptions::default(),
    );
    if let Ok(l) = layout {
        let y = l.axes.iter().find(|a| a.title == "y").expect("a y axis");
        assert!(y.labels.len() <= 20, "{:?}", y.labels);
    }
}

/// Times on a log axis, as the speed charts draw them: whatever span the measured times
/// happen to cover (from microseconds to hours, from a tenth of a decade to many), every
/// size shows at least three tick labels and nothing overprints.
#[test]
fn every_log_time_span_reads_at_every_size() {
    let mut report = Vec::new();
    let starts = (-96..=48).map(|k| 10f64.powf(k as f64 / 16.0));
    for lo in starts {
        for ratio in (1..=48).map(|k| 10f64.powf(k as f64 / 8.0)) {
            let hi = lo * ratio;
            let mut fig = Figure::chart(
                "Speed against accuracy",
                Axis::new("training time", "s").log(),
                Axis::new("score", ""),
                vec![
                    Series::new(
                        "models",
                        vec![lo, (lo * hi).sqrt(), hi],
                        vec![0.7, 0.8, 0.9],
                    )
                    .style(tactile_workbench::figures::SeriesStyle::Markers)
                    .labels(vec![
                        "DS".into(),
                        "GS".into(),
                        "sparse coding + SVM".into(),
                    ]),
                ],
            );
            fig.subtitle = None;
            for (size, opts) in sizes() {
                for p in legibility_problems(&fig, &opts) {
                    report.push(format!("{lo:.3e}..{hi:.3e} at {size}: {p}"));
                }
            }
        }
    }
    assert!(report.is_empty(), "{}\n{}", report.len(), report.join("\n"));
}
