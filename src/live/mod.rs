//! Live touch: a robot's stream over the Foxglove WebSocket protocol, cut into grasps,
//! recorded, and read by a saved model as it arrives. Engine layer: no egui; the window
//! reads a [`Snapshot`], as every view reads its data.
//!
//! - [`protocol`]: the wire format (JSON ops, binary message data);
//! - [`channels`]: which advertised channels the import spec reads, their messages decoded
//!   by the bag importer's CDR reader (or JSON);
//! - [`client`]: the socket thread, its bounded queue, reconnect and status;
//! - [`frames`]: samples into frames on the reference topic;
//! - [`cut`]: grasps by events, by contact or by hand;
//! - [`discover`]: a stream without a spec: its channels, and a spec proposed from them;
//! - [`record`]: each completed grasp into a session file that is always valid;
//! - [`model`]: a saved model's verdict on each grasp, and teaching it;
//! - [`publish`]: a session as the messages of a stream (what `serve` publishes).
//!
//! A grasp cut from a stream becomes a session of one grasp through the bag importer's
//! `assemble`; the recording, the model and the CLI all read that session, so a grasp
//! seen live and the same grasp read back from the recording give the same numbers.

pub mod channels;
pub mod client;
pub mod cut;
pub mod discover;
mod error;
pub mod frames;
pub mod model;
pub mod protocol;
pub mod publish;
pub mod record;
#[cfg(feature = "serve")]
pub mod serve;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub use error::LiveError;

use channels::Plan;
use client::{Client, ClientStatus, lock};
use cut::{Completed, Cutter, Cutting};
use frames::{Assembled, Assembler, StreamFrame};
use model::{Early, LiveModel, Verdict};
use record::{Recorder, grasp_session};

use crate::session::spec::{GraspCut, ImportSpec};
use crate::session::{Session, SessionError};

/// Frames the trace keeps at most, whatever its span: a bound on memory at any rate.
pub const TRACE_CAP: usize = 20_000;
/// Lines of completed grasps the snapshot keeps.
pub const RECENT_CAP: usize = 200;

/// What to read, and what to do with the grasps.
pub struct LiveOptions {
    pub url: String,
    pub spec: ImportSpec,
    /// Cut by hand even when the spec names an events topic (default: events when the spec
    /// has them, else contact).
    pub by_hand: bool,
    /// A model file, and whether labelled grasps teach it (it is then saved after each).
    pub model: Option<(PathBuf, bool)>,
    pub record: Option<PathBuf>,
    /// The span of the trace the snapshot keeps (s).
    pub trace_seconds: f64,
}

/// One completed grasp, as the engine dealt with it.
#[derive(Clone, Debug)]
pub struct GraspReport {
    /// Its number in the stream, from 1.
    pub number: usize,
    pub object: String,
    /// Its labels by label set (the recorded sets), as names.
    pub labels: Vec<(String, String)>,
    pub labelled: bool,
    pub frames: usize,
    pub seconds: f64,
    /// The model's verdict, or why it could not give one.
    pub verdict: Option<Result<Verdict, LiveError>>,
    /// DS/GS's early classification as the grasp went on, frame by frame.
    pub early: Option<Verdict>,
    /// Whether the grasp taught the model (and the file was saved), or why not.
    pub taught: Result<bool, LiveError>,
    /// Whether the grasp is in the recording, or why not.
    pub recorded: Result<bool, LiveError>,
    /// The grasp as a session of one grasp (what the model read and the recording holds).
    pub session: Option<Session>,
}

impl GraspReport {
    /// One line for the CLI.
    pub fn line(&self) -> String {
        let mut out = format!(
            "grasp {}: {}{}, {} frames, {:.2} s",
            self.number,
            self.object,
            self.labels
                .iter()
                .map(|(s, c)| format!(" {s}={c}"))
                .collect::<String>(),
            self.frames,
            self.seconds
        );
        match &self.verdict {
            Some(Ok(v)) => {
                out += &format!("; {}", v.line());
                if let Some(e) = v.early_line() {
                    out += &format!("; {e}");
                }
            }
            Some(Err(e)) => out += &format!("; model: {e}"),
            None => {}
        }
        match &self.taught {
            Ok(true) => out += "; taught",
            Ok(false) => {}
            Err(e) => out += &format!("; not taught: {e}"),
        }
        if let Err(e) = &self.recorded {
            out += &format!("; NOT RECORDED: {e}");
        }
        out
    }
}

/// What a view reads: the latest frame, a bounded trace, the connection's status and the
/// model's latest verdict.
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    pub status: ClientStatus,
    pub latest: Option<StreamFrame>,
    /// (log time ns, total pressure per sensor) of the frames of the last `trace_seconds`.
    pub trace: VecDeque<(u64, Vec<f64>)>,
    /// Messages per second over the last second, and the latest frame's latency (ms) from
    /// its log time to its arrival in the engine (the server's clock against ours).
    pub rate_hz: f64,
    pub latency_ms: Option<f64>,
    /// Frames of the grasp in progress (0 when idle), grasps completed and recorded.
    pub in_progress: usize,
    pub grasps: usize,
    pub recorded: usize,
    /// Reference messages that made no frame, contacts too short to be grasps, and events
    /// refused (with the latest reason).
    pub left_out: u64,
    pub taps: u64,
    pub refused_events: u64,
    pub last_refused: Option<LiveError>,
    pub last_verdict: Option<Verdict>,
    /// DS/GS on the grasp still open: the distribution at every step so far.
    pub open_verdict: Option<Verdict>,
    /// Why the model could not follow the open grasp.
    pub early_error: Option<LiveError>,
    /// The latest completed grasps' lines, oldest first.
    pub recent: VecDeque<String>,
    /// From a frame's log time to the model's step on it (DS/GS following an open grasp).
    pub model_latency: Latencies,
    /// How grasps are cut, in words.
    pub cutting: String,
    /// Why the stream could not start (a [`Running`] engine) or its recording could not be
    /// finished, and why the latest command by hand was refused.
    pub failed: Option<String>,
    pub last_command: Option<String>,
}

/// The engine of a live stream: the socket thread's queue drained into frames, grasps, the
/// recording and the model.
pub struct Live {
    client: Client,
    source: PathBuf,
    spec: ImportSpec,
    assembler: Assembler,
    cutter: Cutter,
    recorder: Option<Recorder>,
    model: Option<LiveModel>,
    /// The model at work on the open grasp (None when idle, or the model has no early
    /// classification).
    early: Option<Early>,
    early_failed: bool,
    /// Written in place, a short lock at a time: the trace is never copied.
    snapshot: Arc<Mutex<Snapshot>>,
    trace_ns: u64,
    grasps: usize,
    /// Messages counted at the start of the current rate window.
    rate_window: (Instant, u64),
}

impl Live {
    pub fn start(opts: LiveOptions) -> Result<Live, SessionError> {
        let plan = Plan::of(&opts.spec)?;
        let cutting = match (&opts.spec.cut, opts.by_hand) {
            (_, true) => Cutting::Hand,
            (Some(GraspCut::Events(_)), false) => Cutting::Events,
            _ => Cutting::Contact(opts.spec.live.contact.clone()),
        };
        let model = match &opts.model {
            Some((path, teach)) => {
                Some(LiveModel::load(path, *teach).map_err(|e| SessionError::caused(path, e))?)
            }
            None => None,
        };
        // Before the socket: a recording that cannot start stops the stream from starting.
        let recorder = opts.record.as_deref().map(Recorder::new).transpose()?;
        Ok(Live {
            assembler: Assembler::new(&plan, opts.spec.sync_tolerance_ns),
            cutter: Cutter::new(&opts.spec, cutting.clone()),
            client: Client::start(&opts.url, plan),
            source: PathBuf::from(&opts.url),
            recorder,
            spec: opts.spec,
            model,
            early: None,
            early_failed: false,
            snapshot: Arc::new(Mutex::new(Snapshot {
                cutting: match &cutting {
                    Cutting::Events => "by the stream's events".into(),
                    Cutting::Contact(_) => "by contact".into(),
                    Cutting::Hand => "by hand".into(),
                },
                ..Snapshot::default()
            })),
            trace_ns: (opts.trace_seconds.max(0.0) * 1e9) as u64,
            grasps: 0,
            rate_window: (Instant::now(), 0),
        })
    }

    /// The snapshot a view reads (updated after each [`Live::step`]).
    pub fn snapshot(&self) -> Arc<Mutex<Snapshot>> {
        self.snapshot.clone()
    }

    pub fn cutting(&self) -> &Cutting {
        self.cutter.cutting()
    }

    /// Wait up to `wait` for messages, take what has arrived, and return the grasps that
    /// ended.
    pub fn step(&mut self, wait: Duration) -> Vec<GraspReport> {
        let mut out = Vec::new();
        if let Ok(first) = self.client.queue.recv_timeout(wait) {
            self.incoming(first, &mut out);
            // A bounded batch, so that the snapshot is refreshed under any load.
            for _ in 0..client::QUEUE {
                match self.client.queue.try_recv() {
                    Ok(m) => self.incoming(m, &mut out),
                    Err(_) => break,
                }
            }
        }
        self.publish();
        out
    }

    /// A command by hand: `start:OBJECT`, `key`, `end:LABELS`, or under contact cutting
    /// `label:OBJECT[:LABELS]` for the next grasp.
    pub fn by_hand(&mut self, text: &str) -> Result<Option<GraspReport>, LiveError> {
        let done = self.cutter.by_hand(text)?;
        Ok(done.map(|c| self.completed(c)))
    }

    /// Stop the socket thread and deal with every message it had queued: the recording
    /// then holds every grasp that ended.
    pub fn finish(mut self) -> (Vec<GraspReport>, Snapshot) {
        self.client.stop();
        let mut out = Vec::new();
        while let Ok(m) = self.client.queue.try_recv() {
            self.incoming(m, &mut out);
        }
        if let Some(r) = &mut self.recorder
            && let Err(e) = r.finish()
        {
            lock(&self.snapshot).failed = Some(format!("finishing the recording: {e}"));
        }
        self.publish();
        let snap = lock(&self.snapshot).clone();
        (out, snap)
    }

    fn incoming(&mut self, m: client::Incoming, out: &mut Vec<GraspReport>) {
        match self.assembler.push(m.t, m.sample) {
            Assembled::Frame(f) => {
                self.trace(&f);
                let t = f.t;
                match self.cutter.frame(f) {
                    Some(c) => out.push(self.completed(c)),
                    None => self.follow_open(t),
                }
            }
            Assembled::Event(t, text) => match self.cutter.event(t, &text) {
                Ok(Some(c)) => out.push(self.completed(c)),
                Ok(None) => {}
                Err(why) => {
                    let mut view = lock(&self.snapshot);
                    view.refused_events += 1;
                    view.last_refused = Some(why);
                }
            },
            Assembled::Nothing => {}
        }
    }

    /// The frame into the snapshot: latest, latency, and the trace of the last seconds.
    fn trace(&self, f: &StreamFrame) {
        let totals = f.taxels.iter().map(|v| v.iter().sum()).collect();
        let mut view = lock(&self.snapshot);
        view.latency_ms = now_ns().map(|now| (now as f64 - f.t as f64) / 1e6);
        // Into the latest frame's own buffers: no allocation per frame.
        match &mut view.latest {
            Some(latest) => {
                latest.t = f.t;
                latest.taxels.clone_from(&f.taxels);
                latest.encoders.clone_from(&f.encoders);
            }
            None => view.latest = Some(f.clone()),
        }
        let trace = &mut view.trace;
        trace.push_back((f.t, totals));
        while trace.len() > TRACE_CAP
            || trace
                .front()
                .is_some_and(|(t0, _)| f.t.saturating_sub(*t0) > self.trace_ns)
        {
            trace.pop_front();
        }
    }

    /// The model on the open grasp's new frames (the latest at log time `t`); the new
    /// steps into the snapshot.
    fn follow_open(&mut self, t: u64) {
        let (Some(model), Some(frames)) = (&self.model, self.cutter.in_progress()) else {
            return;
        };
        if self.early_failed {
            return;
        }
        if self.early.is_none() {
            self.early = model.early();
            let mut view = lock(&self.snapshot);
            view.open_verdict = None;
            view.early_error = None;
        }
        let Some(early) = &mut self.early else { return };
        let outcome = early.update(&self.spec, frames);
        let mut view = lock(&self.snapshot);
        match outcome {
            Ok(()) => {
                let v = &early.verdict;
                let shown = view.open_verdict.get_or_insert_with(|| Verdict {
                    steps: Vec::new(),
                    novelty_steps: Vec::new(),
                    ..v.clone()
                });
                let have = shown.steps.len().min(v.steps.len());
                shown.steps.extend_from_slice(&v.steps[have..]);
                let have = shown.novelty_steps.len().min(v.novelty_steps.len());
                shown
                    .novelty_steps
                    .extend_from_slice(&v.novelty_steps[have..]);
                shown.novelty = v.novelty;
                shown.predicted.clone_from(&v.predicted);
                shown.decision = v.decision;
                shown.settled = v.settled;
                if let Some(now) = now_ns() {
                    view.model_latency.add((now as f64 - t as f64) / 1e6);
                }
            }
            Err(e) => {
                // Said once per grasp: the model is not asked again until it ends.
                view.early_error = Some(e.into());
                view.open_verdict = None;
                self.early_failed = true;
            }
        }
    }

    /// A grasp that ended: a session of one grasp, recorded, read by the model, taught.
    fn completed(&mut self, c: Completed) -> GraspReport {
        self.grasps += 1;
        let early = self.early.take().map(|e| e.verdict);
        self.early_failed = false;
        lock(&self.snapshot).open_verdict = None;
        let sets = self.spec.recorded_label_sets();
        let labels = sets
            .iter()
            .zip(&c.grasp.classes)
            .map(|(s, &k)| {
                (
                    s.name.clone(),
                    s.classes.get(k).cloned().unwrap_or_default(),
                )
            })
            .collect();
        let mut report = GraspReport {
            number: self.grasps,
            object: c.grasp.object.clone(),
            labels,
            labelled: c.labelled,
            frames: c.grasp.frames.len(),
            seconds: (c.end - c.start) as f64 / 1e9,
            verdict: None,
            early,
            taught: Ok(false),
            recorded: Ok(false),
            session: None,
        };
        let one = match grasp_session(&self.spec, Path::new(&self.source), c.grasp) {
            Ok(s) => s,
            Err(e) => {
                report.recorded = Err(e.into());
                self.remember(&report);
                return report;
            }
        };
        if let Some(r) = &mut self.recorder {
            report.recorded = r.append(&one).map(|()| true).map_err(LiveError::from);
            lock(&self.snapshot).recorded = r.grasps();
        }
        if let Some(m) = &mut self.model {
            // DS/GS followed the whole grasp step by step: those steps are its verdict (the
            // models' own prediction of the grasp gives the same bits, tested), so the
            // grasp is not predicted again, which would stall the stream at every grasp's
            // end for as long as the grasp's steps took.
            let followed = report
                .early
                .as_ref()
                .filter(|e| e.steps.len() == report.frames);
            let verdict = match followed {
                Some(e) => Ok(e.clone()),
                None => m.verdict(&one).map_err(LiveError::from),
            };
            lock(&self.snapshot).last_verdict = verdict.as_ref().ok().cloned();
            report.verdict = Some(verdict);
            if c.labelled {
                report.taught = m.teach(&one).map_err(LiveError::from);
            }
        }
        report.session = Some(one);
        self.remember(&report);
        report
    }

    /// The grasp's line into the snapshot's bounded list.
    fn remember(&self, report: &GraspReport) {
        let mut view = lock(&self.snapshot);
        if view.recent.len() == RECENT_CAP {
            view.recent.pop_front();
        }
        view.recent.push_back(report.line());
    }

    /// The counters into the snapshot.
    fn publish(&mut self) {
        let status = self.client.status();
        let (since, count) = self.rate_window;
        let elapsed = since.elapsed().as_secs_f64();
        let mut view = lock(&self.snapshot);
        if elapsed >= 1.0 {
            view.rate_hz = status.messages.saturating_sub(count) as f64 / elapsed;
            self.rate_window = (Instant::now(), status.messages);
        }
        view.status = status;
        view.in_progress = self.cutter.in_progress().map_or(0, <[_]>::len);
        view.grasps = self.grasps;
        view.left_out = self.assembler.left_out;
        view.taps = self.cutter.taps;
    }
}

/// Latencies (ms) counted in 0.1 ms bins up to 2 s (the last bin holds the longer ones):
/// percentiles over a stream of any length in a fixed space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Latencies {
    bins: Vec<u64>,
    count: u64,
}

impl Latencies {
    const BIN_MS: f64 = 0.1;
    const BINS: usize = 20_001;

    pub fn add(&mut self, ms: f64) {
        if self.bins.is_empty() {
            self.bins = vec![0; Self::BINS];
        }
        let k = ((ms.max(0.0) / Self::BIN_MS) as usize).min(Self::BINS - 1);
        self.bins[k] += 1;
        self.count += 1;
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    /// The `q` quantile (0–1), as its bin's upper edge; None before any latency.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let want = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (k, n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= want {
                return Some((k + 1) as f64 * Self::BIN_MS);
            }
        }
        None
    }
}

fn now_ns() -> Option<u64> {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .ok()
        .map(|d| d.as_nanos() as u64)
}

/// A live stream run on a thread of its own, for a window: it never blocks its caller.
/// Commands by hand go through a bounded queue; what happens is read from the snapshot.
pub struct Running {
    pub snapshot: Arc<Mutex<Snapshot>>,
    commands: std::sync::mpsc::SyncSender<String>,
    stop: Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// Commands by hand queued at most (a person cannot type faster than the engine reads).
const COMMANDS: usize = 64;

impl Running {
    /// Start the engine on its thread: the spec and model are read there, and a failure to
    /// start is the snapshot's `failed`.
    pub fn start(opts: LiveOptions) -> Running {
        let snapshot = Arc::new(Mutex::new(Snapshot::default()));
        let (commands, rx) = std::sync::mpsc::sync_channel::<String>(COMMANDS);
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let thread = {
            let (snapshot, stop) = (snapshot.clone(), stop.clone());
            std::thread::Builder::new()
                .name("live-engine".into())
                .spawn(move || {
                    let mut live = match Live::start(opts) {
                        Ok(l) => l,
                        Err(e) => {
                            lock(&snapshot).failed = Some(e.to_string());
                            return;
                        }
                    };
                    // The engine writes into the snapshot the caller holds.
                    let first = lock(&live.snapshot).clone();
                    *lock(&snapshot) = first;
                    live.snapshot = snapshot;
                    let stopping = || stop.load(std::sync::atomic::Ordering::Relaxed);
                    while !stopping() {
                        live.step(Duration::from_millis(20));
                        while let Ok(text) = rx.try_recv() {
                            if let Err(e) = live.by_hand(&text) {
                                lock(&live.snapshot).last_command = Some(format!("`{text}`: {e}"));
                            }
                        }
                    }
                    live.finish();
                })
                .ok()
        };
        Running {
            snapshot,
            commands,
            stop,
            thread,
        }
    }

    /// A command by hand (see [`Live::by_hand`]); false when the queue is full.
    pub fn command(&self, text: &str) -> bool {
        self.commands.try_send(text.to_string()).is_ok()
    }

    /// Ask the engine to stop, without waiting: it deals with the messages already
    /// received, completes the recording, and its status turns to stopped.
    pub fn stop(&self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether the engine's thread has ended (stopped, or failed to start).
    pub fn ended(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }

    /// Stop and wait until the recording is complete.
    pub fn join(mut self) {
        self.stop();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Running {
    /// The engine ends on its own (a window closing the stream does not wait for it).
    fn drop(&mut self) {
        self.stop();
    }
}
