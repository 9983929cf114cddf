//! The topics the spec reads, the role of each, and the check of a channel's type and
//! definition against the decoder.

use std::path::Path;

use crate::session::SessionError;
use crate::session::cdr::{self, ArrayKind, MsgType, TACTILE_TYPES};
use crate::session::error::shorten;
use crate::session::spec::ImportSpec;

/// What the importer does with a topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// Index into `Bag::tactile`.
    Tactile(usize),
    Joints,
    Events,
}

impl Role {
    /// The spec's topic of this role, in words.
    pub(crate) fn what(self) -> &'static str {
        match self {
            Role::Tactile(_) => "tactile topic",
            Role::Joints => "joint topic",
            Role::Events => "events topic",
        }
    }
}

/// The topics the spec reads, with the role of each.
pub(crate) fn roles(
    spec: &ImportSpec,
    events: Option<&str>,
) -> Result<Vec<(String, Role)>, SessionError> {
    let mut out: Vec<(String, Role)> = Vec::new();
    let mut tactile = 0;
    for (s, sensor) in spec.sensors.iter().enumerate() {
        let Some(topic) = &sensor.topic else {
            return Err(SessionError::field(
                &spec.path,
                format!("sensors[{s}].topic"),
                format!(
                    "sensor `{}` needs the topic it is read from",
                    sensor.sensor.name
                ),
            ));
        };
        if !out.iter().any(|(t, _)| t == topic) {
            out.push((topic.clone(), Role::Tactile(tactile)));
            tactile += 1;
        }
    }
    let mut add = |topic: &str, role: Role, field: &str| {
        if out.iter().any(|(t, _)| t == topic) {
            return Err(SessionError::field(
                &spec.path,
                field,
                format!("topic `{topic}` is already read for another purpose"),
            ));
        }
        out.push((topic.to_string(), role));
        Ok(())
    };
    if let Some(j) = &spec.joints {
        let Some(topic) = &j.topic else {
            return Err(SessionError::field(
                &spec.path,
                "joints.topic",
                "the JointState topic of the joints is missing",
            ));
        };
        add(topic, Role::Joints, "joints.topic")?;
    }
    if let Some(topic) = events {
        add(topic, Role::Events, "grasps.events")?;
    }
    Ok(out)
}

/// The spec's topic of each role, and the types it may have.
pub(crate) fn allowed(role: Role) -> &'static str {
    match role {
        Role::Tactile(_) => TACTILE_TYPES,
        Role::Joints => "sensor_msgs/msg/JointState",
        Role::Events => "std_msgs/msg/String",
    }
}

pub(crate) fn type_fits(role: Role, ty: MsgType) -> bool {
    matches!(
        (role, ty),
        (Role::Tactile(_), MsgType::MultiArray(_))
            | (Role::Joints, MsgType::JointState)
            | (Role::Events, MsgType::String)
    )
}

/// A channel as first seen in a file: its role and element type, once checked.
#[derive(Clone, Copy)]
pub(super) struct Checked {
    pub(super) role: Role,
    pub(super) kind: Option<ArrayKind>,
}

/// Lists a channel's topic and type among the bag's topics (once); returns the type.
pub(super) fn note_topic(seen: &mut Vec<(String, String)>, channel: &mcap::Channel<'_>) -> String {
    let schema_name = channel
        .schema
        .as_ref()
        .map(|s| s.name.clone())
        .unwrap_or_else(|| "no schema".into());
    if !seen.iter().any(|(t, _)| *t == channel.topic) {
        seen.push((channel.topic.clone(), schema_name.clone()));
    }
    schema_name
}

/// Check a channel the first time it appears: a spec topic must have a supported type
/// whose definition in the bag matches the decoder, in CDR.
pub(super) fn check_channel(
    file: &Path,
    channel: &mcap::Channel<'_>,
    roles: &[(String, Role)],
    seen: &mut Vec<(String, String)>,
) -> Result<Option<Checked>, SessionError> {
    let schema_name = note_topic(seen, channel);
    let Some(&(_, role)) = roles.iter().find(|(t, _)| *t == channel.topic) else {
        return Ok(None);
    };
    let err = |m: String| SessionError::topic(file, &channel.topic, None, m);
    let ty = MsgType::from_name(&schema_name).filter(|&ty| type_fits(role, ty));
    let Some(ty) = ty else {
        return Err(err(format!(
            "its message type is {}; the spec reads it as {}",
            shorten(&schema_name),
            allowed(role)
        )));
    };
    if channel.message_encoding != "cdr" {
        return Err(err(format!(
            "messages are encoded as `{}`, not ROS 2 CDR",
            shorten(&channel.message_encoding)
        )));
    }
    if let Some(schema) = &channel.schema {
        cdr::check_schema(ty, &schema.encoding, &schema.data)
            .map_err(|e| SessionError::topic_caused(file, &channel.topic, None, e))?;
    }
    Ok(Some(Checked {
        role,
        kind: match ty {
            MsgType::MultiArray(k) => Some(k),
            _ => None,
        },
    }))
}
