//! Models that leave their session, in the window: a grasp-stability run keeps its model in
//! the Models list; "Evaluate on session…" tests it on another open session, whose held-out
//! result links its confusion cells to that session's grasps; the list survives a restart
//! through the data folder, where a bad model file is a toast.
#![cfg(feature = "gui")]

mod common;

use std::path::Path;
use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::{Persisted, View, WorkbenchApp};
use tactile_workbench::experiments::figure_id::FigureId;
use tactile_workbench::figures::FigureKind;
use tactile_workbench::session::{self, simulate};

use common::gui::wait_for_jobs;

const DAY_2: &str = "Simulated grasp stability, day 2";

/// A grasp-stability run of 8 bases on the active session, from the Stability view.
fn train(h: &mut Harness<'static, WorkbenchApp>) {
    h.get_by_label("Grasp stability").click();
    h.run_ok();
    h.get_by_label("num_bases").set_value_accesskit(8.0);
    h.run_ok();
    h.get_by_label("Run").click();
    h.step();
    h.step();
    wait_for_jobs(h, Duration::from_secs(300));
    assert_eq!(
        h.state().analyses.models.list.len(),
        1,
        "{:?}",
        h.state().analyses.notes.texts()
    );
}

/// The picker's path field set to `path`, then `ok`.
fn pick(h: &mut Harness<'static, WorkbenchApp>, path: &Path, ok: &str) {
    assert!(h.state().picker.is_some(), "the in-app picker is open");
    h.get_by_role_and_label(egui::accesskit::Role::TextInput, "Path")
        .set_text_value_accesskit(&path.display().to_string());
    h.run_ok();
    h.get_by_label(ok).click();
    h.run_ok();
    wait_for_jobs(h, Duration::from_secs(60));
}

/// The accessible name of a heatmap cell, as the figure view gives it.
fn cell_label(m: &tactile_workbench::figures::Heatmap, row: usize, col: usize) -> String {
    format!(
        "{} {} × {} {}",
        m.y.title, m.rows[row], m.x.title, m.columns[col]
    )
}

#[test]
fn a_model_evaluated_on_another_session_links_its_confusion_to_that_sessions_grasps() {
    let dir = common::temp_dir("gui-models-evaluate");
    // Another day of the simulated gripper: the same sensors, other draws.
    let mut day2 = simulate::grasp_stability(2);
    day2.meta.name = DAY_2.into();
    let day2_path = dir.join("day2.json");
    session::save(&day2, &day2_path).unwrap();
    let mut h = common::gui::workbench_opening(
        vec![common::sample("grasp-stability.json"), day2_path],
        1400.0,
        1000.0,
    );
    assert_eq!(h.state().browser.active, 0);
    train(&mut h);
    h.get_by_label("Models (1)");
    h.get_by_label("sparse coding + SVM · num_bases 8");

    // Evaluate on day 2 (offered first: not the training session), calibration first:60.
    h.get_by_label("Evaluate on session…").click();
    h.run_ok();
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Calibration")
        .click();
    h.run_ok();
    h.get_by_label("first K grasps").click();
    h.run_ok();
    h.get_by_label("K").set_value_accesskit(60.0);
    h.run_ok();
    h.get_by_label("Evaluate").click();
    h.step();
    wait_for_jobs(&mut h, Duration::from_secs(120));
    let results = &h.state().analyses.results;
    assert_eq!(results.len(), 2, "{:?}", h.state().analyses.notes.texts());
    let r = results[1].clone();
    let held = r.held_out.clone().expect("a held-out result");
    assert_eq!(r.session, DAY_2);
    assert_eq!(
        (held.trained_on.as_str(), held.tested_on.as_str()),
        ("Simulated grasp stability", DAY_2)
    );
    assert_eq!(held.calibration, "first:60");
    assert_eq!((held.trained_grasps, held.tested_grasps), (540, 540));
    // Shown at once, in the Stability view, with day 2 active.
    assert_eq!(h.state().view, View::Stability);
    assert_eq!(h.state().browser.active, 1);
    h.get_by_label(&format!("Held out: {}", held.text()));

    // A confusion cell selects exactly the day-2 grasps of its true class and prediction.
    let FigureKind::Heatmap(m) = &r
        .figures
        .iter()
        .find(|(n, _)| *n == FigureId::Confusion)
        .expect("a confusion map")
        .1
        .kind
    else {
        panic!("a confusion heatmap");
    };
    let (row, col) = (0..2)
        .flat_map(|a| (0..2).map(move |b| (a, b)))
        .filter(|&(a, b)| m.values[a][b] > 0.0)
        .min_by(|x, y| m.values[x.0][x.1].total_cmp(&m.values[y.0][y.1]))
        .expect("a non-empty cell");
    h.get_by_label(&cell_label(m, row, col)).click();
    h.run_ok();
    let sel = h.state().selection.clone();
    assert_eq!(sel.session, Some(1), "the tested session's grasps");
    // The map gives each true class's share: its count over that class's day-2 grasps.
    let outcome = day2.label_set("outcome").unwrap();
    let class_of = |g: usize| &day2.label_sets[outcome].classes[day2.grasps[g].labels[outcome]];
    let of_row = (0..day2.grasps.len())
        .filter(|&g| class_of(g) == &m.rows[row])
        .count();
    assert_eq!(
        sel.grasps.len(),
        (m.values[row][col] * of_row as f64).round() as usize
    );
    for &g in &sel.grasps {
        assert_eq!(
            class_of(g),
            &m.rows[row],
            "grasp {g} is truly {}",
            m.rows[row]
        );
    }
    // The first is focused: its tile gives its decision value, the replay shows it.
    let (s, g) = sel.focus.unwrap();
    assert_eq!(s, 1);
    assert!(sel.grasps.contains(&g));
    let code = r.grasp_code(g).expect("a decision for every grasp");
    assert_eq!(code.predicted, m.columns[col]);
    assert_eq!(code.decision > 0.0, m.columns[col] == m.columns[1]);
    h.get_by_label_contains(&format!("decision value {:+.3}", code.decision));
    h.get_by_label_contains("key frame (full contact)");

    // Save selection as session: a session file of exactly those grasps.
    h.get_by_label("Save selection as session…").click();
    h.run_ok();
    let picked = dir.join("picked.json");
    pick(&mut h, &picked, "Save");
    let saved = session::open(&picked).unwrap();
    assert_eq!(saved.meta.name, "picked");
    let mut chosen = sel.grasps.clone();
    chosen.sort_unstable();
    let want: Vec<_> = chosen.iter().map(|&g| day2.grasps[g].clone()).collect();
    assert_eq!(saved.grasps, want);

    // A session with other sensors is not offered, and the window says why; the app stays
    // usable.
    h.state_mut().open(
        tactile_workbench::app::loader::Source::Bundled("object-recognition.json".into()),
        &egui::Context::default(),
    );
    while h.state().is_loading() {
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    h.run_ok();
    assert_eq!(h.state().sessions.len(), 3);
    let other = h
        .state()
        .sessions
        .iter()
        .position(|s| s.session.label_set("outcome").is_none())
        .unwrap();
    // Back to the training session (its name shows in the held-out numbers too).
    h.state_mut().browser.active = 0;
    h.run_ok();
    h.get_by_label("Evaluate on session…").click();
    h.run_ok();
    h.state_mut()
        .analyses
        .models
        .evaluate
        .as_mut()
        .unwrap()
        .session = other;
    h.run_ok();
    let form = h.state().analyses.models.evaluate.clone().unwrap();
    assert_ne!(form.session, other, "moved to a session the model can read");
    let name = h.state().sessions[other].session.meta.name.clone();
    h.get_by_label_contains(&format!(
        "Not listed: {name}: the session does not fit the model"
    ));
    h.get_by_label("Cancel").click();
    h.run_ok();
    assert!(h.state().analyses.models.evaluate.is_none());
    assert_eq!(h.state().analyses.results.len(), 2);
    h.get_by_label("Recognition").click();
    h.run_ok();
    assert_eq!(h.state().view, View::Recognition);
    let _ = std::fs::remove_dir_all(dir);
}

/// The workbench keeping its results and models in `data`.
fn kept_in(data: &Path, persisted: Option<Persisted>) -> Harness<'static, WorkbenchApp> {
    let ctx = egui::Context::default();
    let mut app = WorkbenchApp::new(&ctx, persisted, Vec::new());
    app.keep_results_in(&ctx, data.to_path_buf());
    let mut h = common::gui::harness_of(app, 1400.0, 900.0);
    wait_for_jobs(&mut h, Duration::from_secs(60));
    h
}

#[test]
fn the_models_list_survives_a_restart_and_saves_and_loads_through_the_picker() {
    let data = common::temp_dir("gui-models-kept");
    let folder = common::temp_dir("gui-models-saved");
    let mut h = kept_in(&data, None);
    h.get_by_label("Simulated grasp stability").click();
    h.run_ok();
    train(&mut h);
    wait_for_jobs(&mut h, Duration::from_secs(60));
    let model = h.state().analyses.models.list[0].file.clone();
    let files: Vec<_> = std::fs::read_dir(data.join("models"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "kept in the data folder: {files:?}");

    // The result's card saves the model it trained (as the Models list's row does) where
    // the user chooses.
    h.get_by_label("Save model…");
    h.get_by_label("Save sparse coding + SVM model…").click();
    h.run_ok();
    let saved = folder.join("stability-model.json");
    pick(&mut h, &saved, "Save");
    assert_eq!(
        tactile_workbench::models::load(&saved).unwrap(),
        model,
        "{:?}",
        h.state().analyses.notes.texts()
    );
    let persisted = h.state().persisted();
    drop(h);

    // Restart: the model is listed again.
    let mut h = kept_in(&data, Some(persisted));
    assert_eq!(h.state().analyses.models.list.len(), 1);
    assert_eq!(h.state().analyses.models.list[0].file, model);
    assert_eq!(h.state().view, View::Stability);
    h.get_by_label("Models (1)");
    h.get_by_label("sparse coding + SVM · num_bases 8");
    // Loading the same model again adds nothing; after Remove, it comes back from its file.
    h.get_by_label("Load model…").click();
    h.run_ok();
    pick(&mut h, &saved, "Open");
    h.get_by_label_contains("already in the list");
    h.get_by_label("Remove").click();
    h.run_ok();
    assert!(h.state().analyses.models.list.is_empty());
    assert_eq!(std::fs::read_dir(data.join("models")).unwrap().count(), 0);
    h.get_by_label("Load model…").click();
    h.run_ok();
    pick(&mut h, &saved, "Open");
    assert_eq!(h.state().analyses.models.list.len(), 1);
    h.get_by_label_contains("model loaded: sparse coding + SVM");
    let _ = std::fs::remove_dir_all(data);
    let _ = std::fs::remove_dir_all(folder);
}

#[test]
fn a_bad_model_file_in_the_data_folder_is_a_toast() {
    let data = common::temp_dir("gui-models-bad");
    std::fs::create_dir_all(data.join("models")).unwrap();
    std::fs::write(
        data.join("models/broken.json"),
        r#"{"format": "tactile-workbench-model", "version": 1}"#,
    )
    .unwrap();
    let mut h = kept_in(&data, None);
    h.run_ok();
    assert!(h.state().analyses.models.list.is_empty());
    h.get_by_label_contains("broken.json");
    // The app goes on: the Stability view and its empty list draw.
    h.get_by_label("Grasp stability").click();
    h.run_ok();
    h.get_by_label("Models (0)");
    let _ = std::fs::remove_dir_all(data);
}

/// The recognition sample's later trials, a session of their own.
const LATER_TRIALS: &str = "Simulated object recognition, trials 16-20";

#[test]
fn recognition_and_clustering_runs_leave_models_that_test_on_another_session() {
    let dir = common::temp_dir("gui-models-sequences");
    // The sample split by trial: the window trains on trials 1-15 and tests on 16-20.
    let sample = session::open(&common::sample("object-recognition.json")).unwrap();
    let split = |trials: std::ops::RangeInclusive<u32>, name: &str| {
        let spec = session::subset::SubsetSpec {
            trials: trials.into(),
            ..Default::default()
        };
        let s = session::subset::subset(&sample, &spec, name).unwrap();
        let path = dir.join(format!("{}.json", s.grasps.len()));
        session::save(&s, &path).unwrap();
        path
    };
    let first = split(1..=15, "Simulated object recognition, trials 1-15");
    let later = split(16..=20, LATER_TRIALS);
    let mut h = common::gui::workbench_opening(vec![first, later], 1400.0, 1000.0);
    assert_eq!(h.state().browser.active, 0);

    // A DS run of one order: its experts, taught every grasp, join the Recognition list.
    h.get_by_label("Recognition").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(1.0);
    h.run_ok();
    h.get_by_label("Run").click();
    h.step();
    h.step();
    wait_for_jobs(&mut h, Duration::from_secs(300));
    let models = &h.state().analyses.models.list;
    assert_eq!(models.len(), 1, "{:?}", h.state().analyses.notes.texts());
    let p = &models[0].file.provenance;
    assert_eq!(p.method.key(), "ds");
    assert_eq!(p.session.grasps, h.state().sessions[0].session.grasps.len());
    // Selected by the run's own protocol accuracy.
    let acc = h.state().analyses.results[0]
        .score("accuracy (all)")
        .unwrap();
    assert_eq!(p.selection[0].value, acc);
    h.get_by_label("Models (1)");
    h.get_by_label("DS · capacity 50, tau 15");

    // Tested on the later trials (every object was taught): a held-out recognition result
    // there, well above the 1-in-10 chance of the sample's ten objects.
    h.get_by_label("Evaluate on session…").click();
    h.run_ok();
    h.get_by_label("Evaluate").click();
    h.step();
    wait_for_jobs(&mut h, Duration::from_secs(120));
    let results = &h.state().analyses.results;
    assert_eq!(results.len(), 2, "{:?}", h.state().analyses.notes.texts());
    let held = results[1].held_out.clone().expect("a held-out result");
    assert_eq!(held.tested_on, LATER_TRIALS);
    assert_eq!(h.state().view, View::Recognition);
    assert!(
        results[1].score("accuracy").unwrap() > 0.5,
        "{:?} {:?}",
        results[1].scores,
        results[0].scores
    );

    // A DU sweep of two orders chooses its threshold without labels; its model, learned
    // at that threshold, joins the Clustering list (not the Recognition one).
    h.state_mut().browser.active = 0;
    h.get_by_label("Clustering").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(2.0);
    h.get_by_label("from").set_value_accesskit(0.3);
    h.get_by_label("to").set_value_accesskit(0.4);
    h.get_by_label("step").set_value_accesskit(0.1);
    h.run_ok();
    h.get_by_label("Run").click();
    h.step();
    h.step();
    wait_for_jobs(&mut h, Duration::from_secs(600));
    let models = &h.state().analyses.models.list;
    assert_eq!(models.len(), 2, "{:?}", h.state().analyses.notes.texts());
    let p = &models[1].file.provenance;
    assert_eq!(p.method.key(), "du");
    let threshold = p
        .parameters
        .iter()
        .find(|(k, _)| k == "threshold")
        .map(|(_, v)| v.parse::<f64>().unwrap())
        .unwrap();
    assert!([0.3, 0.4].contains(&threshold), "{threshold}");
    h.get_by_label("Models (1)");
    let _ = std::fs::remove_dir_all(dir);
}
