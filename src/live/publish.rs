//! A recorded session as the messages of a live stream, what `serve` publishes: each
//! sensor on its own topic as a `std_msgs/msg/Float64MultiArray`, the encoders as a
//! `sensor_msgs/msg/JointState`, and the grasps as `std_msgs/msg/String` events
//! (`start:OBJECT`, `key`, `end:LABELS`), all in ROS 2 CDR, with the import spec that
//! reads them back. Values travel as f64, so a recording of the stream holds the session's
//! values exactly.
//!
//! Within a frame the joints and the other sensors are published before the reference
//! sensor (the first), whose message makes the frame; a grasp's `start` comes before its
//! first frame, `key` right after its key frame and `end` right after its last frame.

use crate::session::Session;

use super::LiveError;

/// The topics of a served session.
pub const EVENTS_TOPIC: &str = "/grasp_events";
pub const JOINTS_TOPIC: &str = "/joint_states";

/// The definition of a `std_msgs/msg/Float64MultiArray`, as `ros2 bag` stores it.
pub const FLOAT64_MULTIARRAY: &str = "std_msgs/MultiArrayLayout layout
float64[] data
================================================================================
MSG: std_msgs/MultiArrayLayout
MultiArrayDimension[] dim
uint32 data_offset
================================================================================
MSG: std_msgs/MultiArrayDimension
string label
uint32 size
uint32 stride
";

pub const JOINT_STATE: &str = "std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
";

pub const STRING: &str = "string data\n";

/// A topic of the stream: its name, schema name and `ros2msg` definition.
#[derive(Clone, Debug, PartialEq)]
pub struct Topic {
    pub name: String,
    pub schema_name: &'static str,
    pub definition: &'static str,
}

/// One message: its topic (index into [`Stream::topics`]), its time from the stream's
/// start (ns) and its CDR bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub topic: usize,
    pub at: u64,
    pub data: Vec<u8>,
}

/// A session laid out as a stream at `rate` times its speed.
pub struct Stream<'s> {
    session: &'s Session,
    pub topics: Vec<Topic>,
    rate: f64,
    /// The gap between two grasps (ns of the stream).
    gap: u64,
}

/// Little-endian plain CDR, aligned from the end of the 4-byte header.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Cdr {
        Cdr(vec![0, 1, 0, 0])
    }
    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend(s.as_bytes());
        self.0.push(0);
    }
    fn f64s(&mut self, v: &[f64]) {
        self.u32(v.len() as u32);
        if !v.is_empty() {
            self.align(8);
        }
        for x in v {
            self.0.extend(x.to_le_bytes());
        }
    }
}

/// A `Float64MultiArray` of `values` (no dimensions, offset 0).
pub fn multiarray(values: &[f64]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.u32(0);
    c.u32(0);
    c.f64s(values);
    c.0
}

/// A `JointState` of the named positions, stamped `t` ns.
pub fn joint_state(t: u64, names: &[String], positions: &[f64]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.u32((t / 1_000_000_000) as u32);
    c.u32((t % 1_000_000_000) as u32);
    c.string("");
    c.u32(names.len() as u32);
    for n in names {
        c.string(n);
    }
    c.f64s(positions);
    c.f64s(&[]);
    c.f64s(&[]);
    c.0
}

/// A `String`.
pub fn string(text: &str) -> Vec<u8> {
    let mut c = Cdr::new();
    c.string(text);
    c.0
}

fn sensor_topic(name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("/tactile/{clean}")
}

impl<'s> Stream<'s> {
    /// The stream of `session` at `rate` times its speed (its frame times divided by
    /// `rate`); refused when a class or object name could not travel in an event.
    pub fn new(session: &'s Session, rate: f64) -> Result<Stream<'s>, LiveError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(LiveError::Rate { rate });
        }
        for set in &session.label_sets {
            if let Some(c) = set.classes.iter().find(|c| c.contains([',', ':', '\n'])) {
                return Err(LiveError::EventUnsafeClass {
                    class: c.clone(),
                    set: set.name.clone(),
                });
            }
        }
        let mut topics: Vec<Topic> = session
            .sensors
            .iter()
            .map(|s| Topic {
                name: sensor_topic(&s.name),
                schema_name: "std_msgs/msg/Float64MultiArray",
                definition: FLOAT64_MULTIARRAY,
            })
            .collect();
        for (i, t) in topics.iter().enumerate() {
            if topics[..i].iter().any(|o| o.name == t.name) {
                return Err(LiveError::SharedTopic {
                    topic: t.name.clone(),
                });
            }
        }
        if !session.encoders.is_empty() {
            topics.push(Topic {
                name: JOINTS_TOPIC.into(),
                schema_name: "sensor_msgs/msg/JointState",
                definition: JOINT_STATE,
            });
        }
        topics.push(Topic {
            name: EVENTS_TOPIC.into(),
            schema_name: "std_msgs/msg/String",
            definition: STRING,
        });
        let period = session.meta.frame_rate_hz.map_or(0.1, |hz| 1.0 / hz);
        Ok(Stream {
            session,
            topics,
            rate,
            gap: ((5.0 * period / rate) * 1e9) as u64,
        })
    }

    /// Nanoseconds of the stream for `seconds` of the session.
    fn ns(&self, seconds: f64) -> u64 {
        (seconds.max(0.0) / self.rate * 1e9).round() as u64
    }

    /// The span of grasp `g` in the stream (ns).
    fn span(&self, g: usize) -> u64 {
        let frames = &self.session.grasps[g].frames;
        frames.last().map_or(0, |f| self.ns(f.t - frames[0].t))
    }

    /// The messages of grasp `g`, its start at `start` ns of the stream; the next grasp
    /// may start at the returned time.
    pub fn grasp(&self, g: usize, start: u64) -> (Vec<Message>, u64) {
        let s = self.session;
        let grasp = &s.grasps[g];
        let events = self.topics.len() - 1;
        let joints = (!s.encoders.is_empty()).then_some(s.sensors.len());
        let mut out = Vec::new();
        out.push(Message {
            topic: events,
            at: start,
            data: string(&format!("start:{}", grasp.object)),
        });
        let t0 = grasp.frames.first().map_or(0.0, |f| f.t);
        let mut last = start;
        for (i, f) in grasp.frames.iter().enumerate() {
            let at = start + self.ns(f.t - t0);
            last = at;
            if let Some(j) = joints {
                out.push(Message {
                    topic: j,
                    at,
                    data: joint_state(at, &s.encoders, &f.encoders),
                });
            }
            for (k, values) in f.taxels.iter().enumerate().skip(1) {
                out.push(Message {
                    topic: k,
                    at,
                    data: multiarray(values),
                });
            }
            out.push(Message {
                topic: 0,
                at,
                data: multiarray(&f.taxels[0]),
            });
            if i == grasp.key_frame {
                out.push(Message {
                    topic: events,
                    at,
                    data: string("key"),
                });
            }
        }
        let labels: Vec<&str> = s
            .label_sets
            .iter()
            .zip(&grasp.labels)
            .filter(|(set, _)| set.name != crate::session::spec::OBJECT)
            .map(|(set, &c)| set.classes.get(c).map_or("", String::as_str))
            .collect();
        out.push(Message {
            topic: events,
            at: last,
            data: string(&format!("end:{}", labels.join(","))),
        });
        (out, start + self.span(g) + self.gap)
    }

    /// The import spec (JSON) that reads this stream back as the session.
    pub fn spec(&self) -> serde_json::Value {
        let s = self.session;
        let sensors: Vec<serde_json::Value> = s
            .sensors
            .iter()
            .zip(&self.topics)
            .map(|(sensor, topic)| {
                let mut v = serde_json::json!({
                    "name": sensor.name,
                    "topic": topic.name,
                    "layout": sensor.layout,
                    "unit": sensor.unit,
                    "transform": sensor.transform,
                });
                if let Some(r) = sensor.range {
                    v["range"] = serde_json::json!(r);
                }
                v
            })
            .collect();
        let mut spec = serde_json::json!({
            "name": s.meta.name,
            "sensors": sensors,
            "label_sets": s.label_sets,
            "grasps": {"events": EVENTS_TOPIC},
        });
        if let Some(hz) = s.meta.frame_rate_hz {
            spec["frame_rate_hz"] = serde_json::json!(hz);
        }
        if !s.encoders.is_empty() {
            spec["joints"] = serde_json::json!({"topic": JOINTS_TOPIC, "names": s.encoders});
        }
        spec
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::cdr::{self, ArrayKind, MsgType};

    #[test]
    fn messages_decode_with_the_bag_reader() {
        let mut out = Vec::new();
        cdr::decode_multiarray(&multiarray(&[1.5, -2.0]), ArrayKind::F64, &mut out).unwrap();
        assert_eq!(out, [1.5, -2.0]);
        let names = ["a".to_string(), "bc".to_string()];
        let js = joint_state(3_000_000_007, &names, &[0.25, 7.0]);
        let js = cdr::decode_joint_state(&js).unwrap();
        assert_eq!(js.names, ["a", "bc"]);
        assert_eq!(js.positions, [0.25, 7.0]);
        assert_eq!(cdr::decode_string(&string("end:mug")).unwrap(), "end:mug");
        for (ty, def) in [
            (MsgType::MultiArray(ArrayKind::F64), FLOAT64_MULTIARRAY),
            (MsgType::JointState, JOINT_STATE),
            (MsgType::String, STRING),
        ] {
            cdr::check_schema(ty, "ros2msg", def.as_bytes()).unwrap();
        }
    }
}
