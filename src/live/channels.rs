//! Which advertised channels the spec reads, and their messages decoded into samples: the
//! same topics, roles, types and definition checks as a bag's (`session::bag`), and the
//! same CDR decoder; `json` channels carry the same messages as ROS 2's JSON form
//! (`{"data": [...]}`, `{"name": [...], "position": [...]}`, `{"data": "text"}`).

use crate::error::Kept;
use crate::session::bag::{Role, allowed, roles, type_fits};
use crate::session::cdr::{self, ArrayKind, MsgType};
use crate::session::spec::{GraspCut, ImportSpec};
use crate::session::{Sensor, SessionError};

use super::LiveError;
use super::protocol::Channel;

/// The spec's topics and what each message of them must hold.
#[derive(Clone, Debug)]
pub struct Plan {
    pub(crate) roles: Vec<(String, Role)>,
    /// Per tactile topic (in role order): the spec's sensors read from it and the values a
    /// message holds (the end of the last sensor's slice).
    pub tactile: Vec<TactileTopic>,
    pub joint_names: Vec<String>,
    pub sensors: Vec<Sensor>,
}

#[derive(Clone, Debug)]
pub struct TactileTopic {
    pub topic: String,
    pub sensors: Vec<(usize, std::ops::Range<usize>)>,
    pub width: usize,
}

impl Plan {
    pub fn of(spec: &ImportSpec) -> Result<Plan, SessionError> {
        let events = match &spec.cut {
            Some(GraspCut::Events(t)) => Some(t.as_str()),
            _ => None,
        };
        let roles = roles(spec, events)?;
        let tactile = roles
            .iter()
            .filter(|(_, r)| matches!(r, Role::Tactile(_)))
            .map(|(topic, _)| {
                let sensors: Vec<(usize, std::ops::Range<usize>)> = spec
                    .sensors
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.topic.as_deref() == Some(topic))
                    .map(|(i, s)| (i, s.range_in_message()))
                    .collect();
                let width = sensors.iter().map(|(_, r)| r.end).max().unwrap_or(0);
                TactileTopic {
                    topic: topic.clone(),
                    sensors,
                    width,
                }
            })
            .collect();
        Ok(Plan {
            roles,
            tactile,
            joint_names: spec.encoder_names(),
            sensors: spec.sensors.iter().map(|s| s.sensor.clone()).collect(),
        })
    }

    /// How a channel's messages are read: `Ok(None)` when the spec does not read its topic,
    /// an error naming the topic when its type or definition does not fit.
    pub fn route(&self, channel: &Channel) -> Result<Option<Route>, LiveError> {
        let Some(&(_, role)) = self.roles.iter().find(|(t, _)| *t == channel.topic) else {
            return Ok(None);
        };
        let topic = || channel.topic.clone();
        let ty = MsgType::from_name(&channel.schema_name).filter(|&ty| type_fits(role, ty));
        let Some(ty) = ty else {
            return Err(LiveError::Schema {
                topic: topic(),
                schema: channel.schema_name.clone(),
                reads: allowed(role),
            });
        };
        let json = match channel.encoding.as_str() {
            "cdr" => {
                let encoding = channel.schema_encoding.as_deref().unwrap_or("");
                cdr::check_schema(ty, encoding, channel.schema.as_bytes()).map_err(|source| {
                    LiveError::Definition {
                        topic: topic(),
                        source,
                    }
                })?;
                false
            }
            "json" => true,
            other => {
                return Err(LiveError::Encoding {
                    topic: topic(),
                    encoding: other.to_string(),
                });
            }
        };
        Ok(Some(Route { role, ty, json }))
    }

    /// A message of a routed channel, checked as a bag's: a tactile row of the topic's
    /// width with every value finite and in its sensor's range, the named joints' finite
    /// positions, or an event's text.
    pub fn decode(&self, route: &Route, payload: &[u8]) -> Result<Sample, LiveError> {
        match (route.role, route.ty) {
            (Role::Tactile(i), MsgType::MultiArray(kind)) => {
                let mut values = Vec::new();
                if route.json {
                    values = json_numbers(payload, "data")?;
                } else {
                    cdr::decode_multiarray(payload, kind, &mut values)?;
                }
                self.check_row(i, &values, kind)?;
                Ok(Sample::Tactile { topic: i, values })
            }
            (Role::Joints, MsgType::JointState) => {
                let (names, positions) = if route.json {
                    let v = json_value(payload)?;
                    let names: Vec<String> = v
                        .get("name")
                        .and_then(|n| serde_json::from_value(n.clone()).ok())
                        .ok_or_else(|| json_field("name", "a list of strings"))?;
                    (names, json_numbers(payload, "position")?)
                } else {
                    let js = cdr::decode_joint_state(payload)?;
                    let names = js.names.iter().map(|n| n.to_string()).collect();
                    (names, js.positions)
                };
                if names.len() != positions.len() {
                    return Err(LiveError::JointCount {
                        names: names.len(),
                        positions: positions.len(),
                    });
                }
                let mut out = Vec::with_capacity(self.joint_names.len());
                for name in &self.joint_names {
                    let Some(k) = names.iter().position(|n| n == name) else {
                        return Err(LiveError::MissingJoint {
                            joint: name.clone(),
                            has: names,
                        });
                    };
                    let v = positions[k];
                    if !v.is_finite() {
                        return Err(LiveError::JointNotFinite {
                            joint: name.clone(),
                            value: v,
                        });
                    }
                    out.push(v);
                }
                Ok(Sample::Joints(out))
            }
            (Role::Events, MsgType::String) => {
                let text = if route.json {
                    json_value(payload)?
                        .get("data")
                        .and_then(|d| d.as_str())
                        .map(str::to_string)
                        .ok_or_else(|| json_field("data", "a string"))?
                } else {
                    cdr::decode_string(payload)?.to_string()
                };
                Ok(Sample::Event(text))
            }
            _ => Err(LiveError::RoleMismatch),
        }
    }

    fn check_row(&self, topic: usize, values: &[f64], kind: ArrayKind) -> Result<(), LiveError> {
        let tt = &self.tactile[topic];
        if values.len() != tt.width {
            let parts: Vec<String> = tt
                .sensors
                .iter()
                .map(|(s, r)| format!("`{}` at {}..{}", self.sensors[*s].name, r.start, r.end))
                .collect();
            return Err(LiveError::RowWidth {
                kind,
                got: values.len(),
                layouts: parts.join(", "),
                width: tt.width,
            });
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(LiveError::NotFinite {
                index: k,
                value: values[k],
            });
        }
        for (s, range) in &tt.sensors {
            let sensor = &self.sensors[*s];
            if let Some(k) = values[range.clone()]
                .iter()
                .position(|&v| !sensor.in_range(v))
            {
                return Err(LiveError::OutOfRange {
                    sensor: sensor.name.clone(),
                    taxel: k,
                    value: values[range.start + k],
                    range: sensor.range_text(),
                });
            }
        }
        Ok(())
    }
}

/// A routed channel: its role, its type and whether it is JSON (else CDR).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Route {
    pub(crate) role: Role,
    pub ty: MsgType,
    pub json: bool,
}

/// A decoded message.
#[derive(Clone, Debug, PartialEq)]
pub enum Sample {
    /// A row of tactile topic `topic` (index into [`Plan::tactile`]).
    Tactile {
        topic: usize,
        values: Vec<f64>,
    },
    /// The spec's joints, in its order.
    Joints(Vec<f64>),
    Event(String),
}

fn json_value(payload: &[u8]) -> Result<serde_json::Value, LiveError> {
    serde_json::from_slice(payload).map_err(|e| LiveError::Json(Kept::new(e)))
}

fn json_field(field: impl Into<String>, expected: &'static str) -> LiveError {
    LiveError::JsonField {
        field: field.into(),
        expected,
    }
}

fn json_numbers(payload: &[u8], field: &str) -> Result<Vec<f64>, LiveError> {
    let v = json_value(payload)?;
    let list = v
        .get(field)
        .and_then(|d| d.as_array())
        .ok_or_else(|| json_field(field, "a list"))?;
    list.iter()
        .enumerate()
        .map(|(k, x)| {
            x.as_f64()
                .ok_or_else(|| json_field(format!("{field}[{k}]"), "a number"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::publish::{FLOAT64_MULTIARRAY, JOINT_STATE, joint_state, multiarray};
    use std::path::Path;

    fn plan() -> Plan {
        let spec = ImportSpec::from_str(
            r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "raw",
                             "range": [0, 255]},
                            {"name": "b", "topic": "/a", "slice": [2, 4], "layout": "grid 1x2",
                             "unit": "raw"}],
               "joints": {"topic": "/js", "names": ["j2", "j1"]},
               "grasps": {"events": "/ev"}}"#,
            Path::new("spec.json"),
        )
        .unwrap();
        Plan::of(&spec).unwrap()
    }

    fn channel(topic: &str, encoding: &str, schema_name: &str, schema: &str) -> Channel {
        Channel {
            id: 1,
            topic: topic.into(),
            encoding: encoding.into(),
            schema_name: schema_name.into(),
            schema_encoding: Some("ros2msg".into()),
            schema: schema.into(),
        }
    }

    #[test]
    fn cdr_and_json_channels_decode_to_the_spec() {
        let p = plan();
        let arr = "std_msgs/msg/Float64MultiArray";
        let r = p
            .route(&channel("/a", "cdr", arr, FLOAT64_MULTIARRAY))
            .unwrap()
            .unwrap();
        assert_eq!(
            p.decode(&r, &multiarray(&[1.0, 2.0, 3.0, 4.0])).unwrap(),
            Sample::Tactile {
                topic: 0,
                values: vec![1.0, 2.0, 3.0, 4.0]
            }
        );
        let err = p.decode(&r, &multiarray(&[1.0, 2.0, 3.0])).unwrap_err();
        assert!(
            matches!(
                err,
                LiveError::RowWidth {
                    got: 3,
                    width: 4,
                    ..
                }
            ),
            "{err:?}"
        );
        let text = err.to_string();
        assert!(
            text.contains("3 values") && text.contains("`b` at 2..4"),
            "{text}"
        );
        let err = p
            .decode(&r, &multiarray(&[1.0, 300.0, 3.0, 4.0]))
            .unwrap_err();
        assert!(
            matches!(&err, LiveError::OutOfRange { sensor, taxel: 1, .. } if sensor == "a"),
            "{err:?}"
        );
        assert!(err.to_string().contains("sensor `a` taxel 1"), "{err}");
        assert!(matches!(
            p.decode(&r, &multiarray(&[1.0, 2.0, 3.0, 4.0])[..20]),
            Err(LiveError::Cdr(_))
        ));
        let js = "sensor_msgs/msg/JointState";
        let r = p
            .route(&channel("/js", "cdr", js, JOINT_STATE))
            .unwrap()
            .unwrap();
        let names = ["j1".to_string(), "j2".to_string()];
        assert_eq!(
            p.decode(&r, &joint_state(0, &names, &[1.0, 2.0])).unwrap(),
            Sample::Joints(vec![2.0, 1.0])
        );
        let r = p.route(&channel("/a", "json", arr, "")).unwrap().unwrap();
        assert_eq!(
            p.decode(&r, br#"{"data": [0, 1, 2, 3]}"#).unwrap(),
            Sample::Tactile {
                topic: 0,
                values: vec![0.0, 1.0, 2.0, 3.0]
            }
        );
        assert!(matches!(
            p.decode(&r, b"{not json"),
            Err(LiveError::Json(_))
        ));
        assert_eq!(
            p.decode(&r, br#"{"data": [0, "x"]}"#),
            Err(json_field("data[1]", "a number"))
        );
        let r = p
            .route(&channel("/ev", "json", "std_msgs/String", ""))
            .unwrap()
            .unwrap();
        assert_eq!(
            p.decode(&r, br#"{"data": "start:mug"}"#).unwrap(),
            Sample::Event("start:mug".into())
        );
    }

    #[test]
    fn channels_that_do_not_fit_are_refused_by_topic() {
        let p = plan();
        assert_eq!(
            p.route(&channel("/camera", "cdr", "x/Image", "")).unwrap(),
            None
        );
        let err = p.route(&channel(
            "/a",
            "cdr",
            "sensor_msgs/msg/JointState",
            JOINT_STATE,
        ));
        let err = err.unwrap_err();
        assert!(
            matches!(&err, LiveError::Schema { topic, .. } if topic == "/a"),
            "{err:?}"
        );
        assert!(err.to_string().contains("channel `/a`"), "{err}");
        let custom = "std_msgs/MultiArrayLayout layout\nfloat64[] data\nint32 extra\n";
        let err = p
            .route(&channel(
                "/a",
                "cdr",
                "std_msgs/msg/Float64MultiArray",
                custom,
            ))
            .unwrap_err();
        assert!(
            matches!(&err, LiveError::Definition { topic, source: crate::session::cdr::CdrError::NotStandard { .. } }
                if topic == "/a"),
            "{err:?}"
        );
        let err = p
            .route(&channel(
                "/a",
                "protobuf",
                "std_msgs/msg/Float64MultiArray",
                "",
            ))
            .unwrap_err();
        assert_eq!(
            err,
            LiveError::Encoding {
                topic: "/a".into(),
                encoding: "protobuf".into()
            }
        );
        assert!(err.to_string().contains("protobuf"), "{err}");
    }
}
