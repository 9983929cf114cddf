//! The workbench opens on the bundled sample sessions; a grasp is selected in the browser
//! and its replay is stepped with buttons and keys, all by accessible labels.
#![cfg(feature = "gui")]

mod common;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::WorkbenchApp;

fn harness() -> Harness<'static, WorkbenchApp> {
    common::gui::workbench(1400.0, 900.0)
}

#[test]
fn opens_the_samples_selects_a_grasp_and_steps_the_replay() {
    let mut h = harness();
    h.get_by_label("Simulated grasp stability");
    h.get_by_label("Simulated object recognition");
    h.get_by_label("540 of 540 grasps");
    // A first start shows a grasp, not an empty replay.
    assert_eq!(h.state().selection.focus, Some((0, 0)));
    h.get_by_label_contains("Frame 1 / ");

    h.get_by_label_contains("object_01 #2 ·").click();
    h.run_ok();
    assert_eq!(h.state().selection.focus, Some((0, 1)));
    h.get_by_label_contains("Frame 1 / 16");

    h.get_by_label("Step forward").click();
    h.run_ok();
    h.get_by_label_contains("Frame 2 / 16");

    h.key_press(egui::Key::ArrowRight);
    h.run_ok();
    h.get_by_label_contains("Frame 3 / 16");
    h.key_press(egui::Key::ArrowLeft);
    h.run_ok();
    h.get_by_label_contains("Frame 2 / 16");

    h.get_by_label("Step back").click();
    h.run_ok();
    h.get_by_label_contains("Frame 1 / 16");

    // Space plays: the button turns into Pause and frames advance with time.
    h.key_press(egui::Key::Space);
    h.step();
    assert!(h.state().replay.playing);
    h.get_by_label("Pause");
    // Half a second at 12.5 frames per second: about six frames on.
    for _ in 0..30 {
        h.step();
    }
    let frame = h.state().replay.frame;
    assert!(
        (4..=8).contains(&frame),
        "playback advanced to frame {frame}"
    );
    h.key_press(egui::Key::Space);
    h.step();
    assert!(!h.state().replay.playing);
    h.get_by_label("Play");
}

#[test]
fn filters_and_replays_an_object_recognition_grasp() {
    let mut h = harness();
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("200 of 200 grasps");
    h.get_by_label_contains("sponge #3 ·").click();
    h.run_ok();
    assert_eq!(h.state().selection.focus, Some((1, 2)));
    // Every sensor is drawn, with its taxel count, and the traces are titled.
    for finger in ["thumb", "index", "middle", "ring", "little"] {
        h.get_by_label(&format!("{finger} (12 taxels)"));
    }
    h.get_by_label("Joint encoders");
    h.get_by_label("Per-finger feature");

    // The recognition forms as the hand closes: DS's class distribution at each step.
    h.get_by_label("Show the recognition as the hand closes")
        .click();
    let t = std::time::Instant::now();
    while (h.state().analyses.busy() || h.state().analyses.trace.is_none())
        && t.elapsed() < std::time::Duration::from_secs(120)
    {
        h.step();
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    h.run_ok();
    assert!(
        h.state().analyses.trace.is_some(),
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
    h.get_by_label_contains("Class distribution at step 1 (true: sponge");
    h.key_press(egui::Key::ArrowRight);
    h.run_ok();
    h.get_by_label_contains("Class distribution at step 2 (true: sponge");

    // Filtering by object keeps only that object's grasps: the combo offers every object.
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Filter by object")
        .click();
    h.run_ok();
    // The list is taller than the popup: scroll to the object first.
    h.get_by_label("mug").scroll_to_me();
    h.run_ok();
    h.get_by_label("mug").click();
    h.run_ok();
    h.get_by_label("20 of 200 grasps");
    assert!(h.query_by_label_contains("sponge #1 ·").is_none());
    assert_eq!(h.get_all_by_label_contains("mug #").count(), 20);
    // And back to all of them.
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Filter by object")
        .click();
    h.run_ok();
    h.get_by_label("all objects").scroll_to_me();
    h.run_ok();
    h.get_by_label("all objects").click();
    h.run_ok();
    h.get_by_label("200 of 200 grasps");
}

/// A tile layout the user changed comes back after a restart (through what eframe stores).
#[test]
fn a_changed_layout_comes_back_after_a_restart() {
    use tactile_workbench::app::View;
    let mut h = harness();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    assert_eq!(h.state().view, View::SpeedAccuracy);
    h.get_all_by_label("Maximise").next().unwrap().click();
    h.run_ok();
    h.get_by_label("Restore layout");
    let saved = serde_json::to_string(&h.state().persisted()).unwrap();
    let persisted = serde_json::from_str(&saved).unwrap();
    let app = WorkbenchApp::new(&egui::Context::default(), Some(persisted), Vec::new());
    let mut h2 = common::gui::harness_of(app, 1400.0, 900.0);
    h2.run_ok();
    assert_eq!(h2.state().view, View::SpeedAccuracy);
    h2.get_by_label("Restore layout").click();
    h2.run_ok();
    assert_eq!(h2.get_all_by_label("Maximise").count(), 2);
}

/// A notification shows as a toast, fades after a few seconds, and stays in the log.
#[test]
fn a_toast_fades_and_the_log_keeps_it() {
    let mut h = harness();
    h.state_mut().analyses.notes.info("exported three figures");
    h.run_ok();
    h.get_by_label("exported three figures");
    // 60 frames a second: seven seconds on, the toast is gone.
    for _ in 0..420 {
        h.step();
    }
    assert!(h.query_by_label("exported three figures").is_none());
    h.get_by_label("View").click();
    h.run_ok();
    h.get_by_label("Notification log").click();
    h.run_ok();
    h.get_by_label("exported three figures");
}
