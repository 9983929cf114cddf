//! `bench-live`: the live path under the issue's load, measured end to end.
//!
//! The Foxglove SDK's own server (as in `tests/live.rs`) publishes 5 sensors × 24 taxels at
//! 1 kHz and the joints at 100 Hz, grasp after grasp (0.5 s each, announced by events),
//! for `--seconds` (default 60). The workbench window (an egui_kittest harness drawing the
//! live view at 60 frames per second on this thread) is connected through
//! File > Connect's path, `live::Running`, with a DS model of 10 classes following every
//! open grasp. At the end it prints:
//! - messages published and received;
//! - the latency from a frame's publication (its log time) to DS's class distribution
//!   for it, p50 and p95;
//! - the window's frame time (one harness step: layout and tessellation of every tile),
//!   p50, p95 and max; with `--headless` the window is never drawn (the engine alone, as
//!   `live` runs it);
//! - the process's RSS at 60 s and at the end (server, engine and window together; no
//!   recording: the issue's "recording aside"), and every `--rss-every` seconds.
//!
//! ```sh
//! cargo run --example bench-live -- --seconds 60
//! cargo run --example bench-live -- --seconds 600 --rss-every 60   # the 10-minute soak
//! ```

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use tactile_workbench::app::{View, WorkbenchApp};
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::features::FeatureSet;
// `serve` reads `publish` and `LiveError` from the crate root.
use tactile_workbench::live::LiveError;
use tactile_workbench::live::publish::{self, Message, Stream};
use tactile_workbench::models::{self, SequenceFitOptions};
use tactile_workbench::session::{self, Frame, Grasp, Layout, Sensor, Session};

#[path = "../src/live/serve.rs"]
#[allow(dead_code)]
mod serve;

const TAXELS: usize = 24;
const RATE_HZ: f64 = 1000.0;
const GRASP_S: f64 = 0.5;

/// The simulated recognition sample (10 objects, 5 fingertips of 12 taxels) widened to 24
/// taxels per sensor (a 4 × 6 grid, each taxel twice with a small offset) and resampled
/// to `hz` over `seconds` per grasp.
fn widened(hz: f64, seconds: f64, grasps_per_object: usize) -> Session {
    let s = session::simulate::object_recognition(7);
    let frames = (hz * seconds).round() as usize;
    let mut per_object = std::collections::HashMap::new();
    let grasps: Vec<Grasp> = s
        .grasps
        .iter()
        .filter(|g| {
            let n = per_object.entry(g.object.clone()).or_insert(0usize);
            *n += 1;
            *n <= grasps_per_object
        })
        .map(|g| {
            let last = g.frames.len().saturating_sub(1).max(1) as f64;
            let frames = (0..frames)
                .map(|i| {
                    // Linear interpolation between the sample's frames.
                    let x = i as f64 / (frames - 1).max(1) as f64 * last;
                    let (a, w) = (x.floor() as usize, x.fract());
                    let b = (a + 1).min(g.frames.len() - 1);
                    let (fa, fb) = (&g.frames[a], &g.frames[b]);
                    let mix = |p: &[f64], q: &[f64]| -> Vec<f64> {
                        p.iter().zip(q).map(|(u, v)| u + w * (v - u)).collect()
                    };
                    Frame {
                        t: i as f64 / hz,
                        taxels: fa
                            .taxels
                            .iter()
                            .zip(&fb.taxels)
                            .map(|(p, q)| {
                                let v = mix(p, q);
                                (0..TAXELS)
                                    .map(|k| v[k % v.len()] + (k / v.len()) as f64)
                                    .collect()
                            })
                            .collect(),
                        encoders: mix(&fa.encoders, &fb.encoders),
                    }
                })
                .collect();
            Grasp {
                frames,
                key_frame: (g.key_frame as f64 / last * (frames_len(hz, seconds) - 1) as f64)
                    as usize,
                ..g.clone()
            }
        })
        .collect();
    let sensors = s
        .sensors
        .iter()
        .map(|x| Sensor {
            layout: Layout::Grid { rows: 4, cols: 6 },
            range: None,
            transform: session::ValueTransform::Identity,
            ..x.clone()
        })
        .collect();
    let mut meta = s.meta.clone();
    meta.frame_rate_hz = Some(hz);
    meta.name = format!("bench {hz} Hz");
    Session {
        meta,
        sensors,
        grasps,
        ..s
    }
}

fn frames_len(hz: f64, seconds: f64) -> usize {
    (hz * seconds).round() as usize
}

fn rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(f64::NAN, |pages| pages * 4096.0 / 1e6)
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(((v.len() as f64 * q).ceil() as usize).saturating_sub(1))
        .copied()
        .unwrap_or(f64::NAN)
}

fn main() {
    let mut seconds = 60.0;
    let mut rss_every = None;
    let mut headless = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--headless" {
            headless = true;
            continue;
        }
        match (a.as_str(), args.next().and_then(|v| v.parse::<f64>().ok())) {
            ("--seconds", Some(v)) if v > 0.0 => seconds = v,
            ("--rss-every", Some(v)) if v > 0.0 => rss_every = Some(v),
            _ => {
                eprintln!("usage: bench-live [--seconds S] [--rss-every S] [--headless]");
                std::process::exit(2);
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("bench-live-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");

    // DS on 10 classes: 5 grasps per object of the same sensors at 50 Hz.
    let train = widened(50.0, GRASP_S, 5);
    let defaults = RecognitionParams::default();
    let opts = SequenceFitOptions {
        method: MethodId::Ds,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        seed: 0,
        ds: defaults.ds,
        gs: defaults.gs,
    };
    let t = Instant::now();
    let (model, secs) = models::fit_sequences(&train, &opts).expect("DS fits");
    let file = models::sequence_file(model, &train, secs, Default::default(), None);
    let model_path = dir.join("ds.json");
    models::save(&file, &model_path).expect("the model saves");
    println!(
        "DS: {} classes, {} features, fitted in {:.1} s",
        file.provenance.classes.len(),
        match &file.model {
            models::Model::Sequences(m) => m.inputs.feature_names.len(),
            _ => 0,
        },
        t.elapsed().as_secs_f64()
    );

    let shown = widened(RATE_HZ, GRASP_S, 2);
    let stream = Stream::new(&shown, 1.0).expect("a stream");
    let spec_path = dir.join("spec.json");
    std::fs::write(&spec_path, stream.spec().to_string()).expect("the spec saves");
    let topics = stream.topics.clone();
    let joints_topic = shown.sensors.len();
    let mut server = serve::Server::start("127.0.0.1", 0, &topics).expect("the server starts");
    let port = server.port();

    // The window, connected as File > Connect does.
    let mut app = WorkbenchApp::new(&egui::Context::default(), None, Vec::new());
    app.view = View::Live;
    let live = &mut app.rooms.live;
    live.form.url = format!("ws://127.0.0.1:{port}");
    live.form.spec = spec_path.display().to_string();
    live.form.model = model_path.display().to_string();
    live.connect();
    let mut h = egui_kittest::Harness::builder()
        .with_size(egui::Vec2::new(1400.0, 900.0))
        .with_step_dt(1.0 / 60.0)
        .build_ui_state(
            |ui, app: &mut WorkbenchApp| {
                app.tick(ui.ctx());
                app.show(ui);
            },
            app,
        );

    let stop = Arc::new(AtomicBool::new(false));
    let publisher = {
        let stop = stop.clone();
        let shown = shown.clone();
        std::thread::spawn(move || {
            let stream = Stream::new(&shown, 1.0).expect("a stream");
            server.wait_for_subscriptions(stream.topics.len(), &stop);
            let n = shown.grasps.len();
            let limit = (seconds * 1e9) as u64;
            // Grasp after grasp until the time is up; the joints at every 10th frame.
            let mut at = 0;
            let messages = (0..).map_while(move |g: usize| {
                (at < limit).then(|| {
                    let (m, next) = stream.grasp(g % n, at);
                    at = next;
                    m
                })
            });
            let mut joint = 0usize;
            let thinned = messages.flatten().filter(move |m: &Message| {
                if m.topic != joints_topic {
                    return true;
                }
                joint += 1;
                joint % 10 == 1
            });
            let published = server.play_messages(thinned, &stop);
            (server, published)
        })
    };

    let mut frame_ms = Vec::new();
    let started = Instant::now();
    let mut rss_at_60 = None;
    let mut next_rss = rss_every.unwrap_or(f64::INFINITY);
    while !publisher.is_finished() {
        let t = Instant::now();
        if !headless {
            h.step();
            frame_ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        if rss_at_60.is_none() && started.elapsed() > Duration::from_secs(60) {
            rss_at_60 = Some(rss_mb());
        }
        let at = started.elapsed().as_secs_f64();
        if at >= next_rss {
            let snap = h.state().rooms.live.snapshot();
            let (messages, grasps) = snap.map_or((0, 0), |s| {
                let s = s.lock().unwrap();
                (s.status.messages, s.grasps)
            });
            println!(
                "at {at:.0} s: RSS {:.1} MB, {messages} messages, {grasps} grasps",
                rss_mb()
            );
            next_rss += rss_every.unwrap_or(f64::INFINITY);
        }
        // A display at 60 Hz: the next frame when it is due.
        std::thread::sleep(Duration::from_secs_f64(1.0 / 60.0).saturating_sub(t.elapsed()));
    }
    let rss_end = rss_mb();
    let (server, published) = publisher.join().expect("the publisher");
    // What is still in the sockets and the queue arrives: wait until every message is in,
    // or the count has stood still for 2 s.
    let received = |h: &egui_kittest::Harness<'_, WorkbenchApp>| {
        h.state()
            .rooms
            .live
            .snapshot()
            .map_or(0, |s| s.lock().unwrap().status.messages)
    };
    let (mut last, mut since) = (received(&h), Instant::now());
    while received(&h) < published as u64 && since.elapsed() < Duration::from_secs(2) {
        if !headless {
            h.step();
        }
        std::thread::sleep(Duration::from_millis(50));
        if received(&h) != last {
            (last, since) = (received(&h), Instant::now());
        }
    }
    let snap = h
        .state()
        .rooms
        .live
        .snapshot()
        .expect("connected")
        .lock()
        .unwrap()
        .clone();
    h.state_mut().rooms.live.disconnect();
    server.stop();

    let st = &snap.status;
    println!(
        "{seconds:.0} s of stream: {published} messages published, {} received, {} malformed, \
         {} queue waits, {} frames left out; {} grasps, {} recorded",
        st.messages, st.malformed, st.waits, snap.left_out, snap.grasps, snap.recorded
    );
    let q = |p| snap.model_latency.quantile(p).unwrap_or(f64::NAN);
    println!(
        "publish → DS step latency over {} frames: p50 {:.2} ms, p95 {:.2} ms",
        snap.model_latency.count(),
        q(0.5),
        q(0.95)
    );
    let n = frame_ms.len();
    let max = frame_ms.iter().copied().fold(0.0, f64::max);
    let (p50, p95) = (
        percentile(&mut frame_ms, 0.5),
        percentile(&mut frame_ms, 0.95),
    );
    if headless {
        println!("headless: the window was not drawn");
    } else {
        println!(
            "window frame time over {n} frames: p50 {p50:.2} ms, p95 {p95:.2} ms, max {max:.2} ms"
        );
    }
    match rss_at_60 {
        Some(r) => println!(
            "RSS: {r:.1} MB at 60 s, {rss_end:.1} MB at the end ({:+.1} MB)",
            rss_end - r
        ),
        None => println!("RSS: {rss_end:.1} MB at the end (a run under 60 s has no minute-1 mark)"),
    }
    let _ = std::fs::remove_dir_all(Path::new(&dir));
}
