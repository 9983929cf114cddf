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

use channels::Plan;
use client::{Client, ClientStatus, lock};
use cut::{Completed, Cutter, Cutting};
use frames::{Assembled, Assembler, StreamFrame};
use model::{LiveModel, Verdict};
use record::{Recorder, grasp_session};

use crate::session::spec::{GraspCut, ImportSpec};
use crate::session::{Session, SessionError};

/// Frames the trace keeps at most, whatever its span: a bound on memory at any rate.
pub const TRACE_CAP: usize = 20_000;

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
    pub verdict: Option<Result<Verdict, String>>,
    /// Whether the grasp taught the model (and the file was saved), or why not.
    pub taught: Result<bool, String>,
    /// Whether the grasp is in the recording, or why not.
    pub recorded: Result<bool, String>,
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
            Some(Ok(v)) => out += &format!("; {}", v.line()),
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
    pub last_refused: Option<String>,
    pub last_verdict: Option<Verdict>,
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
            Some((path, teach)) => Some(
                LiveModel::load(path, *teach)
                    .map_err(|e| SessionError::file(path, e.to_string()))?,
            ),
            None => None,
        };
        Ok(Live {
            assembler: Assembler::new(&plan, opts.spec.sync_tolerance_ns),
            cutter: Cutter::new(&opts.spec, cutting),
            client: Client::start(&opts.url, plan),
            source: PathBuf::from(&opts.url),
            recorder: opts.record.as_deref().map(Recorder::new),
            spec: opts.spec,
            model,
            snapshot: Arc::new(Mutex::new(Snapshot::default())),
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
    pub fn by_hand(&mut self, text: &str) -> Result<Option<GraspReport>, String> {
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
        self.publish();
        let snap = lock(&self.snapshot).clone();
        (out, snap)
    }

    fn incoming(&mut self, m: client::Incoming, out: &mut Vec<GraspReport>) {
        match self.assembler.push(m.t, m.sample) {
            Assembled::Frame(f) => {
                self.trace(&f);
                if let Some(c) = self.cutter.frame(f) {
                    out.push(self.completed(c));
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
        view.latest = Some(f.clone());
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

    /// A grasp that ended: a session of one grasp, recorded, read by the model, taught.
    fn completed(&mut self, c: Completed) -> GraspReport {
        self.grasps += 1;
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
            taught: Ok(false),
            recorded: Ok(false),
            session: None,
        };
        let one = match grasp_session(&self.spec, Path::new(&self.source), c.grasp) {
            Ok(s) => s,
            Err(e) => {
                report.recorded = Err(e.to_string());
                return report;
            }
        };
        if let Some(r) = &mut self.recorder {
            report.recorded = r.append(&one).map(|()| true).map_err(|e| e.to_string());
            lock(&self.snapshot).recorded = r.grasps();
        }
        if let Some(m) = &mut self.model {
            let verdict = m.verdict(&one).map_err(|e| e.to_string());
            lock(&self.snapshot).last_verdict = verdict.as_ref().ok().cloned();
            report.verdict = Some(verdict);
            if c.labelled {
                report.taught = m.teach(&one).map_err(|e| e.to_string());
            }
        }
        report.session = Some(one);
        report
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

fn now_ns() -> Option<u64> {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .ok()
        .map(|d| d.as_nanos() as u64)
}
