//! "Run on a cluster…" in the views' forms: the form as set up through its widgets is
//! written as a sweep plan, whose shards, run and merged as on a cluster, give the result
//! the form's own Run gives here; a form that cannot shard says why and writes nothing.
#![cfg(feature = "gui")]

mod common;

use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::WorkbenchApp;
use tactile_workbench::jobs::Progress;
use tactile_workbench::sweep::{self, ShardRun};

fn wait_for_jobs(h: &mut Harness<'static, WorkbenchApp>) {
    common::gui::wait_for_jobs(h, Duration::from_secs(300));
}

fn open_cluster_section(h: &mut Harness<'static, WorkbenchApp>) {
    h.get_by_label("Run on a cluster…").click();
    h.run_ok();
}

#[test]
fn a_clustering_form_planned_for_a_cluster_merges_into_the_local_result() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Clustering").click();
    h.run_ok();

    // GU, two repetitions, thresholds 0.05 and 0.1: set through the form's widgets.
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Learner")
        .click();
    h.run_ok();
    h.get_by_label("GU (generative, EVT novelty)").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(2.0);
    h.run_ok();
    h.get_by_label("from").set_value_accesskit(0.05);
    h.run_ok();
    h.get_by_label("to").set_value_accesskit(0.1);
    h.run_ok();
    h.get_by_label("step").set_value_accesskit(0.05);
    h.run_ok();

    let dir = common::temp_dir("gui-cluster").child("plan");
    open_cluster_section(&mut h);
    h.get_by_label("shards").set_value_accesskit(3.0);
    h.run_ok();
    h.get_by_label("Plan folder")
        .set_text_value_accesskit(&dir.display().to_string());
    h.run_ok();
    h.get_by_label("Write plan").click();
    h.step();
    wait_for_jobs(&mut h);
    let texts = h.state().analyses.notes.texts();
    assert!(
        texts.iter().any(|t| t.contains("sbatch")),
        "messages: {texts:?}"
    );

    // Two orders (each learned under both thresholds at once), and for each order the
    // sequential k-means baseline at k = 2 … 20, in the three shards asked for.
    let (plan, _) = sweep::read_plan(&dir).expect("the plan reads");
    assert_eq!(plan.experiment.name(), "clustering");
    assert_eq!(plan.items.len(), 2 + 2 * 19);
    assert_eq!(plan.shard_count(), 3);
    assert_eq!(plan.session.name, "Simulated object recognition");
    let script = std::fs::read_to_string(dir.join(sweep::SBATCH_FILE)).unwrap();
    assert!(script.contains("#SBATCH --array=0-2"), "{script}");

    // The shards as a cluster runs them, then merged: the same figures as Run here.
    for i in 0..3 {
        let r = sweep::run_shard(&dir, i, &Progress::new()).unwrap();
        assert!(matches!(r, ShardRun::Done { .. }), "{r:?}");
    }
    let merged = sweep::merge(&dir, &Progress::new()).unwrap();
    h.get_by_label("Run").click();
    h.step();
    wait_for_jobs(&mut h);
    let local = h
        .state()
        .analyses
        .results
        .last()
        .expect("the local run's result")
        .clone();
    let merged = merged
        .analysis
        .expect("a clustering sweep merges into a result");
    assert_eq!(local.label, merged.label);
    assert_eq!(
        serde_json::to_value(&local.figures).unwrap(),
        serde_json::to_value(&merged.figures).unwrap()
    );
}

#[test]
fn a_single_configuration_is_not_sharded_and_a_grid_is() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Grasp stability").click();
    h.run_ok();
    open_cluster_section(&mut h);
    h.get_by_label("A cluster shards a grid search: tick Grid search.");
    assert!(h.query_by_label("Write plan").is_none());

    h.get_by_label("Grid search (β and γ over 0.5, 1, 2)")
        .click();
    h.run_ok();
    h.get_by_label("bases from").set_value_accesskit(10.0);
    h.run_ok();
    h.get_by_label("to").set_value_accesskit(30.0);
    h.run_ok();
    h.get_by_label("step").set_value_accesskit(10.0);
    h.run_ok();
    let dir = common::temp_dir("gui-cluster-grid").child("plan");
    h.get_by_label("Plan folder")
        .set_text_value_accesskit(&dir.display().to_string());
    h.run_ok();
    h.get_by_label("Write plan").click();
    h.step();
    wait_for_jobs(&mut h);
    // 10, 20 and 30 bases, each with β over 0.5, 1 and 2: one item a dictionary (its
    // three γ share it).
    let (plan, _) = sweep::read_plan(&dir).expect("the plan reads");
    assert_eq!(plan.experiment.name(), "stability");
    assert_eq!(plan.items.len(), 9);
    assert_eq!(plan.shard_count(), 4);

    // A folder that already holds a plan is refused, and the error is shown.
    h.get_by_label("Write plan").click();
    h.step();
    wait_for_jobs(&mut h);
    let texts = h.state().analyses.notes.texts();
    assert!(
        texts.iter().any(|t| t.contains("already holds a plan")),
        "messages: {texts:?}"
    );
}
