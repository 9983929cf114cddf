//! A researcher's own recordings in the window: a dropped ROS 2 bag or folder of trial
//! files, or a long-format CSV given on the command line, waits in the import dialog for its spec, then opens as a
//! session that replays like any other. A spec that does not read is refused in the dialog
//! with its error, and nothing is opened.
#![cfg(feature = "gui")]

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::WorkbenchApp;

fn fixtures() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures"))
}

/// The number of grasps the fixture script wrote into `expected` (its own record, not the
/// importer's).
fn scripted_grasps(expected: &str) -> usize {
    let path = fixtures().join("expected").join(expected);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap())
        .expect("the script's record reads");
    v["grasps"].as_array().expect("a grasp list").len()
}

/// A file as the window's integration hands a drop to egui.
#[derive(Debug)]
struct Dropped(PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

fn drop_file(h: &mut Harness<'static, WorkbenchApp>, path: &Path) {
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(path.to_path_buf())));
    h.run_ok();
}

fn wait_for_sessions(h: &mut Harness<'static, WorkbenchApp>, n: usize) {
    let t = Instant::now();
    while (h.state().is_loading() || h.state().sessions.len() < n)
        && t.elapsed() < Duration::from_secs(60)
    {
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    h.run_ok();
    assert_eq!(
        h.state().sessions.len(),
        n,
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
}

#[test]
fn a_dropped_bag_is_imported_with_the_spec_beside_it_and_replays() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    drop_file(&mut h, &fixtures().join("ros2/plain-windows.mcap"));
    // Nothing is read before a spec is accepted.
    h.get_by_label_contains("plain-windows.mcap needs an import spec");
    assert_eq!(h.state().sessions.len(), 2);
    assert!(!h.state().is_loading());

    // The spec named after the bag is offered; importing it opens the session.
    h.get_by_label("Import").click();
    h.run_ok();
    wait_for_sessions(&mut h, 3);
    assert!(h.query_by_label_contains("needs an import spec").is_none());
    let grasps = scripted_grasps("plain-windows.json");
    let s = &h.state().sessions[2].session;
    assert_eq!(
        s.meta.name,
        "Gripper with a palm pad, grasps cut by windows"
    );
    assert_eq!(s.grasps.len(), grasps);

    // It is listed and replays in its own layout: every sensor is drawn.
    h.get_by_label("Gripper with a palm pad, grasps cut by windows")
        .click();
    h.run_ok();
    h.get_by_label(&format!("{grasps} of {grasps} grasps"));
    h.state_mut().selection.focus = Some((2, 0));
    h.run_ok();
    h.get_by_label_contains(" / 10 · t = ");
    for sensor in ["left", "right", "palm"] {
        h.get_by_label_contains(&format!("{sensor} ("));
    }
}

/// A dropped folder of trial files waits for its spec like a bag, is offered the spec named
/// after it, and imports one grasp per file.
#[test]
fn a_dropped_folder_of_trial_files_is_imported_with_the_spec_beside_it() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    drop_file(&mut h, &fixtures().join("trials/by-name"));
    h.get_by_label_contains("by-name needs an import spec");
    assert_eq!(h.state().sessions.len(), 2);
    h.get_by_label("Import").click();
    h.run_ok();
    wait_for_sessions(&mut h, 3);
    let s = &h.state().sessions[2].session;
    assert_eq!(s.meta.name, "Trials by file name");
    // The eight grasps of the long CSV the folder was split from.
    assert_eq!(s.grasps.len(), scripted_grasps("long-grasps.json"));
}

#[test]
fn a_csv_on_the_command_line_waits_for_its_spec_and_a_bad_spec_is_refused() {
    let csv = fixtures().join("long/grasps.csv");
    let app = WorkbenchApp::new(&egui::Context::default(), None, vec![csv]);
    let mut h = common::gui::harness_now(app, 1400.0, 900.0);
    h.run_ok();
    h.get_by_label_contains("grasps.csv needs an import spec");

    // A spec that does not exist: the dialog says so, names it, and opens nothing.
    let missing = fixtures().join("long/no-such.spec.json");
    h.get_by_label("Spec file")
        .set_text_value_accesskit(&missing.display().to_string());
    h.run_ok();
    h.get_by_label("Import").click();
    h.run_ok();
    h.get_by_label_contains("no-such.spec.json");
    h.get_by_label_contains("needs an import spec");
    assert!(h.state().sessions.is_empty());
    assert!(!h.state().is_loading());

    // The right spec imports it.
    let spec = fixtures().join("long/grasps.spec.json");
    h.get_by_label("Spec file")
        .set_text_value_accesskit(&spec.display().to_string());
    h.run_ok();
    h.get_by_label("Import").click();
    h.run_ok();
    wait_for_sessions(&mut h, 1);
    assert_eq!(
        h.state().sessions[0].session.grasps.len(),
        scripted_grasps("long-grasps.json")
    );
    // The source is remembered with its spec, so the next start reopens it.
    let label = h.state().persisted().sources[0].label();
    assert!(label.ends_with("grasps.spec.json"), "{label}");
}

#[test]
fn cancel_drops_the_recording_and_opens_nothing() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    drop_file(&mut h, &fixtures().join("ros2/zstd-events"));
    h.get_by_label_contains("zstd-events needs an import spec");
    h.get_by_label("Cancel").click();
    h.run_ok();
    assert!(h.query_by_label_contains("needs an import spec").is_none());
    assert_eq!(h.state().sessions.len(), 2);
    assert!(!h.state().is_loading());
}

/// A session the user opens becomes the active one once it has loaded, with a toast; the
/// sessions restored at start leave the active one where it was.
#[test]
fn a_session_the_user_opens_becomes_active_with_a_toast() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.run_ok();
    assert_eq!(h.state().sessions.len(), 2);
    let mut copy =
        tactile_workbench::session::open(&common::sample("grasp-stability.json")).unwrap();
    copy.meta.name = "A copy of the stability sample".into();
    let dir = common::temp_dir("gui-open-active");
    let path = dir.join("copy.json");
    tactile_workbench::session::native::save(&copy, &path).unwrap();
    let ctx = h.ctx.clone();
    h.state_mut().open_path(path, &ctx);
    let t0 = Instant::now();
    while h.state().sessions.len() < 3 && t0.elapsed() < Duration::from_secs(60) {
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    h.run_ok();
    let state = h.state();
    let active = &state.sessions[state.browser.active].session.meta.name;
    assert_eq!(active, "A copy of the stability sample");
    h.get_by_label_contains("opened «A copy of the stability sample»");
    let _ = std::fs::remove_dir_all(dir);
}
