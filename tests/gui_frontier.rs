//! The Speed vs accuracy view's frontiers: a frontier computed from the form becomes the
//! model size the Recognition view uses by default (and its result says so); clicking a
//! size on the frontier chart trains that model, and clicking it again opens the result.
#![cfg(feature = "gui")]

mod common;

use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::{View, WorkbenchApp, figure_view};
use tactile_workbench::experiments::frontier::Frontier;
use tactile_workbench::experiments::frontier_report::frontier_figures;
use tactile_workbench::experiments::report::SizeReason;
use tactile_workbench::figures::FigureKind;

fn wait_for_jobs(h: &mut Harness<'static, WorkbenchApp>) {
    common::gui::wait_for_jobs(h, Duration::from_secs(300));
}

/// Click the marker of size `k` of the only frontier on the prediction-time chart, where
/// the frontier pane drew it in the last frame.
fn click_size(h: &mut Harness<'static, WorkbenchApp>, frontier: &Frontier, k: usize) {
    h.get_by_label("prediction time per step or sample").click();
    h.run_ok();
    let figs = frontier_figures(std::slice::from_ref(frontier));
    let (_, fig) = figs
        .iter()
        .find(|(name, _)| name == "frontier-prediction")
        .expect("a prediction-time frontier");
    let FigureKind::Chart(chart) = &fig.kind else {
        panic!("the frontier is a chart");
    };
    assert_eq!(chart.series[0].name, frontier.short_label());
    let pos = figure_view::marker_position(&h.ctx, "frontier", chart, 0, k)
        .expect("the frontier chart was drawn");
    h.hover_at(pos);
    h.run_ok();
    // The pane tells what is under the pointer before it is clicked.
    h.get_by_label_contains("click to open or train");
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_ok();
}

#[test]
fn a_frontier_sets_the_default_size_and_its_points_train_and_open_models() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    assert_eq!(h.state().view, View::SpeedAccuracy);
    h.get_by_label_contains("No frontier for «Simulated object recognition» yet");

    // DS on all features (the form's default method), four sizes, two repetitions.
    h.get_by_label("capacities")
        .set_text_value_accesskit("5, 20");
    h.get_by_label("taus").set_text_value_accesskit("1, 5");
    h.run_ok();
    h.get_by_label("frontier repetitions")
        .set_value_accesskit(2.0);
    h.run_ok();
    h.get_by_label("Compute frontier").click();
    h.step();
    wait_for_jobs(&mut h);
    let frontier = h
        .state()
        .analyses
        .frontiers
        .first()
        .unwrap_or_else(|| panic!("messages: {:?}", h.state().analyses.notes.texts()))
        .clone();
    assert_eq!(frontier.points.len(), 4);
    let rec = &frontier.points[frontier.recommended];
    let (capacity, tau) = (rec.knob("capacity").unwrap(), rec.knob("tau").unwrap());
    h.get_by_label_contains("Recommended DS, all features: capacity");

    // The Recognition view now trains the recommended size by default, and says so.
    h.get_by_label("Recognition").click();
    h.run_ok();
    h.get_by_label("Model size (recommended):");
    assert_eq!(
        h.get_by_label("capacity").value().as_deref(),
        Some(format!("capacity {capacity}").as_str())
    );
    assert_eq!(
        h.get_by_label("tau").value().as_deref(),
        Some(format!("tau {tau}").as_str())
    );

    // A size that is not the recommended one, clicked on the chart, is trained in its view.
    let other = (0..frontier.points.len())
        .find(|&k| k != frontier.recommended)
        .unwrap();
    let p = &frontier.points[other];
    let knobs = format!(
        "capacity {}, tau {}",
        p.knob("capacity").unwrap(),
        p.knob("tau").unwrap()
    );
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    click_size(&mut h, &frontier, other);
    assert_eq!(h.state().view, View::Recognition);
    wait_for_jobs(&mut h);
    let results = &h.state().analyses.results;
    assert_eq!(
        results.len(),
        1,
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
    let size = results[0].model_size.clone().expect("a recognition size");
    assert_eq!(size.knobs, knobs);
    assert_eq!(size.reason, SizeReason::User);
    assert!(results[0].label.starts_with("DS"), "{}", results[0].label);

    // Clicking that size again opens the model rather than training it twice.
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    click_size(&mut h, &frontier, other);
    wait_for_jobs(&mut h);
    assert_eq!(h.state().view, View::Recognition);
    assert_eq!(h.state().analyses.results.len(), 1);
}
