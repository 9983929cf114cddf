//! The live view against a served sample: the Foxglove SDK's own server (as in
//! `tests/live.rs`) plays grasps of the simulated recognition sample; the window connects
//! through File > Connect to a live stream…, shows the frames, the status and DS at work,
//! pauses its display while the stream goes on, and proposes a spec from the channels.
#![cfg(feature = "gui")]

mod common;

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::views::pane::LivePane;
use tactile_workbench::app::views::{Pane, layout_key};
use tactile_workbench::app::{View, WorkbenchApp};
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::features::FeatureSet;
// `serve` reads `publish` and `LiveError` from the crate root.
use tactile_workbench::live::LiveError;
use tactile_workbench::live::publish::{self, Stream};
use tactile_workbench::models::{self, SequenceFitOptions};
use tactile_workbench::session::{self, ImportSpec, Session};

#[path = "../src/live/serve.rs"]
#[allow(dead_code)]
mod serve;

fn sample() -> Session {
    session::load(&common::sample("object-recognition.json")).unwrap()
}

/// Serve `s` at `rate` on a free port once a client subscribed to every topic, the grasps
/// over and over until `stop`.
fn serve_loop(s: Session, rate: f64, stop: Arc<AtomicBool>) -> (u16, std::thread::JoinHandle<()>) {
    let topics = Stream::new(&s, rate).unwrap().topics.len();
    serve_loop_for(s, rate, stop, topics)
}

/// [`serve_loop`] once clients hold `subscriptions` (a spec may leave topics out).
fn serve_loop_for(
    s: Session,
    rate: f64,
    stop: Arc<AtomicBool>,
    subscriptions: usize,
) -> (u16, std::thread::JoinHandle<()>) {
    let topics = Stream::new(&s, rate).unwrap().topics;
    let mut server = serve::Server::start("127.0.0.1", 0, &topics).unwrap();
    let port = server.port();
    let thread = std::thread::spawn(move || {
        let stream = Stream::new(&s, rate).unwrap();
        server.wait_for_subscriptions(subscriptions, &stop);
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            server.play(&stream, 0..s.grasps.len(), &stop, |_| {});
        }
        server.stop();
    });
    (port, thread)
}

/// Step the window until `done` (bounded), sleeping so the stream's threads run.
fn step_until(
    h: &mut Harness<'static, WorkbenchApp>,
    limit: Duration,
    done: impl Fn(&WorkbenchApp) -> bool,
) {
    let t = Instant::now();
    while !done(h.state()) && t.elapsed() < limit {
        h.step();
        std::thread::sleep(Duration::from_millis(15));
    }
    h.step();
}

fn engine_grasps(app: &WorkbenchApp) -> usize {
    app.rooms
        .live
        .snapshot()
        .map_or(0, |s| s.lock().unwrap().grasps)
}

#[test]
fn the_live_view_shows_a_served_stream_with_ds_at_work() {
    let dir = common::temp_dir("gui-live");
    let all = sample();
    let (mut train, mut shown) = (all.clone(), all);
    train.grasps.truncate(40);
    shown.grasps.drain(..40);
    shown.grasps.truncate(6);
    let defaults = RecognitionParams::default();
    let mut ds = defaults.ds;
    ds.gp.capacity = 20;
    let opts = SequenceFitOptions {
        method: MethodId::Ds,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        seed: 0,
        ds,
        gs: defaults.gs,
    };
    let (model, secs) = models::fit_sequences(&train, &opts).unwrap();
    let model_path = dir.join("ds.json");
    models::save(
        &models::sequence_file(model, &train, secs, Default::default(), None),
        &model_path,
    )
    .unwrap();
    let spec_path = dir.join("served.spec.json");
    std::fs::write(
        &spec_path,
        Stream::new(&shown, 1.0).unwrap().spec().to_string(),
    )
    .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    // About a second and a half per grasp.
    let (port, server) = serve_loop(shown, 1.0, stop.clone());

    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Connect to a live stream…").click();
    h.run_ok();
    assert_eq!(h.state().view, View::Live);
    assert!(h.state().form_open);
    h.get_by_label("Not connected: File > Connect to a live stream…, or the form's Connect.");

    // Without a spec the form lists the server's channels and proposes one.
    h.state_mut().rooms.live.form.url = format!("ws://127.0.0.1:{port}");
    h.get_by_label("List channels").click();
    step_until(&mut h, Duration::from_secs(10), |_| false);
    h.get_by_label_contains("7 channels advertised");
    h.get_by_label_contains("/tactile/thumb: std_msgs/msg/Float64MultiArray (cdr), 12 values");
    let proposed = dir.join("proposed.spec.json");
    h.get_by_label("Save as").focus();
    h.run_ok();
    h.get_by_label("Save as")
        .type_text(&proposed.display().to_string());
    h.run_ok();
    h.get_by_label("Save spec").scroll_to_me();
    h.run_ok();
    h.get_by_label("Save spec").click();
    h.run_ok();
    h.get_by_label(&format!("saved {}", proposed.display()));
    let spec = ImportSpec::load(&proposed).unwrap();
    assert_eq!(spec.sensors.len(), 5);
    assert_eq!(spec.sensors[0].sensor.layout.taxel_count(), 12);
    assert_eq!(spec.encoder_names(), sample().encoders);
    assert_eq!(
        h.state().rooms.live.form.spec,
        proposed.display().to_string()
    );

    // Connect with the served spec and the model.
    {
        let form = &mut h.state_mut().rooms.live.form;
        form.spec = spec_path.display().to_string();
        form.model = model_path.display().to_string();
    }
    h.get_by_label("Connect").click();
    step_until(&mut h, Duration::from_secs(30), |app| {
        app.rooms.live.snapshot().is_some_and(|s| {
            let s = s.lock().unwrap();
            s.grasps >= 1 && s.open_verdict.as_ref().is_some_and(|v| v.steps.len() >= 3)
        })
    });
    h.get_by_label_contains("connected to `tactile-workbench serve` (foxglove.sdk.v1)");
    h.get_by_label_contains("0 malformed");
    for finger in ["thumb", "index", "middle", "ring", "little"] {
        assert!(h.get_all_by_label(finger).next().is_some(), "{finger}");
    }
    // DS at work on the open grasp, step by step.
    h.get_by_label_contains("Grasp in progress:");
    h.get_by_label_contains("ds: running decision");
    h.get_by_label_contains("Class distribution at step");
    h.get_by_label_contains("grasp 1: ");

    // Pause freezes the display; the engine goes on.
    h.get_by_label("Pause").click();
    h.run_ok();
    assert!(h.state().rooms.live.paused());
    let shown_then = engine_grasps(h.state());
    let line = format!("· {shown_then} grasps ·");
    step_until(&mut h, Duration::from_secs(20), |app| {
        engine_grasps(app) > shown_then
    });
    assert!(engine_grasps(h.state()) > shown_then, "the stream went on");
    h.get_by_label_contains(&line);
    h.get_by_label("Resume").click();
    h.run_ok();
    h.step();
    assert!(!h.state().rooms.live.paused());
    let now = engine_grasps(h.state());
    h.get_by_label_contains(&format!("· {now} grasps ·"));

    // At 1000 × 700, with four grasps listed below it, the model's chart keeps three y
    // labels: the list gives way to the chart, not the chart to the list.
    step_until(&mut h, Duration::from_secs(30), |app| {
        engine_grasps(app) >= 5
    });
    h.set_size(egui::Vec2::new(1000.0, 700.0));
    h.run_steps(4);
    let layout = &h.state().layouts[&layout_key(View::Live)];
    let id = (layout.tree.tiles)
        .find_pane(&Pane::Live(LivePane::Model))
        .expect("a model tile");
    let tile = layout.tree.tiles.rect(id).expect("shown");
    let labels = y_labels(&h.output().shapes, tile);
    assert!(
        labels >= 3,
        "the model's chart shows {labels} y labels in {tile:?}"
    );

    h.get_all_by_label("Disconnect").next().unwrap().click();
    h.run_ok();
    assert!(!h.state().rooms.live.is_connected());
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    server.join().unwrap();
}

/// The most numbers painted in one right-aligned column in the left half of `tile`: a
/// chart's y tick labels (the class bars' values stand at the tile's right edge).
fn y_labels(shapes: &[egui::epaint::ClippedShape], tile: egui::Rect) -> usize {
    fn numbers(shape: &egui::Shape, out: &mut Vec<egui::Rect>) {
        match shape {
            egui::Shape::Vec(v) => v.iter().for_each(|s| numbers(s, out)),
            egui::Shape::Text(t) if t.galley.text().trim().parse::<f64>().is_ok() => {
                out.push(t.galley.rect.translate(t.pos.to_vec2()));
            }
            _ => {}
        }
    }
    let mut rects = Vec::new();
    for s in shapes.iter().filter(|s| tile.contains_rect(s.clip_rect)) {
        numbers(&s.shape, &mut rects);
    }
    let mut columns: std::collections::BTreeMap<i32, Vec<i32>> = Default::default();
    for r in rects.iter().filter(|r| r.right() < tile.center().x) {
        let ys = columns.entry(r.right().round() as i32).or_default();
        ys.push(r.center().y.round() as i32);
    }
    (columns.into_values())
        .map(|mut ys| {
            ys.sort();
            ys.dedup();
            ys.len()
        })
        .max()
        .unwrap_or(0)
}

/// A DU model at work on an open grasp: the running cluster, and the novelty of the grasp
/// so far as a chart against the threshold, step by step.
#[test]
fn the_live_view_shows_du_novelty_step_by_step() {
    use tactile_workbench::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use tactile_workbench::models::ClusterFitOptions;
    let dir = common::temp_dir("gui-live-du");
    let all = sample();
    let (mut train, mut shown) = (all.clone(), all);
    train.grasps.truncate(40);
    shown.grasps.drain(..40);
    shown.grasps.truncate(4);
    let mut params = ClusteringParams::for_learner(UnsupervisedLearner::Du);
    params.ds.gp.capacity = 20;
    let opts = ClusterFitOptions {
        method: MethodId::Du,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        threshold: 0.4,
        seed: 0,
        params,
    };
    let (model, _) = models::fit_clusters(&train, &opts).unwrap();
    let model_path = dir.join("du.json");
    models::save(&models::cluster_file(model, &train, 0.0, None), &model_path).unwrap();
    let spec_path = dir.join("served.spec.json");
    std::fs::write(
        &spec_path,
        Stream::new(&shown, 1.0).unwrap().spec().to_string(),
    )
    .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let (port, server) = serve_loop(shown, 1.0, stop.clone());
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Connect to a live stream…").click();
    h.run_ok();
    {
        let form = &mut h.state_mut().rooms.live.form;
        form.url = format!("ws://127.0.0.1:{port}");
        form.spec = spec_path.display().to_string();
        form.model = model_path.display().to_string();
    }
    h.get_by_label("Connect").click();
    step_until(&mut h, Duration::from_secs(30), |app| {
        app.rooms.live.snapshot().is_some_and(|s| {
            let s = s.lock().unwrap();
            s.open_verdict
                .as_ref()
                .is_some_and(|v| v.novelty_steps.len() >= 3)
        })
    });
    h.get_by_label_contains("Grasp in progress:");
    h.get_by_label_contains("du: running decision cluster");
    h.get_by_label_contains("(new cluster above 0.400)");
    h.get_by_label_contains("of the grasp so far against cluster");
    h.get_by_label_contains("du novelty of the grasp so far, step by step");
    // The chart is the open verdict's: its novelty at every step, the threshold marked.
    let snap = h.state().rooms.live.snapshot().unwrap();
    let v = snap.lock().unwrap().open_verdict.clone().unwrap();
    let figure = v.figure(5).unwrap();
    let tactile_workbench::figures::FigureKind::Chart(c) = &figure.kind else {
        panic!("a chart")
    };
    assert_eq!(c.series.len(), 1);
    let novelties: Vec<f64> = v.novelty_steps.iter().map(|s| s.novelty).collect();
    assert_eq!(c.series[0].y, novelties);
    assert_eq!(c.ref_lines.len(), 1);
    assert_eq!(c.ref_lines[0].value, 0.4);
    h.get_all_by_label("Disconnect").next().unwrap().click();
    h.run_ok();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    server.join().unwrap();
}

/// A pad of 2 × 2 taxels pressed in the middle of each grasp: 20 idle frames (with a
/// little noise, so the idle total has a spread), 20 pressed, 20 idle, at 50 Hz; objects
/// cup and mug, outcome ok or slip.
fn pressed_pad(grasps: usize) -> Session {
    use tactile_workbench::session::{
        Frame, Grasp, LabelSet, Layout, Sensor, SessionMeta, ValueTransform,
    };
    let grasps = (0..grasps)
        .map(|g| Grasp {
            object: ["cup", "mug"][g % 2].into(),
            trial: None,
            labels: vec![g % 2, (g / 2) % 2],
            frames: (0..60)
                .map(|i| {
                    let idle = 1.0 + 0.05 * ((i * 7 + g) % 5) as f64;
                    let v = if (20..40).contains(&i) { 50.0 } else { idle };
                    Frame {
                        t: i as f64 / 50.0,
                        taxels: vec![vec![v; 4]],
                        encoders: Vec::new(),
                    }
                })
                .collect(),
            key_frame: 30,
        })
        .collect();
    Session {
        meta: SessionMeta {
            name: "pressed pad".into(),
            source: "tests/gui_live.rs".into(),
            licence: String::new(),
            citation: String::new(),
            frame_rate_hz: Some(50.0),
            notes: String::new(),
        },
        sensors: vec![Sensor {
            name: "pad".into(),
            layout: Layout::Grid { rows: 2, cols: 2 },
            unit: "kPa".into(),
            transform: ValueTransform::Identity,
            range: None,
        }],
        encoders: Vec::new(),
        label_sets: vec![
            LabelSet {
                name: "object".into(),
                classes: vec!["cup".into(), "mug".into()],
            },
            LabelSet {
                name: "outcome".into(),
                classes: vec!["ok".into(), "slip".into()],
            },
        ],
        grasps,
    }
}

fn snapshot_of(app: &WorkbenchApp) -> Option<tactile_workbench::live::Snapshot> {
    app.rooms.live.snapshot().map(|s| s.lock().unwrap().clone())
}

/// Choose `option` in the combo box labelled `combo`.
fn choose(h: &mut Harness<'static, WorkbenchApp>, combo: &str, option: &str) {
    h.get_by_label(combo).click();
    h.run_ok();
    h.get_by_label(option).click();
    h.run_ok();
}

/// Cutting by hand (Start grasp, the key K, the key G with the labels chosen) and, on a
/// stream without events, labelling the next contact grasp: each grasp is recorded with
/// the object and labels chosen in the view.
#[test]
fn the_live_view_cuts_by_hand_and_labels_contact_grasps() {
    let dir = common::temp_dir("gui-live-hand");
    let pad = pressed_pad(40);
    // No events topic: grasps are cut by contact, or by hand when asked.
    let mut spec = Stream::new(&pad, 1.0).unwrap().spec();
    spec.as_object_mut().unwrap().remove("grasps");
    spec["live"] = serde_json::json!({"contact": {"min_rise": 20, "min_duration_s": 0.2}});
    let spec_path = dir.join("pad.spec.json");
    std::fs::write(&spec_path, spec.to_string()).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    // The pad's topic only: the spec leaves the events out.
    let (port, server) = serve_loop_for(pad, 1.0, stop.clone(), 1);

    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Connect to a live stream…").click();
    h.run_ok();
    let by_hand = dir.join("by-hand.json");
    {
        let form = &mut h.state_mut().rooms.live.form;
        form.url = format!("ws://127.0.0.1:{port}");
        form.spec = spec_path.display().to_string();
        form.record = by_hand.display().to_string();
    }
    h.get_by_label("Cut grasps by hand").click();
    h.run_ok();
    h.get_by_label("Connect").click();
    step_until(&mut h, Duration::from_secs(20), |app| {
        snapshot_of(app).is_some_and(|s| s.latest.is_some())
    });
    assert!(
        snapshot_of(h.state()).unwrap().latest.is_some(),
        "no frame arrived"
    );
    h.get_by_label_contains("cut by hand");
    choose(&mut h, "known objects", "mug");
    choose(&mut h, "outcome", "slip");
    h.get_by_label("Start grasp (G)").click();
    step_until(&mut h, Duration::from_secs(10), |app| {
        snapshot_of(app).is_some_and(|s| s.in_progress >= 10)
    });
    h.key_press(egui::Key::K);
    step_until(&mut h, Duration::from_secs(10), |app| {
        snapshot_of(app).is_some_and(|s| s.in_progress >= 20)
    });
    h.key_press(egui::Key::G);
    step_until(&mut h, Duration::from_secs(10), |app| {
        engine_grasps(app) == 1
    });
    assert_eq!(engine_grasps(h.state()), 1);
    h.get_by_label_contains("grasp 1: mug outcome=slip");
    // The next G starts a grasp again (the button says what G does next).
    h.get_by_label("Start grasp (G)");
    h.get_all_by_label("Disconnect").next().unwrap().click();
    h.run_ok();
    // The engine finishes the recording on its own thread.
    let t = Instant::now();
    while session::journal::journal_path(&by_hand).exists() && t.elapsed() < Duration::from_secs(10)
    {
        std::thread::sleep(Duration::from_millis(20));
    }
    let recorded = session::load(&by_hand).unwrap();
    assert_eq!(recorded.grasps.len(), 1);
    let g = &recorded.grasps[0];
    assert_eq!(g.object, "mug");
    assert_eq!(recorded.label_sets[1].classes[g.labels[1]], "slip");
    assert!(g.frames.len() >= 20, "{} frames", g.frames.len());
    // The key frame is where K was pressed, not the last frame.
    assert!(
        g.key_frame >= 9 && g.key_frame + 1 < g.frames.len(),
        "{}",
        g.key_frame
    );

    // By contact: the labels chosen go to the next grasp; the one after is unlabelled.
    let by_contact = dir.join("by-contact.json");
    h.get_by_label("Cut grasps by hand").click();
    h.state_mut().rooms.live.form.record = by_contact.display().to_string();
    h.run_ok();
    h.get_by_label("Connect").click();
    step_until(&mut h, Duration::from_secs(10), |app| {
        snapshot_of(app).is_some_and(|s| s.cutting == "by contact")
    });
    h.get_by_label_contains("cut by contact");
    choose(&mut h, "known objects", "cup");
    choose(&mut h, "outcome", "ok");
    h.get_by_label("Label the next grasp").click();
    h.run_ok();
    step_until(&mut h, Duration::from_secs(30), |app| {
        engine_grasps(app) >= 2
    });
    h.get_by_label_contains("grasp 1: cup outcome=ok");
    h.get_by_label_contains("grasp 2: unlabelled");
    h.get_all_by_label("Disconnect").next().unwrap().click();
    h.run_ok();
    let t = Instant::now();
    while session::journal::journal_path(&by_contact).exists()
        && t.elapsed() < Duration::from_secs(10)
    {
        std::thread::sleep(Duration::from_millis(20));
    }
    let recorded = session::load(&by_contact).unwrap();
    assert!(recorded.grasps.len() >= 2);
    let (first, second) = (&recorded.grasps[0], &recorded.grasps[1]);
    assert_eq!(first.object, "cup");
    assert_eq!(recorded.label_sets[1].classes[first.labels[1]], "ok");
    assert_eq!(second.object, "unlabelled");
    // A contact grasp holds the pressed frames (20 at 50 Hz), give or take the hysteresis.
    assert!(
        (15..=25).contains(&first.frames.len()),
        "{}",
        first.frames.len()
    );
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    server.join().unwrap();
}
