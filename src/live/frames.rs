//! Frames from a stream's samples: as in a bag, the reference topic (the first sensor's)
//! makes the frames, and every other topic gives a frame its latest message. Live, a
//! frame cannot wait for a later message, so the nearest earlier one stands for it; with
//! the spec's `sync_tolerance_s` that message must lie within it, else the frame is left
//! out and counted, as the bag importer leaves out and counts frames it cannot fill.

use super::channels::{Plan, Sample};

/// One frame of the stream at log time `t` (ns), its taxels per spec sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamFrame {
    pub t: u64,
    pub taxels: Vec<Vec<f64>>,
    pub encoders: Vec<f64>,
}

/// What a sample makes: a frame, an event's text, or nothing yet.
#[derive(Clone, Debug, PartialEq)]
pub enum Assembled {
    Frame(StreamFrame),
    Event(u64, String),
    Nothing,
}

pub struct Assembler {
    /// Per spec sensor: its tactile topic and its values' range in that topic's rows.
    places: Vec<(usize, std::ops::Range<usize>)>,
    /// The latest row of each tactile topic but the reference, and its time.
    latest: Vec<Option<(u64, Vec<f64>)>>,
    joints: Option<(u64, Vec<f64>)>,
    has_joints: bool,
    tolerance: Option<u64>,
    /// Reference messages that made no frame: some other topic had no message (within the
    /// tolerance) yet.
    pub left_out: u64,
}

impl Assembler {
    pub fn new(plan: &Plan, tolerance: Option<u64>) -> Assembler {
        let mut places = vec![(0, 0..0); plan.sensors.len()];
        for (k, tt) in plan.tactile.iter().enumerate() {
            for (s, range) in &tt.sensors {
                places[*s] = (k, range.clone());
            }
        }
        Assembler {
            places,
            latest: vec![None; plan.tactile.len()],
            joints: None,
            has_joints: !plan.joint_names.is_empty(),
            tolerance,
            left_out: 0,
        }
    }

    pub fn push(&mut self, t: u64, sample: Sample) -> Assembled {
        match sample {
            Sample::Event(text) => Assembled::Event(t, text),
            Sample::Joints(v) => {
                self.joints = Some((t, v));
                Assembled::Nothing
            }
            Sample::Tactile { topic, values } if topic > 0 => {
                self.latest[topic] = Some((t, values));
                Assembled::Nothing
            }
            Sample::Tactile { values, .. } => match self.frame(t, &values) {
                Some(f) => Assembled::Frame(f),
                None => {
                    self.left_out += 1;
                    Assembled::Nothing
                }
            },
        }
    }

    fn fresh(&self, at: u64, t: u64) -> bool {
        self.tolerance.is_none_or(|tol| t.abs_diff(at) <= tol)
    }

    /// The frame of reference row `row` at `t`, when every other topic has a message.
    fn frame(&self, t: u64, row: &[f64]) -> Option<StreamFrame> {
        let mut taxels = Vec::with_capacity(self.places.len());
        for (topic, range) in &self.places {
            let values = if *topic == 0 {
                row
            } else {
                match &self.latest[*topic] {
                    Some((at, v)) if self.fresh(*at, t) => v.as_slice(),
                    _ => return None,
                }
            };
            taxels.push(values[range.clone()].to_vec());
        }
        let encoders = match (&self.joints, self.has_joints) {
            (_, false) => Vec::new(),
            (Some((at, v)), true) if self.fresh(*at, t) => v.clone(),
            _ => return None,
        };
        Some(StreamFrame {
            t,
            taxels,
            encoders,
        })
    }
}
