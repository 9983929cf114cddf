//! Work is never lost: a project saves and opens through the in-app path field (no system
//! dialog is needed), and the results of a run come back when the workbench restarts on the
//! same data folder, with the forms as they were left.
#![cfg(feature = "gui")]

mod common;

use std::path::Path;
use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::{KEPT_RESULTS, Persisted, View, WorkbenchApp};

use common::gui::wait_for_jobs;

/// The workbench keeping its results in `data`, on `persisted` (the state of a last run).
fn workbench(data: &Path, persisted: Option<Persisted>) -> Harness<'static, WorkbenchApp> {
    let ctx = egui::Context::default();
    let mut app = WorkbenchApp::new(&ctx, persisted, Vec::new());
    app.keep_results_in(&ctx, data.to_path_buf());
    let mut h = common::gui::harness_of(app, 1400.0, 900.0);
    wait_for_jobs(&mut h, Duration::from_secs(60));
    h
}

/// The picker's path field.
fn path_field<'h>(h: &'h Harness<'static, WorkbenchApp>) -> egui_kittest::Node<'h> {
    h.get_by_role_and_label(egui::accesskit::Role::TextInput, "Path")
}

/// File > `item`, then `path` typed into the in-app picker's path field and confirmed.
fn through_the_picker(h: &mut Harness<'static, WorkbenchApp>, item: &str, path: &Path, ok: &str) {
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label(item).click();
    h.run_ok();
    assert!(h.state().picker.is_some(), "{item} opens the in-app picker");
    path_field(h).set_text_value_accesskit(&path.display().to_string());
    h.run_ok();
    h.get_by_label(ok).click();
    h.run_ok();
    assert!(h.state().picker.is_none(), "{ok} closes the picker");
}

fn run_baselines(h: &mut Harness<'static, WorkbenchApp>) {
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Baselines").click();
    h.run_ok();
    h.get_by_label("orders").set_value_accesskit(2.0);
    h.run_ok();
    h.get_by_label("Run").click();
    h.step();
    h.step();
    wait_for_jobs(h, Duration::from_secs(300));
    assert_eq!(
        h.state().analyses.results.len(),
        1,
        "{:?}",
        h.state().analyses.notes.texts()
    );
}

#[test]
fn save_and_open_a_project_through_the_path_field_and_keep_results_across_a_restart() {
    let data = common::temp_dir("gui-kept-results");
    let folder = common::temp_dir("gui-project-folder");
    let mut h = workbench(&data, None);
    run_baselines(&mut h);
    // Kept in the data folder as soon as the job finished.
    assert!(
        data.join(KEPT_RESULTS).is_file(),
        "results kept in {}",
        data.display()
    );

    // Save project: the field starts on a location, the folder is listed, Save writes it.
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Save project…").click();
    h.run_ok();
    let start = path_field(&h).value().unwrap_or_default();
    assert!(start.ends_with("project.json"), "default location: {start}");
    h.get_by_label("Cancel").click();
    h.run_ok();
    let saved = folder.join("saved.json");
    through_the_picker(&mut h, "Save project…", &saved, "Save");
    wait_for_jobs(&mut h, Duration::from_secs(60));
    assert!(saved.is_file(), "{:?}", h.state().analyses.notes.texts());
    // The project carries the run's models (k-means and the SOM at least) ...
    let models = h.state().analyses.models.list.len();
    assert!(models >= 2, "{models} models");
    let project = tactile_workbench::project::Project::load(&saved).unwrap();
    assert_eq!(project.models.len(), models);
    // ... and brings them to a workbench that has never seen them.
    let elsewhere = common::temp_dir("gui-project-elsewhere");
    let mut other = workbench(&elsewhere, None);
    assert!(other.state().analyses.models.list.is_empty());
    through_the_picker(&mut other, "Open project…", &saved, "Open");
    wait_for_jobs(&mut other, Duration::from_secs(60));
    assert_eq!(other.state().analyses.models.list.len(), models);
    drop(other);
    let _ = std::fs::remove_dir_all(elsewhere);

    // A path that cannot be used is a toast, and the picker stays for another try.
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Open project…").click();
    h.run_ok();
    path_field(&h).set_text_value_accesskit(&folder.join("absent.json").display().to_string());
    h.run_ok();
    h.get_by_label("Open").click();
    h.run_ok();
    h.get_by_label_contains("no such file");
    assert!(h.state().picker.is_some());
    // The listing of the folder shows the saved file; clicking it fills the path field.
    h.get_by_label("saved.json").click();
    h.run_ok();
    h.get_by_label("Open").click();
    h.run_ok();
    assert!(h.state().picker.is_none());
    wait_for_jobs(&mut h, Duration::from_secs(60));
    assert_eq!(
        h.state().analyses.results.len(),
        2,
        "the project's result added"
    );

    // A form setting to see after the restart.
    h.get_by_label("Recognition").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(3.0);
    h.run_ok();
    let persisted = h.state().persisted();
    let kept = h.state().analyses.results.len();
    drop(h);

    // Restart on the same data folder: the results and the form are back.
    let mut h = workbench(&data, Some(persisted));
    assert_eq!(h.state().analyses.results.len(), kept);
    assert_eq!(h.state().rooms.recognition.form.reps, 3);
    h.get_by_label_contains("reopened");
    h.get_by_label("Baselines").click();
    h.run_ok();
    assert_eq!(h.state().view, View::Baselines);
    // The view shows the reopened result, not an offer to run.
    assert!(
        h.query_by_label_contains("No results yet").is_none(),
        "active {} of {:?}; results on {:?}; {:?}",
        h.state().browser.active,
        h.state()
            .sessions
            .iter()
            .map(|s| s.session.meta.name.clone())
            .collect::<Vec<_>>(),
        h.state()
            .analyses
            .results
            .iter()
            .map(|r| r.session.clone())
            .collect::<Vec<_>>(),
        h.state().analyses.notes.texts()
    );
    h.get_by_label("All numbers").click();
    h.run_ok();
    h.get_by_label("k-means NMI");
    let _ = std::fs::remove_dir_all(data);
    let _ = std::fs::remove_dir_all(folder);
}

/// The workbench opening `files` (as `tactile-workbench FILES…` does), stepped until its
/// opening has an outcome (bounded: a guard against hangs).
fn opening(files: Vec<std::path::PathBuf>) -> (Harness<'static, WorkbenchApp>, Result<(), String>) {
    let app = WorkbenchApp::new(&egui::Context::default(), None, files);
    let mut h = common::gui::harness_now(app, 1400.0, 900.0);
    let start = std::time::Instant::now();
    loop {
        h.step();
        if let Some(outcome) = h.state().startup_outcome() {
            return (h, outcome);
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the opening never ended: {:?}",
            h.state().analyses.notes.texts()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// `--measure-startup` ends on what the opening gives: a JSON that is not a session, a
/// project of another version or one naming unreadable sessions ends it with their errors
/// (it used to wait for sessions that never came).
#[test]
fn an_opening_that_fails_ends_with_its_errors() {
    let dir = common::temp_dir("gui-opening-fails");
    let not_session = dir.join("settings.json");
    std::fs::write(&not_session, r#"{"theme": "dark"}"#).unwrap();
    let (_, outcome) = opening(vec![not_session.clone()]);
    let e = outcome.expect_err("not a session");
    assert!(e.contains("settings.json") && e.contains("format"), "{e}");

    let future = dir.join("future.project.json");
    std::fs::write(
        &future,
        r#"{"format": "tactile-workbench-project", "version": 99, "sessions": [], "results": []}"#,
    )
    .unwrap();
    let (_, outcome) = opening(vec![future]);
    let e = outcome.expect_err("a project of another version");
    assert!(e.contains("version 99"), "{e}");

    let gone = dir.join("gone.project.json");
    let missing = dir.join("missing.json");
    tactile_workbench::project::Project::new(vec![missing.display().to_string()], Vec::new())
        .save(&gone)
        .unwrap();
    let (_, outcome) = opening(vec![gone]);
    let e = outcome.expect_err("its session is missing");
    assert!(e.contains("missing.json"), "{e}");

    let (_, outcome) = opening(vec![common::sample("grasp-stability.json")]);
    assert_eq!(outcome, Ok(()));
}

/// A project opens only sessions: a path into a system folder or to a file that is not a
/// session is refused by name and not opened; the notification lists what it opens.
#[test]
fn a_project_opens_only_sessions_and_says_which() {
    let dir = common::temp_dir("gui-project-paths");
    let notes = dir.join("notes.txt");
    std::fs::write(&notes, "not a session").unwrap();
    let sample = common::sample("object-recognition.json");
    let labels = vec![
        "/etc/passwd".to_string(),
        "/proc/self/environ".to_string(),
        notes.display().to_string(),
        sample.display().to_string(),
    ];
    let project = dir.join("p.project.json");
    tactile_workbench::project::Project::new(labels, Vec::new())
        .save(&project)
        .unwrap();
    let (h, outcome) = opening(vec![project]);
    let e = outcome.expect_err("three sessions refused");
    for refused in ["/etc/passwd", "/proc/self/environ", "notes.txt"] {
        assert!(e.contains(refused), "{refused} named in: {e}");
    }
    assert!(e.contains("system folder /etc"), "{e}");
    let texts = h.state().analyses.notes.texts();
    assert!(
        texts
            .iter()
            .any(|t| t.contains("it opens the sessions") && t.contains("object-recognition.json")),
        "{texts:?}"
    );
    let opened: Vec<String> = h
        .state()
        .sessions
        .iter()
        .map(|s| s.source.label())
        .collect();
    assert_eq!(opened, vec![sample.display().to_string()]);
}
