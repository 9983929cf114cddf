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
use tactile_workbench::app::{View, WorkbenchApp};
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::features::FeatureSet;
// `serve` reads `publish` from the crate root.
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
    let topics = Stream::new(&s, rate).unwrap().topics;
    let mut server = serve::Server::start("127.0.0.1", 0, &topics).unwrap();
    let port = server.port();
    let thread = std::thread::spawn(move || {
        let stream = Stream::new(&s, rate).unwrap();
        server.wait_for_subscriptions(stream.topics.len(), &stop);
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

    h.get_all_by_label("Disconnect").next().unwrap().click();
    h.run_ok();
    assert!(!h.state().rooms.live.is_connected());
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    server.join().unwrap();
}
