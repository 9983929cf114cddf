//! Grasps cut from a stream as it arrives, in one of three ways:
//!
//! - **events**: the spec's events topic, with the bag importer's grammar (`start:OBJECT`,
//!   optional `key`, `end:LABELS`); a grasp holds the frames whose time lies from its start
//!   to its end, both included, and its key frame is the frame nearest the `key` time (the
//!   earlier on a tie), exactly as a bag's grasp;
//! - **contact**: the total pressure over a baseline that follows the idle hand
//!   (`ContactParams`); such a grasp is labelled by hand beforehand, else it is unlabelled;
//! - **by hand**: the same grammar as events, given by the window or the CLI at the time of
//!   the latest frame.
//!
//! A bad event (an `end` without `start`, an unknown class) is refused with its reason; the
//! grasp in progress is kept.

use crate::session::ros2::event_classes;
use crate::session::spec::{ContactParams, ImportSpec, RawGrasp};
use crate::session::{Frame, Sensor};

use super::LiveError;
use super::frames::StreamFrame;

/// The object of a contact grasp nobody labelled.
pub const UNLABELLED: &str = "unlabelled";

/// How grasps are cut.
#[derive(Clone, Debug, PartialEq)]
pub enum Cutting {
    Events,
    Contact(ContactParams),
    Hand,
}

/// A grasp that has ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Completed {
    pub grasp: RawGrasp,
    /// Log times (ns) of its start and end.
    pub start: u64,
    pub end: u64,
    /// Whether its labels were given (by an event or by hand), so that it may teach.
    pub labelled: bool,
}

/// A grasp in progress.
#[derive(Clone, Debug)]
struct Open {
    start: u64,
    object: String,
    key: Option<u64>,
    frames: Vec<Frame>,
    stamps: Vec<u64>,
}

/// The contact detector's state: the baseline and variance of the idle total pressure.
#[derive(Clone, Debug, Default)]
struct Contact {
    baseline: Option<f64>,
    variance: f64,
    last: u64,
}

pub struct Cutter {
    spec: ImportSpec,
    sensors: Vec<Sensor>,
    cutting: Cutting,
    open: Option<Open>,
    contact: Contact,
    /// A label given by hand for the next contact grasp: object and classes.
    label: Option<(String, Vec<usize>)>,
    /// The latest frame's time: hand commands happen then.
    now: Option<u64>,
    /// Contacts shorter than the minimum duration, left out.
    pub taps: u64,
}

impl Cutter {
    pub fn new(spec: &ImportSpec, cutting: Cutting) -> Cutter {
        Cutter {
            sensors: spec.sensors.iter().map(|s| s.sensor.clone()).collect(),
            spec: spec.clone(),
            cutting,
            open: None,
            contact: Contact::default(),
            label: None,
            now: None,
            taps: 0,
        }
    }

    pub fn cutting(&self) -> &Cutting {
        &self.cutting
    }

    /// The frames of the grasp in progress (none when idle).
    pub fn in_progress(&self) -> Option<&[Frame]> {
        self.open.as_ref().map(|o| o.frames.as_slice())
    }

    /// The baseline of the idle total pressure (contact cutting, once a frame was seen).
    pub fn baseline(&self) -> Option<f64> {
        self.contact.baseline
    }

    /// A frame of the stream: added to the grasp in progress; under contact cutting it may
    /// start or end one.
    pub fn frame(&mut self, f: StreamFrame) -> Option<Completed> {
        self.now = Some(self.now.map_or(f.t, |n| n.max(f.t)));
        if let Cutting::Contact(p) = &self.cutting {
            let p = p.clone();
            return self.contact_frame(f, &p);
        }
        if let Some(open) = &mut self.open
            && f.t >= open.start
        {
            push(open, f);
        }
        None
    }

    /// An event of the events topic at `t`.
    pub fn event(&mut self, t: u64, text: &str) -> Result<Option<Completed>, LiveError> {
        if self.cutting != Cutting::Events {
            return Err(LiveError::EventsUnused {
                event: text.to_string(),
                cutting: self.describe(),
            });
        }
        self.command(t, text)
    }

    /// A command by hand (`start:OBJECT`, `key`, `end:LABELS`) at the latest frame's time;
    /// under contact cutting, `label:OBJECT[:LABELS]` labels the next grasp instead.
    pub fn by_hand(&mut self, text: &str) -> Result<Option<Completed>, LiveError> {
        if let Cutting::Contact(_) = self.cutting {
            let Some(rest) = text.trim().strip_prefix("label:") else {
                return Err(LiveError::NotALabel {
                    command: text.to_string(),
                });
            };
            let (object, labels) = rest.split_once(':').unwrap_or((rest, ""));
            self.label = Some(self.labels(object.trim(), labels)?);
            return Ok(None);
        }
        let Some(t) = self.now else {
            return Err(LiveError::NoFrameYet);
        };
        self.command(t, text)
    }

    fn describe(&self) -> &'static str {
        match self.cutting {
            Cutting::Events => "the events topic",
            Cutting::Contact(_) => "contact",
            Cutting::Hand => "hand",
        }
    }

    /// The object checked and the classes of `labels` (comma-separated, one per recorded
    /// label set).
    fn labels(&self, object: &str, labels: &str) -> Result<(String, Vec<usize>), LiveError> {
        self.spec.check_object(object)?;
        let sets = self.spec.recorded_label_sets();
        let classes = event_classes(&self.spec, &sets, labels, labels)?;
        Ok((object.to_string(), classes))
    }

    /// The events grammar of the bag importer.
    fn command(&mut self, t: u64, text: &str) -> Result<Option<Completed>, LiveError> {
        let text = text.trim();
        let (word, arg) = text.split_once(':').unwrap_or((text, ""));
        match (word.trim(), &mut self.open) {
            ("start", Some(o)) => Err(LiveError::StartWhileOpen {
                open_since: o.start,
            }),
            ("start", None) => {
                let object = arg.trim();
                self.spec.check_object(object)?;
                self.open = Some(Open {
                    start: t,
                    object: object.to_string(),
                    key: None,
                    frames: Vec::new(),
                    stamps: Vec::new(),
                });
                Ok(None)
            }
            ("key", Some(o)) => {
                if o.key.is_some() {
                    return Err(LiveError::SecondKey);
                }
                o.key = Some(t);
                Ok(None)
            }
            ("end", Some(o)) => {
                let object = o.object.clone();
                let (_, classes) = self.labels(&object, arg)?;
                let Some(mut o) = self.open.take() else {
                    return Ok(None);
                };
                // Frames after the end that arrived before it (another publisher's clock).
                let keep = o.stamps.partition_point(|&s| s <= t);
                o.frames.truncate(keep);
                o.stamps.truncate(keep);
                if o.frames.is_empty() {
                    return Err(LiveError::EmptyGrasp { object: o.object });
                }
                Ok(Some(finish(o, t, classes, true)))
            }
            ("key" | "end", None) => Err(LiveError::BeforeStart {
                event: text.to_string(),
            }),
            _ => Err(LiveError::NotAnEvent {
                event: text.to_string(),
            }),
        }
    }

    fn total(&self, f: &StreamFrame) -> f64 {
        self.sensors
            .iter()
            .zip(&f.taxels)
            .map(|(s, v)| {
                v.iter()
                    .enumerate()
                    .map(|(k, &raw)| s.transform.apply(k, raw))
                    .sum::<f64>()
            })
            .sum()
    }

    fn contact_frame(&mut self, f: StreamFrame, p: &ContactParams) -> Option<Completed> {
        let total = self.total(&f);
        let t = f.t;
        let c = &mut self.contact;
        let Some(baseline) = c.baseline else {
            c.baseline = Some(total);
            c.last = t;
            return None;
        };
        let sigma = c.variance.sqrt();
        let rise = total - baseline;
        match &mut self.open {
            None => {
                if rise > (p.onset_sigma * sigma).max(p.min_rise) {
                    let (object, _) = self
                        .label
                        .clone()
                        .unwrap_or_else(|| (UNLABELLED.to_string(), Vec::new()));
                    let mut open = Open {
                        start: t,
                        object,
                        key: None,
                        frames: Vec::new(),
                        stamps: Vec::new(),
                    };
                    push(&mut open, f);
                    self.open = Some(open);
                } else if rise <= p.min_rise {
                    // Only the idle hand moves the baseline: it follows drift, not touch. A
                    // rise past the floor is never idle, even when the spread allows it:
                    // else a stream met mid-contact (the baseline seeded by a touch, the
                    // spread by the fall from it) would feed every later touch into the
                    // spread and never see a grasp.
                    let dt = t.saturating_sub(c.last) as f64 / 1e9;
                    let alpha = 1.0 - (-dt / p.baseline_s).exp();
                    let d = total - baseline;
                    c.baseline = Some(baseline + alpha * d);
                    c.variance = (1.0 - alpha) * (c.variance + alpha * d * d);
                }
                c.last = t;
                None
            }
            Some(open) => {
                push(open, f);
                c.last = t;
                if rise >= (p.offset_sigma * sigma).max(p.min_rise / 2.0) {
                    return None;
                }
                let open = self.open.take()?;
                if (t - open.start) as f64 / 1e9 < p.min_duration_s {
                    self.taps += 1;
                    return None;
                }
                let (labelled, classes) = match self.label.take() {
                    Some((_, classes)) => (true, classes),
                    None => (false, vec![0; self.spec.recorded_label_sets().len()]),
                };
                Some(finish(open, t, classes, labelled))
            }
        }
    }
}

fn push(open: &mut Open, f: StreamFrame) {
    open.frames.push(Frame {
        t: (f.t - open.start) as f64 / 1e9,
        taxels: f.taxels,
        encoders: f.encoders,
    });
    open.stamps.push(f.t);
}

/// The grasp of `open` ended at `end`; its key frame nearest the key time, as a bag's.
fn finish(open: Open, end: u64, classes: Vec<usize>, labelled: bool) -> Completed {
    let stamps = &open.stamps;
    let key_frame = open.key.map(|k| {
        let after = stamps.partition_point(|&s| s < k).min(stamps.len() - 1);
        if after > 0 && k - stamps[after - 1] <= stamps[after].abs_diff(k) {
            after - 1
        } else {
            after
        }
    });
    Completed {
        start: open.start,
        end,
        labelled,
        grasp: RawGrasp {
            object: open.object,
            classes,
            frames: open.frames,
            key_frame,
            trial: None,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::spec::LabelError;
    use std::path::Path;

    const MS: u64 = 1_000_000;

    fn spec(extra: &str) -> ImportSpec {
        let text = format!(
            r#"{{"sensors": [{{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "kPa"}}],
               "label_sets": [{{"name": "outcome", "classes": ["ok", "slip"]}}]{extra}}}"#
        );
        ImportSpec::from_str(&text, Path::new("spec.json")).unwrap()
    }

    fn frame(t: u64, p: f64) -> StreamFrame {
        StreamFrame {
            t,
            taxels: vec![vec![p, 0.0]],
            encoders: Vec::new(),
        }
    }

    #[test]
    fn events_cut_as_a_bag_does() {
        let mut c = Cutter::new(&spec(""), Cutting::Events);
        c.frame(frame(5 * MS, 1.0));
        assert_eq!(c.event(10 * MS, "start:mug").unwrap(), None);
        for k in 1..=5 {
            assert!(c.frame(frame(10 * MS * k, k as f64)).is_none());
        }
        c.event(30 * MS, "key").unwrap();
        assert_eq!(c.event(35 * MS, "key"), Err(LiveError::SecondKey));
        let done = c.event(40 * MS, "end:slip").unwrap().unwrap();
        // Frames from the start to the end, both included; times from the start.
        let ts: Vec<f64> = done.grasp.frames.iter().map(|f| f.t).collect();
        assert_eq!(ts, [0.0, 0.01, 0.02, 0.03]);
        assert_eq!(done.grasp.key_frame, Some(2));
        assert_eq!(done.grasp.classes, [1]);
        assert!(done.labelled);
        let err = c.event(50 * MS, "end:ok").unwrap_err();
        assert_eq!(
            err,
            LiveError::BeforeStart {
                event: "end:ok".into()
            }
        );
        assert!(err.to_string().contains("before any"), "{err}");
        assert!(matches!(
            c.event(50 * MS, "start:"),
            Err(LiveError::Spec(LabelError::EmptyObject))
        ));
        c.event(60 * MS, "start:cup").unwrap();
        let err = c.event(70 * MS, "end:wobbly").unwrap_err().to_string();
        assert!(err.contains("wobbly") && err.contains("outcome"), "{err}");
        assert!(c.in_progress().is_some(), "a refused end keeps the grasp");
    }

    /// Met in the middle of a contact (the first frame pressed), the detector still finds
    /// the grasps that follow.
    #[test]
    fn contact_met_mid_touch_still_finds_the_next_grasps() {
        let mut c = Cutter::new(&spec(""), Cutting::Contact(ContactParams::default()));
        let (mut t, mut grasps) = (0, 0);
        for cycle in 0..30 {
            for i in 0..60 {
                t += 20 * MS;
                let idle = 1.0 + 0.05 * ((i * 7 + cycle) % 5) as f64;
                // The first cycle starts pressed.
                let pressed = (20..40).contains(&i) || (cycle == 0 && i < 10);
                let p = if pressed { 100.0 } else { idle };
                grasps += usize::from(c.frame(frame(t, p)).is_some());
            }
            t += 500 * MS;
        }
        // The first few go by while the baseline falls from the touch it was seeded by (and
        // the spread of that fall fades); without the floor, none is ever found.
        assert!(grasps >= 20, "{grasps} grasps of 30");
    }

    #[test]
    fn contact_follows_drift_and_skips_taps() {
        let p = ContactParams {
            min_rise: 5.0,
            min_duration_s: 0.05,
            ..ContactParams::default()
        };
        let mut c = Cutter::new(&spec(""), Cutting::Contact(p));
        let mut t = 0;
        let mut grasps = Vec::new();
        let mut run = |c: &mut Cutter, grasps: &mut Vec<Completed>, p: f64, n: usize| {
            for _ in 0..n {
                t += 10 * MS;
                grasps.extend(c.frame(frame(t, p)));
            }
        };
        // A baseline drifting from 100 to 130 over 30 s never makes a grasp.
        for k in 0..3000 {
            run(&mut c, &mut grasps, 100.0 + 0.01 * k as f64, 1);
        }
        assert!(grasps.is_empty());
        // An exponential baseline lags a ramp by its slope × time constant (1 /s × 2 s).
        assert!((c.baseline().unwrap() - 128.0).abs() < 0.5);
        // A 30 ms tap is left out.
        run(&mut c, &mut grasps, 160.0, 3);
        run(&mut c, &mut grasps, 130.0, 1);
        assert_eq!((grasps.len(), c.taps), (0, 1));
        // A grasp of 0.5 s on the drifted baseline.
        c.by_hand("label:mug:ok").unwrap();
        run(&mut c, &mut grasps, 170.0, 50);
        run(&mut c, &mut grasps, 131.0, 1);
        assert_eq!(grasps.len(), 1);
        let g = &grasps[0];
        assert_eq!(g.grasp.frames.len(), 51);
        assert_eq!((g.grasp.object.as_str(), g.labelled), ("mug", true));
        // The next one nobody labelled.
        run(&mut c, &mut grasps, 170.0, 50);
        run(&mut c, &mut grasps, 130.0, 1);
        assert_eq!(grasps[1].grasp.object, UNLABELLED);
        assert!(!grasps[1].labelled);
    }

    #[test]
    fn by_hand_uses_the_latest_frame_time() {
        let mut c = Cutter::new(&spec(""), Cutting::Hand);
        assert_eq!(c.by_hand("start:mug"), Err(LiveError::NoFrameYet));
        c.frame(frame(10 * MS, 1.0));
        c.by_hand("start:mug").unwrap();
        c.frame(frame(20 * MS, 2.0));
        let g = c.by_hand("end:ok").unwrap().unwrap();
        assert_eq!(g.grasp.frames.len(), 1);
        assert_eq!((g.start, g.end), (10 * MS, 20 * MS));
        assert!(
            matches!(
                c.event(30 * MS, "start:mug"),
                Err(LiveError::EventsUnused { .. })
            ),
            "events are not used"
        );
    }
}
