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
    // A first start shows a grasp, not an empty replay: at its key frame (full contact),
    // coloured over the grasp's own range.
    assert_eq!(h.state().selection.focus, Some((0, 0)));
    let key = |h: &Harness<'static, WorkbenchApp>, g: usize| {
        h.state().sessions[0].session.grasps[g].key_frame
    };
    let k0 = key(&h, 0);
    assert!(k0 > 0, "the sample's key frame is not its first");
    assert_eq!(h.state().replay.frame, k0);
    h.get_by_label_contains(&format!("Frame {} / 16 · ", k0 + 1));
    h.get_by_label_contains("key frame (full contact)");
    assert_eq!(
        h.state().replay.colours,
        tactile_workbench::app::replay::ColourRange::Grasp
    );

    h.get_by_label_contains("object_01 #2 ·").click();
    h.run_ok();
    assert_eq!(h.state().selection.focus, Some((0, 1)));
    let k1 = key(&h, 1);
    h.get_by_label_contains(&format!("Frame {} / 16", k1 + 1));
    // The slider numbers frames as the label does, from 1: at 1 it shows the first frame.
    // Then step with buttons and keys.
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "frame")
        .set_value_accesskit(1.0);
    h.run_ok();
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
    // Both traces' time axes are painted whole, at both window sizes (the last trace ends
    // at the tile's bottom edge, not under it).
    for size in [
        egui::Vec2::new(1400.0, 900.0),
        egui::Vec2::new(1000.0, 700.0),
    ] {
        h.set_size(size);
        h.run_steps(3);
        let titles = whole_texts(&h.output().shapes, "time (s)");
        assert_eq!(
            titles,
            (2, 2),
            "time axis titles (painted, whole) at {size:?}"
        );
    }

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
    let k = h.state().replay.frame;
    h.get_by_label_contains(&format!(
        "Class distribution at step {} (true: sponge",
        k + 1
    ));
    h.key_press(egui::Key::ArrowRight);
    h.run_ok();
    h.get_by_label_contains(&format!(
        "Class distribution at step {} (true: sponge",
        k + 2
    ));

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

/// A click on a trace moves the replay to the frame under the pointer.
#[test]
fn a_click_on_a_trace_seeks() {
    let mut h = harness();
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label_contains("sponge #3 ·").click();
    h.run_ok();
    let g = &h.state().sessions[1].session.grasps[2];
    let (n, t0, t1) = (
        g.frames.len(),
        g.frames[0].t,
        g.frames[g.frames.len() - 1].t,
    );
    assert!(h.state().replay.frame > 1);
    // The left edge of the plot area is the grasp's first frame (x axis from t0 to t1 with a
    // small margin): a click a few points inside it lands on the first frames.
    let rect = h.get_by_label("Joint encoders trace").rect();
    let near_start = egui::pos2(rect.left() + 0.06 * rect.width(), rect.center().y);
    for pressed in [true, false] {
        h.event(egui::Event::PointerMoved(near_start));
        h.event(egui::Event::PointerButton {
            pos: near_start,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::default(),
        });
        h.step();
    }
    h.run_ok();
    let early = h.state().replay.frame;
    assert!(early <= 2, "a click near the start seeks to frame {early}");
    // And near the right edge, the last frames.
    let near_end = egui::pos2(rect.right() - 0.06 * rect.width(), rect.center().y);
    for pressed in [true, false] {
        h.event(egui::Event::PointerMoved(near_end));
        h.event(egui::Event::PointerButton {
            pos: near_end,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::default(),
        });
        h.step();
    }
    h.run_ok();
    let late = h.state().replay.frame;
    assert!(
        late + 3 >= n,
        "a click near the end seeks to frame {late} of {n} ({t0}..{t1} s)"
    );
    h.get_by_label_contains(&format!("Frame {} / {n}", late + 1));
}

/// A session of one frame per grasp (as BTS3 is) has no time axis: the replay shows its
/// values, a bar per finger, instead of an empty trace.
#[test]
fn a_single_frame_grasp_shows_its_values_not_an_empty_trace() {
    let mut s = tactile_workbench::session::load(&common::sample("grasp-stability.json"))
        .expect("the sample loads");
    for g in &mut s.grasps {
        let key = g.frames[g.key_frame].clone();
        g.frames = vec![key];
        g.key_frame = 0;
    }
    s.meta.name = "one frame per grasp".into();
    let dir = common::temp_dir("single-frame");
    let path = dir.join("single.json");
    tactile_workbench::session::save(&s, &path).expect("saved");
    let mut h = common::gui::workbench_opening(
        vec![path, common::sample("object-recognition.json")],
        1400.0,
        900.0,
    );
    h.run_ok();
    let active = h.state().browser.active;
    assert_eq!(
        h.state().sessions[active].session.meta.name,
        "one frame per grasp"
    );
    h.get_by_label_contains("Frame 1 / 1 ·");
    h.get_by_label("Per-finger mean of pressure (the grasp's only frame)");
    assert!(
        h.query_by_label("Per-finger feature trace").is_none(),
        "a one-frame grasp drew a trace over time"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// How many texts reading `text` were painted, and how many of them lie whole within the
/// rectangle they were clipped to.
fn whole_texts(shapes: &[egui::epaint::ClippedShape], text: &str) -> (usize, usize) {
    fn walk(shape: &egui::Shape, clip: egui::Rect, text: &str, out: &mut (usize, usize)) {
        match shape {
            egui::Shape::Vec(v) => v.iter().for_each(|s| walk(s, clip, text, out)),
            egui::Shape::Text(t) if t.galley.text().trim() == text => {
                let rect = (t.galley.rect)
                    .rotate_bb(egui::emath::Rot2::from_angle(t.angle))
                    .translate(t.pos.to_vec2());
                out.0 += 1;
                out.1 += usize::from(clip.expand(1.0).contains_rect(rect));
            }
            _ => {}
        }
    }
    let mut out = (0, 0);
    for s in shapes {
        walk(&s.shape, s.clip_rect, text, &mut out);
    }
    out
}
