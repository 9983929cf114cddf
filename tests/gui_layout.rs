//! The layout holds in a small window (1000 × 700): a section opened in the form panel never
//! widens it, and toasts stay inside the window.
#![cfg(feature = "gui")]

mod common;

use egui_kittest::kittest::Queryable;
use tactile_workbench::app::View;

#[test]
fn opening_export_settings_keeps_the_form_panel_width_and_toasts_stay_inside() {
    let mut h = common::gui::workbench(1000.0, 700.0);
    h.state_mut().view = View::Stability;
    h.run_ok();
    // The central panel's right edge is the form panel's left edge.
    let before = h.get_by_label("Hide form").rect().right();
    h.get_by_label("Export settings").click();
    h.run_ok();
    h.get_by_label("Export folder");
    let after = h.get_by_label("Hide form").rect().right();
    assert!(
        (after - before).abs() < 1.0,
        "the form panel grew from {} to {} px",
        1000.0 - before,
        1000.0 - after
    );
    assert!(
        1000.0 - after <= 0.3 * 1000.0 + 1.0,
        "at most 30 % of the window"
    );

    let long = "exported figures-export/Simulated_grasp_stability-score-vs-bases.svg, \
                figures-export/Simulated_grasp_stability-score-vs-bases.png, \
                figures-export/Simulated_grasp_stability-score-vs-bases.csv";
    h.state_mut().analyses.notes.info(long);
    h.run_ok();
    let toast = h.get_by_label(long).rect();
    assert!(
        toast.left() >= 0.0 && toast.right() <= 1000.0 && toast.bottom() <= 700.0,
        "the toast at {toast:?} leaves the window"
    );
}

/// A chart whose legend would cover more than a third of its plot gets the legend above
/// the plot, as a row of names; with room, the legend stays in the plot's emptiest corner.
#[test]
fn a_crowded_legend_goes_above_the_plot() {
    use tactile_workbench::app::figure_view::{self, Selection};
    use tactile_workbench::figures::{Axis, Figure, Series};
    let series = (1..=10)
        .map(|i| Series::new(format!("series {i}"), vec![0.0, 1.0], vec![0.0, i as f64]))
        .collect();
    let fig = Figure::chart("ten lines", Axis::new("x", ""), Axis::new("y", ""), series);
    let row_shown = |height: f32| {
        let fig = fig.clone();
        let mut h = egui_kittest::Harness::builder()
            .with_size(egui::Vec2::new(600.0, height + 120.0))
            .build_ui(move |ui| {
                figure_view::show(ui, "ten", &fig, height, Selection::None);
            });
        h.run();
        h.query_by_label("— series 10").is_some()
    };
    assert!(row_shown(260.0), "ten entries cover a 260 px plot");
    assert!(!row_shown(700.0), "a 700 px plot has room for them");
}

/// Two short legend entries over a chart whose data reach every corner (two traces
/// sweeping the whole plot, as overlaid grasps do) go above the plot, however tall; the
/// same entries over data that leave a corner free stay in the plot.
#[test]
fn a_legend_never_covers_data() {
    use tactile_workbench::app::figure_view::{self, Selection};
    use tactile_workbench::figures::{Axis, Figure, Series};
    let row_shown = |series: Vec<Series>| {
        let fig = Figure::chart("two traces", Axis::new("x", ""), Axis::new("y", ""), series);
        let mut h = egui_kittest::Harness::builder()
            .with_size(egui::Vec2::new(600.0, 820.0))
            .build_ui(move |ui| {
                figure_view::show(ui, "two", &fig, 700.0, Selection::None);
            });
        h.run();
        h.query_by_label("— up").is_some()
    };
    let x: Vec<f64> = (0..=200).map(|i| i as f64 / 200.0).collect();
    let wave = |f: fn(f64) -> f64| x.iter().map(|&x| f(x)).collect::<Vec<f64>>();
    // Zigzags over the whole height, one rising and one falling: every corner has data.
    let up = wave(|x| (x * 40.0).sin() * 0.5 + 0.5);
    let down = wave(|x| (x * 37.0).cos() * 0.5 + 0.5);
    assert!(row_shown(vec![
        Series::new("up", x.clone(), up),
        Series::new("down", x.clone(), down),
    ]));
    // Two rising lines leave the top left and bottom right free.
    assert!(!row_shown(vec![
        Series::new("up", x.clone(), x.clone()),
        Series::new("down", x.clone(), wave(|x| x * 0.9)),
    ]));
}

/// Figures are exported to the data folder's exports until the user chooses a folder (never
/// the working folder); the folder and the preset come back after a restart, and an export
/// names the files it wrote by their absolute paths.
#[test]
fn the_export_folder_and_preset_persist_and_exports_report_absolute_paths() {
    use tactile_workbench::app::WorkbenchApp;
    use tactile_workbench::figures::{Axis, Figure, Series};
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.state_mut().view = View::Stability;
    h.run_ok();
    let cwd = std::env::current_dir().unwrap();
    let default = h.state().analyses.export.folder();
    assert!(default.is_absolute(), "{}", default.display());
    assert!(
        !default.starts_with(&cwd),
        "{} is under {}",
        default.display(),
        cwd.display()
    );

    h.get_by_label("Export settings").click();
    h.run_ok();
    h.get_by_label("Page width (7 in, 300 DPI)").click();
    h.run_ok();
    let chosen = common::temp_dir("export-chosen");
    // What the folder picker would give.
    h.state_mut().analyses.export.dir = chosen.to_path_buf();
    let settings = h.state().analyses.export.clone();
    assert_eq!(
        (settings.width, settings.dpi),
        (2100, 300.0),
        "the page preset"
    );

    let saved = serde_json::to_string(&h.state().persisted()).unwrap();
    let app = WorkbenchApp::new(
        &egui::Context::default(),
        Some(serde_json::from_str(&saved).unwrap()),
        Vec::new(),
    );
    assert_eq!(app.analyses.export, settings);

    let fig = Figure::chart(
        "A curve",
        Axis::new("x", ""),
        Axis::new("y", ""),
        vec![Series::new("s", vec![1.0, 2.0, 3.0], vec![0.5, 0.7, 0.6])],
    );
    let mut notes = tactile_workbench::app::notify::Notifications::default();
    app.analyses.export.write(&fig, "a-curve", &mut notes);
    let said = notes.texts().join(" ");
    let svg = chosen.join("a-curve.svg");
    assert!(svg.is_file(), "{said}");
    assert!(said.contains(&svg.display().to_string()), "{said}");
    std::fs::remove_dir_all(&chosen).unwrap();
}

/// Keeping results and models in the data folder shows no bar in the jobs strip; a run does.
#[test]
fn bookkeeping_jobs_have_no_progress_bar() {
    use tactile_workbench::app::results::JobOutput;
    let mut h = common::gui::workbench(1000.0, 700.0);
    h.run_ok();
    let (release, wait) = std::sync::mpsc::channel::<()>();
    let (release_run, wait_run) = std::sync::mpsc::channel::<()>();
    let ctx = h.ctx.clone();
    h.state_mut()
        .analyses
        .spawn_bookkeeping(&ctx, "Keeping the results".into(), move |_| {
            let _ = wait.recv();
            Ok(JobOutput::Kept)
        });
    for _ in 0..3 {
        h.step();
    }
    assert!(h.query_by_label_contains("Keeping the results").is_none());
    assert!(
        h.query_by_label("Cancel").is_none(),
        "no jobs strip for bookkeeping"
    );
    h.state_mut()
        .analyses
        .spawn(&ctx, None, "A visible run".into(), move |_| {
            let _ = wait_run.recv();
            Ok(JobOutput::Kept)
        });
    for _ in 0..3 {
        h.step();
    }
    h.get_by_label("A visible run");
    release.send(()).unwrap();
    release_run.send(()).unwrap();
    common::gui::wait_for_jobs(&mut h, std::time::Duration::from_secs(30));
}
