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
    h.get_by_label("Select a grasp in the browser to replay it.");

    h.get_by_label_contains("object_01 #2 ·").click();
    h.run_ok();
    assert_eq!(h.state().selected, Some((0, 1)));
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
    assert_eq!(h.state().selected, Some((1, 2)));
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
        h.state().analyses.messages
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
