//! A stream without a spec: the channels a server advertises, with their schemas, and a
//! spec proposed from them (numeric arrays → sensors with a layout guessed from their
//! length, JointState → the joints, a String topic → the grasp events), to edit and save.
//!
//! The array lengths and joint names are read from one message of each such channel: the
//! discovery subscribes to every channel of a type a spec reads, waits until each array
//! and JointState channel has sent one (or its time limit), and disconnects.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use tungstenite::Message;

use super::LiveError;
use super::client::connect;
use super::protocol::{self, Channel, ServerText};
use crate::error::Kept;
use crate::session::cdr::{self, MsgType};

/// An advertised channel, and what one of its messages showed.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub channel: Channel,
    /// Numeric arrays: the values a message holds.
    pub length: Option<usize>,
    /// JointState: the joints a message names.
    pub joints: Option<Vec<String>>,
}

impl Found {
    fn ty(&self) -> Option<MsgType> {
        MsgType::from_name(&self.channel.schema_name)
    }

    /// The schema in a line: `std_msgs/msg/Float64MultiArray (cdr), 24 values`.
    pub fn line(&self) -> String {
        let mut out = format!(
            "{}: {} ({})",
            self.channel.topic, self.channel.schema_name, self.channel.encoding
        );
        if let Some(n) = self.length {
            out += &format!(", {n} values");
        }
        if let Some(j) = &self.joints {
            out += &format!(", joints {}", j.join(", "));
        }
        out
    }
}

/// Connect to `url`, list the advertised channels, and read one message of each numeric
/// array and JointState channel (within `wait`).
pub fn discover(url: &str, wait: Duration) -> Result<Vec<Found>, LiveError> {
    let at = |e: LiveError| LiveError::Discovery {
        url: url.to_string(),
        source: Kept::new(e),
    };
    let (mut ws, _) = connect(url)?;
    let until = Instant::now() + wait;
    let mut found: Vec<Found> = Vec::new();
    // Subscription id → index into `found`; the channels still to hear from.
    let mut subs: HashMap<u32, usize> = HashMap::new();
    let mut waiting = 0usize;
    let mut quiet_since = Instant::now();
    while Instant::now() < until {
        let message = match ws.read() {
            Ok(m) => m,
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                // Every channel heard from, and no new one for a while: done.
                if waiting == 0
                    && !found.is_empty()
                    && quiet_since.elapsed() > Duration::from_millis(300)
                {
                    break;
                }
                continue;
            }
            Err(e) => return Err(at(LiveError::Ended(Kept::new(e)))),
        };
        match message {
            Message::Text(text) => {
                let Ok(ServerText::Advertise(channels)) = protocol::parse_text(text.as_str())
                else {
                    continue;
                };
                quiet_since = Instant::now();
                let mut pairs = Vec::new();
                for c in channels {
                    if found.iter().any(|f| f.channel.id == c.id) {
                        continue;
                    }
                    let f = Found {
                        channel: c,
                        length: None,
                        joints: None,
                    };
                    // Every channel of a type a spec reads is subscribed (a server may hold
                    // back until its clients listen); the arrays and joints are waited for.
                    if let Some(ty) = f.ty() {
                        let id = subs.len() as u32 + 1;
                        subs.insert(id, found.len());
                        pairs.push((id, f.channel.id));
                        waiting += usize::from(ty != MsgType::String);
                    }
                    found.push(f);
                }
                if !pairs.is_empty() {
                    ws.send(Message::text(protocol::subscribe(&pairs)))
                        .map_err(|e| at(LiveError::Subscribe(Kept::new(e))))?;
                }
            }
            Message::Binary(bytes) => {
                let Ok(Some(data)) = protocol::parse_binary(&bytes) else {
                    continue;
                };
                let Some(&i) = subs.get(&data.subscription) else {
                    continue;
                };
                let f = &mut found[i];
                if f.length.is_some() || f.joints.is_some() {
                    continue;
                }
                // A message that does not decode leaves the channel unsized (the proposal
                // then says so); discovery counts on the next one.
                match (f.ty(), f.channel.encoding.as_str()) {
                    (Some(MsgType::MultiArray(kind)), "cdr") => {
                        let mut v = Vec::new();
                        if cdr::decode_multiarray(data.payload, kind, &mut v).is_ok() {
                            f.length = Some(v.len());
                        }
                    }
                    (Some(MsgType::JointState), "cdr") => {
                        if let Ok(js) = cdr::decode_joint_state(data.payload) {
                            f.joints = Some(js.names.iter().map(|n| n.to_string()).collect());
                        }
                    }
                    (Some(MsgType::MultiArray(_)), "json") => {
                        f.length = serde_json::from_slice::<serde_json::Value>(data.payload)
                            .ok()
                            .and_then(|v| v.get("data")?.as_array().map(Vec::len));
                    }
                    (Some(MsgType::JointState), "json") => {
                        f.joints = serde_json::from_slice::<serde_json::Value>(data.payload)
                            .ok()
                            .and_then(|v| serde_json::from_value(v.get("name")?.clone()).ok());
                    }
                    _ => {}
                }
                if f.length.is_some() || f.joints.is_some() {
                    waiting = waiting.saturating_sub(1);
                }
            }
            Message::Close(_) => break,
            _ => {}
        }
    }
    let _ = ws.close(None);
    let _ = ws.flush();
    if found.is_empty() {
        return Err(LiveError::NoChannel {
            url: url.to_string(),
            wait,
        });
    }
    Ok(found)
}

/// A layout for `n` taxels: the built-in fingertips by their counts (iCub 12, BioTac SP
/// 24), else the squarest grid.
pub fn guess_layout(n: usize) -> String {
    match n {
        12 => "icub-fingertip".into(),
        24 => "biotac-sp".into(),
        _ => {
            let rows = (1..=n.isqrt().max(1))
                .rev()
                .find(|r| n.is_multiple_of(*r))
                .unwrap_or(1);
            format!("grid {rows}x{}", n / rows.max(1))
        }
    }
}

/// The spec proposed for what was found (see the module's text), and the channels left
/// out because no message sized them (for the user to fill in).
pub fn propose(name: &str, found: &[Found]) -> (serde_json::Value, Vec<String>) {
    let mut sensors = Vec::new();
    let mut left_out = Vec::new();
    let mut joints = None;
    let mut events = None;
    for f in found {
        match (f.ty(), f.length, &f.joints) {
            (Some(MsgType::MultiArray(_)), Some(n), _) if n > 0 => {
                // The topic's last word (`/hand/index/tactile` → `tactile` would repeat:
                // then the whole path).
                let topic = f.channel.topic.trim_matches('/');
                let last = topic.rsplit('/').next().unwrap_or_default();
                let taken = |name: &str| {
                    sensors
                        .iter()
                        .any(|s: &serde_json::Value| s["name"] == name)
                };
                let name = if last.is_empty() {
                    format!("sensor{}", sensors.len())
                } else if taken(last)
                    || found
                        .iter()
                        .filter(|o| o.channel.topic.ends_with(&format!("/{last}")))
                        .count()
                        > 1
                {
                    topic.replace('/', "_")
                } else {
                    last.to_string()
                };
                sensors.push(serde_json::json!({
                    "name": name,
                    "topic": f.channel.topic,
                    "layout": guess_layout(n),
                    "unit": "raw",
                }));
            }
            (Some(MsgType::JointState), _, Some(names)) if joints.is_none() => {
                joints = Some(serde_json::json!({"topic": f.channel.topic, "names": names}));
            }
            (Some(MsgType::String), _, _) if events.is_none() => {
                events = Some(f.channel.topic.clone());
            }
            (Some(MsgType::MultiArray(_) | MsgType::JointState), ..) => {
                left_out.push(format!(
                    "{}: no message was read to size it",
                    f.channel.topic
                ));
            }
            _ => {}
        }
    }
    let mut spec = serde_json::json!({"name": name, "sensors": sensors});
    if let Some(j) = joints {
        spec["joints"] = j;
    }
    if let Some(e) = events {
        spec["grasps"] = serde_json::json!({"events": e});
    }
    (spec, left_out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(id: u64, topic: &str, schema: &str) -> Channel {
        Channel {
            id,
            topic: topic.into(),
            encoding: "cdr".into(),
            schema_name: schema.into(),
            schema_encoding: Some("ros2msg".into()),
            schema: String::new(),
        }
    }

    #[test]
    fn layouts_are_guessed_from_the_length() {
        assert_eq!(guess_layout(12), "icub-fingertip");
        assert_eq!(guess_layout(24), "biotac-sp");
        assert_eq!(guess_layout(16), "grid 4x4");
        assert_eq!(guess_layout(30), "grid 5x6");
        assert_eq!(guess_layout(7), "grid 1x7");
    }

    #[test]
    fn the_proposal_loads_as_a_spec() {
        let found = vec![
            Found {
                length: Some(16),
                ..Found {
                    channel: channel(1, "/hand/index", "std_msgs/msg/Float32MultiArray"),
                    length: None,
                    joints: None,
                }
            },
            Found {
                channel: channel(2, "/joint_states", "sensor_msgs/msg/JointState"),
                length: None,
                joints: Some(vec!["a".into(), "b".into()]),
            },
            Found {
                channel: channel(3, "/grasp_events", "std_msgs/msg/String"),
                length: None,
                joints: None,
            },
            Found {
                channel: channel(4, "/camera", "sensor_msgs/msg/Image"),
                length: None,
                joints: None,
            },
        ];
        let (v, left_out) = propose("robot", &found);
        assert_eq!(v["sensors"][0]["layout"], "grid 4x4");
        assert_eq!(v["sensors"][0]["name"], "index");
        assert_eq!(v["joints"]["names"], serde_json::json!(["a", "b"]));
        assert_eq!(v["grasps"]["events"], "/grasp_events");
        assert!(left_out.is_empty());
        let spec = crate::session::ImportSpec::from_str(
            &v.to_string(),
            std::path::Path::new("proposed.json"),
        )
        .unwrap();
        assert_eq!(spec.sensors.len(), 1);
        assert_eq!(spec.encoder_names(), ["a", "b"]);
    }
}
