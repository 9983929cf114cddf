//! Live streams against the real thing: the Foxglove SDK's own WebSocket server (the
//! `foxglove` crate) on 127.0.0.1 publishes a session through `live::serve`, and the live
//! client records it, cuts it, and runs a model on it. A hand-made server covers what the
//! SDK's server cannot send: the old subprotocol alone, and malformed messages.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::features::FeatureSet;
use tactile_workbench::live::client::State;
use tactile_workbench::live::model::LiveModel;
// `serve` reads `publish` and `LiveError` from the crate root.
use tactile_workbench::live::publish::{self, Stream};
use tactile_workbench::live::{GraspReport, Live, LiveError, LiveOptions, Snapshot};
use tactile_workbench::models::{self, Calibration, SequenceFitOptions};
use tactile_workbench::session::{self, ImportSpec, Session, SubsetSpec, import_icub, subset};

#[path = "../src/live/serve.rs"]
#[allow(dead_code)]
mod serve;

/// The first `n` grasps of the simulated recognition sample.
fn sample(n: usize) -> Session {
    let mut s = session::load(&common::sample("object-recognition.json")).unwrap();
    s.grasps.truncate(n);
    s
}

/// The speed-up that plays `s` in about `seconds`.
fn rate_for(s: &Session, seconds: f64) -> f64 {
    let total: f64 = s
        .grasps
        .iter()
        .map(|g| g.frames.last().map_or(0.0, |f| f.t) + 0.5)
        .sum();
    total / seconds
}

/// The spec that reads `s` back, written into `dir`.
fn spec_of(s: &Session, dir: &Path) -> ImportSpec {
    let path = dir.join("spec.json");
    let stream = Stream::new(s, 1.0).unwrap();
    std::fs::write(&path, serde_json::to_string(&stream.spec()).unwrap()).unwrap();
    ImportSpec::load(&path).unwrap()
}

/// A server playing grasps of a session; `done` stops it (and the test then fails on
/// what the client saw, rather than hanging on a server that waits for it).
struct Playing {
    port: u16,
    stop: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<serve::Server>,
}

impl Playing {
    fn done(self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        self.thread.join().unwrap().stop();
    }
}

/// A server on a free port (or `port`), playing grasps `range` of `s` at `rate` once a
/// client subscribed to every topic.
fn play(s: &Session, rate: f64, port: u16, range: std::ops::Range<usize>) -> Playing {
    let topics = Stream::new(s, rate).unwrap().topics;
    // A port just let go of (a restarted server) may take a moment to bind again.
    let t = Instant::now();
    let mut server = loop {
        match serve::Server::start("127.0.0.1", port, &topics) {
            Ok(s) => break s,
            Err(e) if port == 0 || t.elapsed() > Duration::from_secs(2) => panic!("{e}"),
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    };
    let port = server.port();
    let s = s.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        let stream = Stream::new(&s, rate).unwrap();
        server.wait_for_subscriptions(stream.topics.len(), &flag);
        server.play(&stream, range, &flag, |_| {});
        server
    });
    Playing { port, stop, thread }
}

fn options(port: u16, spec: ImportSpec, record: Option<PathBuf>) -> LiveOptions {
    LiveOptions {
        url: format!("ws://127.0.0.1:{port}"),
        spec,
        by_hand: false,
        model: None,
        record,
        trace_seconds: 5.0,
    }
}

/// Run `live` until `done` holds of its reports (or `limit` passes), then finish it.
fn run(
    mut live: Live,
    limit: Duration,
    mut done: impl FnMut(&[GraspReport], &Snapshot) -> bool,
) -> (Vec<GraspReport>, Snapshot) {
    let start = Instant::now();
    let snapshot = live.snapshot();
    let mut reports = Vec::new();
    while start.elapsed() < limit {
        reports.extend(live.step(Duration::from_millis(20)));
        let snap = snapshot.lock().unwrap().clone();
        if done(&reports, &snap) {
            break;
        }
    }
    let (rest, snap) = live.finish();
    reports.extend(rest);
    (reports, snap)
}

/// The recording holds `served`'s grasps: values, labels, key frames and frame counts.
fn assert_same_grasps(recorded: &Session, served: &Session) {
    assert_eq!(recorded.sensors, served.sensors);
    assert_eq!(recorded.encoders, served.encoders);
    assert_eq!(recorded.label_sets, served.label_sets);
    assert_eq!(recorded.grasps.len(), served.grasps.len());
    for (i, (r, s)) in recorded.grasps.iter().zip(&served.grasps).enumerate() {
        assert_eq!((&r.object, &r.labels), (&s.object, &s.labels), "grasp {i}");
        assert_eq!(r.frames.len(), s.frames.len(), "grasp {i} frames");
        assert_eq!(r.key_frame, s.key_frame, "grasp {i} key frame");
        for (fr, fs) in r.frames.iter().zip(&s.frames) {
            assert_eq!((&fr.taxels, &fr.encoders), (&fs.taxels, &fs.encoders));
        }
    }
}

#[test]
fn a_served_session_records_back_exactly_over_the_sdk_subprotocol() {
    let dir = common::temp_dir("live-record");
    let s = sample(8);
    let spec = spec_of(&s, &dir);
    let server = play(&s, rate_for(&s, 1.5), 0, 0..s.grasps.len());
    let out = dir.join("rec.json");
    let live = Live::start(options(server.port, spec, Some(out.clone()))).unwrap();
    let (reports, snap) = run(live, Duration::from_secs(20), |r, _| r.len() == 8);
    server.done();
    assert_eq!(reports.len(), 8, "{snap:?}");
    match &snap.status.state {
        State::Stopped => {}
        other => panic!("{other:?}"),
    }
    assert_eq!(snap.status.malformed, 0, "{:?}", snap.status.last_malformed);
    // Five sensors, the joints and the events.
    assert_eq!(snap.status.subscribed.len(), 7);
    assert_same_grasps(&session::load(&out).unwrap(), &s);
    // The trace is bounded by its span.
    let (first, last) = (snap.trace.front().unwrap().0, snap.trace.back().unwrap().0);
    assert!(last - first <= 5_000_000_000);
}

#[test]
fn the_sdk_server_negotiates_the_new_subprotocol() {
    let s = sample(2);
    let dir = common::temp_dir("live-proto");
    let spec = spec_of(&s, &dir);
    let server = play(&s, rate_for(&s, 0.5), 0, 0..2);
    let live = Live::start(options(server.port, spec, None)).unwrap();
    let mut seen = None;
    let (reports, snap) = run(live, Duration::from_secs(20), |r, snap| {
        if let State::Connected { subprotocol, .. } = &snap.status.state {
            seen = Some(subprotocol.clone());
        }
        r.len() == 2
    });
    server.done();
    assert_eq!(snap.status.malformed, 0);
    assert_eq!(reports.len(), 2);
    assert_eq!(seen.as_deref(), Some("foxglove.sdk.v1"));
}

#[test]
fn the_client_reconnects_after_a_server_restart_and_loses_no_completed_grasp() {
    let dir = common::temp_dir("live-reconnect");
    let s = sample(8);
    let spec = spec_of(&s, &dir);
    let rate = rate_for(&s, 1.0);
    let first = play(&s, rate, 0, 0..4);
    let port = first.port;
    let out = dir.join("rec.json");
    let live = Live::start(options(port, spec, Some(out.clone()))).unwrap();
    let mut first = Some(first);
    let mut second = None;
    let mut restarted = None;
    let mut reconnected = None;
    let (reports, snap) = run(live, Duration::from_secs(30), |r, snap| {
        if r.len() == 4
            && let Some(f) = first.take()
        {
            f.done();
            second = Some(play(&s, rate, port, 4..8));
            restarted = Some(Instant::now());
        }
        if let (Some(t), None, State::Connected { .. }) =
            (restarted, reconnected, &snap.status.state)
            && snap.status.reconnects > 0
        {
            reconnected = Some(t.elapsed());
        }
        r.len() == 8
    });
    if let Some(s) = second {
        s.done();
    }
    let took = reconnected.expect("the client reconnected");
    assert!(took < Duration::from_secs(2), "reconnected after {took:?}");
    assert_eq!(reports.len(), 8, "{snap:?}");
    assert_same_grasps(&session::load(&out).unwrap(), &s);
}

fn trials(s: &Session, t: std::ops::RangeInclusive<u32>) -> Session {
    let spec = SubsetSpec {
        trials: t.into(),
        ..Default::default()
    };
    subset(s, &spec, "part").unwrap()
}

#[test]
fn live_ds_on_icub_equals_evaluate_bit_for_bit() {
    let Some(data) = common::dataset("icub-grasp") else {
        return;
    };
    let dir = common::temp_dir("live-icub");
    let icub = import_icub(&data).unwrap();
    let (train, test) = (trials(&icub, 1..=15), trials(&icub, 16..=20));
    let defaults = RecognitionParams::default();
    let opts = SequenceFitOptions {
        method: MethodId::Ds,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        seed: 0,
        ds: defaults.ds,
        gs: defaults.gs,
    };
    let (model, secs) = models::fit_sequences(&train, &opts).unwrap();
    let file = models::sequence_file(model, &train, secs, Default::default(), None);
    let model_path = dir.join("ds.json");
    models::save(&file, &model_path).unwrap();
    let offline = models::evaluate(&file, &test, Calibration::None).unwrap();
    let models::Model::Sequences(m) = &file.model else {
        panic!("a sequence model")
    };
    let steps = m.predict(&test, Calibration::None).unwrap();

    let spec = spec_of(&test, &dir);
    let n = test.grasps.len();
    let server = play(&test, rate_for(&test, 6.0), 0, 0..n);
    let out = dir.join("rec.json");
    let mut o = options(server.port, spec, Some(out.clone()));
    o.model = Some((model_path, false));
    let (reports, snap) = run(Live::start(o).unwrap(), Duration::from_secs(60), |r, _| {
        r.len() == n
    });
    server.done();
    assert_eq!(reports.len(), n, "{snap:?}");
    let mut right = 0;
    for (i, r) in reports.iter().enumerate() {
        let v = r.verdict.as_ref().unwrap().as_ref().unwrap();
        let want = &offline.predictions[i];
        assert_eq!(v.predicted, want.predicted, "grasp {i}");
        assert_eq!(v.decision.to_bits(), want.decision.to_bits(), "grasp {i}");
        let rows: Vec<Vec<u64>> = steps[i]
            .distributions
            .rows()
            .into_iter()
            .map(|row| row.iter().map(|x| x.to_bits()).collect())
            .collect();
        let live: Vec<Vec<u64>> = v
            .steps
            .iter()
            .map(|row| row.iter().map(|x| x.to_bits()).collect())
            .collect();
        assert_eq!(
            live, rows,
            "grasp {i}: the class distribution of every step"
        );
        right += usize::from(want.truth.as_deref() == Some(v.predicted.as_str()));
    }
    // Table II of the paper: DS above 0.95 on iCub.
    assert!(right as f64 / n as f64 >= 0.9, "{right} of {n}");
    assert_same_grasps(&session::load(&out).unwrap(), &test);
}

#[test]
fn teaching_live_equals_fit_from_grasp_by_grasp() {
    let dir = common::temp_dir("live-teach");
    let s = sample(40);
    let (train, taught) = {
        let mut a = s.clone();
        let mut b = s.clone();
        a.grasps.truncate(30);
        b.grasps.drain(..30);
        (a, b)
    };
    let defaults = RecognitionParams::default();
    let mut ds = defaults.ds;
    ds.gp.capacity = 20;
    let opts = SequenceFitOptions {
        method: MethodId::Ds,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        seed: 3,
        ds,
        gs: defaults.gs,
    };
    let (model, secs) = models::fit_sequences(&train, &opts).unwrap();
    let file = models::sequence_file(model, &train, secs, Default::default(), None);
    let file_at_start = file.clone();
    let live_path = dir.join("live.json");
    models::save(&file, &live_path).unwrap();

    let spec = spec_of(&taught, &dir);
    let n = taught.grasps.len();
    let server = play(&taught, rate_for(&taught, 1.5), 0, 0..n);
    let out = dir.join("rec.json");
    let mut o = options(server.port, spec, Some(out.clone()));
    o.model = Some((live_path.clone(), true));
    let (reports, _) = run(Live::start(o).unwrap(), Duration::from_secs(30), |r, _| {
        r.len() == n
    });
    server.done();
    assert_eq!(reports.len(), n);
    assert!(reports.iter().all(|r| r.taught == Ok(true)));

    // `fit --from` once per grasp of the recording, on a session of that grasp.
    let recorded = session::load(&out).unwrap();
    let out_rec = out.clone();
    let mut chained = file;
    for g in &recorded.grasps {
        let one = Session {
            grasps: vec![g.clone()],
            ..recorded.clone()
        };
        let models::Model::Sequences(m) = &chained.model else {
            panic!("a sequence model")
        };
        let (next, secs) = models::continue_sequences(m, &one).unwrap();
        chained = models::sequence_file(
            next,
            &one,
            secs,
            chained.provenance.size_reason,
            Some(&chained.provenance),
        );
    }
    let live = models::load(&live_path).unwrap();
    assert_eq!(live.model, chained.model);

    // `fit ds RECORDING --from MODEL --in-order` teaches the same chain; the default
    // `--from` (the protocol's seeded shuffle) teaches another order, another model.
    let start = dir.join("start.json");
    models::save(&file_at_start, &start).unwrap();
    let fit = |extra: &[&str], out: &Path| {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .arg("fit")
            .arg("ds")
            .arg(&out_rec)
            .arg("--from")
            .arg(&start)
            .args(extra)
            .arg("-o")
            .arg(out)
            .stdout(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(status.success());
        models::load(out).unwrap()
    };
    let in_order = fit(&["--in-order"], &dir.join("in-order.json"));
    assert_eq!(in_order.model, live.model);
    // The provenance too, but for its times and the hashes of the one-grasp sessions it
    // names: a stream's grasp lists only its own object in its label set, the
    // recording's grasp every object recorded.
    let times = |f: &models::ModelFile| {
        let mut p = f.provenance.clone();
        p.trained_at.clear();
        p.train_seconds = 0.0;
        p.session.hash.clear();
        for (_, v) in &mut p.parameters {
            if let Some(at) = v.find(" [sha256:") {
                v.truncate(at);
            }
        }
        p
    };
    assert_eq!(
        times(&in_order),
        times(&live),
        "provenance but times and hashes"
    );
    let shuffled = fit(&[], &dir.join("shuffled.json"));
    assert_ne!(shuffled.model, live.model);
}

/// DS and GS follow a grasp while it is open, one step per frame; when it ends, those
/// steps are the grasp's verdict (the models' own prediction of the whole grasp).
#[test]
fn early_classification_step_by_step_equals_the_grasps_verdict() {
    let dir = common::temp_dir("live-early");
    let s = sample(36);
    let (train, shown) = {
        let (mut a, mut b) = (s.clone(), s.clone());
        a.grasps.truncate(30);
        b.grasps.drain(..30);
        (a, b)
    };
    let spec = spec_of(&shown, &dir);
    for method in [MethodId::Ds, MethodId::Gs] {
        let defaults = RecognitionParams::default();
        let (mut ds, mut gs) = (defaults.ds, defaults.gs);
        ds.gp.capacity = 20;
        gs.gp.capacity = 20;
        let opts = SequenceFitOptions {
            method,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            seed: 1,
            ds,
            gs,
        };
        let (model, secs) = models::fit_sequences(&train, &opts).unwrap();
        let file = models::sequence_file(model, &train, secs, Default::default(), None);
        let path = dir.join(format!("{}.json", method.key()));
        models::save(&file, &path).unwrap();
        let n = shown.grasps.len();
        let server = play(&shown, rate_for(&shown, 1.5), 0, 0..n);
        let mut o = options(server.port, spec.clone(), None);
        o.model = Some((path.clone(), false));
        let (reports, snap) = run(Live::start(o).unwrap(), Duration::from_secs(30), |r, _| {
            r.len() == n
        });
        server.done();
        assert_eq!(reports.len(), n, "{snap:?}");
        assert_eq!(snap.early_error, None);
        // The live verdict is the steps followed while the grasp was open; the models' own
        // prediction of the recorded grasp must give the same bits.
        let offline = LiveModel::load(&path, false).unwrap();
        for (i, r) in reports.iter().enumerate() {
            let early = r.early.as_ref().expect("the model followed the grasp");
            let v = &offline.verdict(r.session.as_ref().unwrap()).unwrap();
            assert_eq!(r.verdict.as_ref().unwrap().as_ref().unwrap(), v);
            let bits = |steps: &[Vec<f64>]| -> Vec<Vec<u64>> {
                steps
                    .iter()
                    .map(|row| row.iter().map(|x| x.to_bits()).collect())
                    .collect()
            };
            assert_eq!(bits(&early.steps), bits(&v.steps), "{method:?} grasp {i}");
            assert_eq!(
                (&early.predicted, early.settled),
                (&v.predicted, v.settled),
                "{method:?} grasp {i}"
            );
        }
        // The line printed per grasp says the early decisions.
        assert!(
            reports[0].line().contains("early 10%:"),
            "{}",
            reports[0].line()
        );
    }
}

/// DU and GU (the mean and the joint novelty) follow a grasp while it is open: the cluster
/// and the novelty of the grasp so far, one step per frame; every step they give equals the
/// offline assessment of that prefix (the verdict's steps, from the recorded grasp), and
/// the last step's novelty is the grasp's end-of-grasp novelty, bit for bit.
#[test]
fn du_and_gu_novelty_step_by_step_equals_the_grasps_verdict() {
    use tactile_workbench::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use tactile_workbench::learners::GuAggregate;
    use tactile_workbench::models::ClusterFitOptions;
    let dir = common::temp_dir("live-novelty");
    let s = sample(36);
    let (train, shown) = {
        let (mut a, mut b) = (s.clone(), s.clone());
        a.grasps.truncate(30);
        b.grasps.drain(..30);
        (a, b)
    };
    let spec = spec_of(&shown, &dir);
    for (method, aggregate) in [
        (MethodId::Du, GuAggregate::Mean),
        (MethodId::Gu, GuAggregate::Mean),
        (MethodId::Gu, GuAggregate::Joint),
    ] {
        let learner = match method {
            MethodId::Du => UnsupervisedLearner::Du,
            _ => UnsupervisedLearner::Gu,
        };
        let mut params = ClusteringParams::for_learner(learner);
        params.ds.gp.capacity = 20;
        params.gs.gp.capacity = 20;
        params.gu_aggregate = aggregate;
        let opts = ClusterFitOptions {
            method,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            threshold: if method == MethodId::Du { 0.4 } else { 0.1 },
            seed: 1,
            params,
        };
        let case = format!("{method:?} {aggregate:?}");
        let (model, _) = models::fit_clusters(&train, &opts).unwrap();
        let file = models::cluster_file(model, &train, 0.0, None);
        let path = dir.join(format!("{}-{aggregate:?}.json", method.key()));
        models::save(&file, &path).unwrap();
        let n = shown.grasps.len();
        let server = play(&shown, rate_for(&shown, 1.5), 0, 0..n);
        let mut o = options(server.port, spec.clone(), None);
        o.model = Some((path.clone(), false));
        let (reports, snap) = run(Live::start(o).unwrap(), Duration::from_secs(30), |r, _| {
            r.len() == n
        });
        server.done();
        assert_eq!(reports.len(), n, "{case}: {snap:?}");
        assert_eq!(snap.early_error, None, "{case}");
        let offline = LiveModel::load(&path, false).unwrap();
        for (i, r) in reports.iter().enumerate() {
            let early = r.early.as_ref().expect("the model followed the grasp");
            let v = r.verdict.as_ref().unwrap().as_ref().unwrap();
            // (Debug: exact for floats, and NaN, the decision of a clustering, is equal there.)
            let again = offline.verdict(r.session.as_ref().unwrap()).unwrap();
            assert_eq!(format!("{v:?}"), format!("{again:?}"), "{case} grasp {i}");
            // The verdict's last step is the whole grasp's assessment.
            let (novelty, threshold) = v.novelty.expect("a DU/GU novelty");
            assert_eq!(threshold, opts.threshold);
            let last = v.novelty_steps.last().expect("steps");
            assert_eq!(last.step + 1, r.frames, "{case} grasp {i}");
            assert_eq!(
                last.novelty.to_bits(),
                novelty.to_bits(),
                "{case} grasp {i}"
            );
            // Live, step by step: every step followed is the verdict's at that step.
            assert!(!early.novelty_steps.is_empty(), "{case} grasp {i}");
            if aggregate == GuAggregate::Mean {
                assert_eq!(early.novelty_steps.len(), r.frames, "{case} grasp {i}");
            }
            for e in &early.novelty_steps {
                let at = v.novelty_steps.iter().find(|s| s.step == e.step);
                let at = at.expect("the verdict has every step live has");
                assert_eq!(
                    (e.cluster, e.novelty.to_bits()),
                    (at.cluster, at.novelty.to_bits()),
                    "{case} grasp {i} step {}",
                    e.step
                );
            }
            let live_last = early.novelty_steps.last().unwrap();
            if live_last.step + 1 == r.frames {
                assert_eq!(live_last.novelty.to_bits(), novelty.to_bits(), "{case}");
            }
        }
        assert!(
            reports[0].line().contains("novelty by step 10%:cluster"),
            "{}",
            reports[0].line()
        );
    }
}

/// Run `live --record` on `n` grasps of the sample, kill -9 it once it printed `printed`
/// grasps, and check the recording: every completed grasp, validated, equal to the served.
fn kill_9_after(n: usize, seconds: f64, printed: usize) {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let dir = common::temp_dir(&format!("live-kill-{n}"));
    let s = sample(n);
    spec_of(&s, &dir);
    let server = play(&s, rate_for(&s, seconds), 0, 0..s.grasps.len());
    let out = dir.join("rec.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args(["live", &format!("ws://127.0.0.1:{}", server.port), "--spec"])
        .arg(dir.join("spec.json"))
        .arg("--record")
        .arg(&out)
        .arg("--duration")
        .arg("60")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let mut seen = 0;
    while seen < printed {
        let line = lines.next().unwrap().unwrap();
        seen += usize::from(line.starts_with("grasp "));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    server.done();
    let recorded = session::load(&out).unwrap();
    assert!(recorded.grasps.len() >= printed);
    let mut served = s.clone();
    served.grasps.truncate(recorded.grasps.len());
    assert_same_grasps(&recorded, &served);
    // Loading finished the killed recording: a plain session file now.
    assert!(!session::journal::journal_path(&out).exists());
}

#[test]
fn kill_9_of_live_leaves_a_valid_recording_of_every_completed_grasp() {
    kill_9_after(12, 4.0, 3);
}

/// Many grasps, each appended to the journal as it ends: killed after 60 of 80.
#[test]
fn kill_9_after_many_grasps_keeps_every_completed_one() {
    kill_9_after(80, 8.0, 60);
}

/// A hand-made server that offers only the old subprotocol, advertises `/a` (and `/ev`),
/// and sends `frames` once the client subscribed.
fn old_server(frames: Vec<Vec<u8>>) -> (u16, std::thread::JoinHandle<Vec<String>>) {
    use tungstenite::Message;
    use tungstenite::handshake::server::{Request, Response};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let thread = std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        let offered = Arc::new(std::sync::Mutex::new(Vec::new()));
        let seen = offered.clone();
        // The handshake's error response is tungstenite's type, large by design.
        #[allow(clippy::result_large_err)]
        let answer = move |req: &Request, mut res: Response| {
            for v in req.headers().get_all("sec-websocket-protocol") {
                seen.lock()
                    .unwrap()
                    .extend(v.to_str().unwrap().split(',').map(|p| p.trim().to_string()));
            }
            res.headers_mut().insert(
                "sec-websocket-protocol",
                "foxglove.websocket.v1".parse().unwrap(),
            );
            Ok(res)
        };
        let mut ws = tungstenite::accept_hdr(stream, answer).unwrap();
        let channel = |id: u64, topic: &str, name: &str, schema: &str| {
            serde_json::json!({"id": id, "topic": topic, "encoding": "cdr", "schemaName": name,
                               "schemaEncoding": "ros2msg", "schema": schema})
        };
        ws.send(Message::text(
            r#"{"op":"serverInfo","name":"old","capabilities":[]}"#,
        ))
        .unwrap();
        let adv = serde_json::json!({"op": "advertise", "channels": [
            channel(10, "/a", "std_msgs/msg/Float64MultiArray", publish::FLOAT64_MULTIARRAY),
            channel(11, "/ev", "std_msgs/msg/String", publish::STRING),
            channel(12, "/b", "std_msgs/msg/String", publish::STRING),
        ]});
        ws.send(Message::text(adv.to_string())).unwrap();
        let sub: serde_json::Value = loop {
            if let Message::Text(t) = ws.read().unwrap() {
                break serde_json::from_str(t.as_str()).unwrap();
            }
        };
        let id_of = |channel: u64| {
            sub["subscriptions"]
                .as_array()
                .unwrap()
                .iter()
                .find(|s| s["channelId"] == channel)
                .map(|s| s["id"].as_u64().unwrap() as u32)
                .unwrap()
        };
        let (a, ev) = (id_of(10), id_of(11));
        ws.send(Message::text("{not json")).unwrap();
        for (k, payload) in frames.into_iter().enumerate() {
            // Frames tagged 0xEE are events; 0xFF are sent as raw binary.
            let (sub, body) = match payload.split_first() {
                Some((0xEE, rest)) => (ev, rest.to_vec()),
                Some((0xFF, rest)) => {
                    ws.send(Message::binary(rest.to_vec())).unwrap();
                    continue;
                }
                _ => (a, payload),
            };
            let mut m = vec![1u8];
            m.extend(sub.to_le_bytes());
            m.extend((1_000_000_000 + k as u64 * 10_000_000).to_le_bytes());
            m.extend(body);
            ws.send(Message::binary(m)).unwrap();
        }
        // Hold the connection until the client goes.
        while ws.read().is_ok() {}
        offered.lock().unwrap().clone()
    });
    (port, thread)
}

#[test]
fn an_old_server_and_malformed_messages_are_counted_without_panic() {
    let dir = common::temp_dir("live-old");
    let spec_path = dir.join("spec.json");
    std::fs::write(
        &spec_path,
        r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x3", "unit": "kPa"}],
            "grasps": {"events": "/ev"}}"#,
    )
    .unwrap();
    let spec = ImportSpec::load(&spec_path).unwrap();
    let event = |text: &str| {
        let mut v = vec![0xEE];
        v.extend(publish::string(text));
        v
    };
    let good = || publish::multiarray(&[1.0, 2.0, 3.0]);
    let mut truncated = good();
    truncated.truncate(truncated.len() - 3);
    let mut random = vec![0xFF];
    random.extend((0..64u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    let frames = vec![
        event("start:mug"),
        good(),
        truncated,                        // malformed: truncated CDR
        publish::multiarray(&[1.0, 2.0]), // malformed: wrong length
        vec![0xFF, 1, 2],                 // malformed: too short for message data
        random,                           // random bytes: opcode 0, passed over
        vec![0xFF, 9, 9, 9],              // an unknown opcode, passed over
        event("end:"),
        good(),
        event("nonsense"), // a refused event
    ];
    let (port, server) = old_server(frames);
    let o = options(port, spec, None);
    let mut subprotocol = None;
    let (reports, snap) = run(
        Live::start(o).unwrap(),
        Duration::from_secs(10),
        |r, snap| {
            if let State::Connected { subprotocol: p, .. } = &snap.status.state {
                subprotocol = Some(p.clone());
            }
            r.len() == 1 && snap.refused_events == 1
        },
    );
    let offered = server.join().unwrap();
    assert_eq!(offered, ["foxglove.sdk.v1", "foxglove.websocket.v1"]);
    assert_eq!(subprotocol.as_deref(), Some("foxglove.websocket.v1"));
    assert_eq!(reports.len(), 1);
    assert_eq!(reports[0].frames, 1);
    // Bad JSON, truncated CDR, the wrong length, the short frame.
    assert_eq!(snap.status.malformed, 4, "{:?}", snap.status);
    // Decoded: start, a frame, end, a frame after the grasp, the refused event.
    assert_eq!(snap.status.messages, 5);
    assert_eq!(snap.refused_events, 1);
}
