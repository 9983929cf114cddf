//! A message of a topic the spec reads, decoded and checked into its topic's rows: a
//! tactile array, the joints' positions, or an event's text.

use std::path::Path;

use super::{JointTopic, TactileTopic};
use crate::session::SessionError;
use crate::session::cdr::{self, ArrayKind, CdrError};
use crate::session::spec::ImportSpec;

/// Where a message is, for its errors: its file, topic and bag time.
pub(super) struct At<'a> {
    pub(super) file: &'a Path,
    pub(super) topic: &'a str,
    pub(super) t: u64,
}

impl At<'_> {
    fn error(&self, m: String) -> SessionError {
        SessionError::topic(self.file, self.topic, Some(self.t), m)
    }

    /// The message does not decode: the decoder's error is kept.
    fn undecoded(&self, e: CdrError) -> SessionError {
        SessionError::topic_caused(self.file, self.topic, Some(self.t), e)
    }

    /// A MultiArray of a tactile topic: one row of the topic's width, every value finite
    /// and in its sensor's range.
    pub(super) fn tactile(
        &self,
        tt: &mut TactileTopic,
        spec: &ImportSpec,
        kind: ArrayKind,
        data: &[u8],
        scratch: &mut Vec<f64>,
    ) -> Result<(), SessionError> {
        let (file, topic, t) = (self.file, self.topic, self.t);
        let at = |m: String| self.error(m);
        cdr::decode_multiarray(data, kind, scratch).map_err(|e| self.undecoded(e))?;
        if tt.stamps.last().is_some_and(|&last| t < last) {
            return Err(backwards(file, topic, t, tt.stamps[tt.stamps.len() - 1]));
        }
        if scratch.len() != tt.width {
            return Err(at(length_message(spec, tt, scratch.len())));
        }
        if let Some(k) = scratch.iter().position(|v| !v.is_finite()) {
            return Err(at(format!(
                "value {k} is {}, not a finite number",
                scratch[k]
            )));
        }
        for &s in &tt.sensors {
            let sensor = &spec.sensors[s];
            let range = sensor.range_in_message();
            let start = range.start;
            if let Some(k) = scratch[range]
                .iter()
                .position(|&v| !sensor.sensor.in_range(v))
            {
                return Err(at(format!(
                    "sensor `{}` taxel {k} reads {}, outside its range {}",
                    sensor.sensor.name,
                    scratch[start + k],
                    sensor.sensor.range_text()
                )));
            }
        }
        tt.stamps.push(t);
        tt.values.extend_from_slice(scratch);
        Ok(())
    }

    /// A JointState: the position of each named joint (`names`), finite. Without a joint
    /// topic (`jt` none) the message is only checked to decode.
    pub(super) fn joint_state(
        &self,
        jt: Option<&mut JointTopic>,
        names: &[String],
        data: &[u8],
    ) -> Result<(), SessionError> {
        let (file, topic, t) = (self.file, self.topic, self.t);
        let at = |m: String| self.error(m);
        let js = cdr::decode_joint_state(data).map_err(|e| self.undecoded(e))?;
        if js.positions.len() != js.names.len() {
            return Err(at(format!(
                "{} joint names but {} positions",
                js.names.len(),
                js.positions.len()
            )));
        }
        let Some(jt) = jt else {
            return Ok(());
        };
        if jt.stamps.last().is_some_and(|&last| t < last) {
            return Err(backwards(file, topic, t, jt.stamps[jt.stamps.len() - 1]));
        }
        for name in names {
            let Some(k) = js.names.iter().position(|n| n == name) else {
                return Err(at(format!(
                    "joint `{name}` is not in the message (it has: {})",
                    js.names.join(", ")
                )));
            };
            let v = js.positions[k];
            if !v.is_finite() {
                return Err(at(format!("joint `{name}` is at {v}, not a finite number")));
            }
            jt.values.push(v);
        }
        jt.stamps.push(t);
        Ok(())
    }

    /// A String of the events topic: its text at its time.
    pub(super) fn event(
        &self,
        events: &mut Vec<(u64, String)>,
        data: &[u8],
    ) -> Result<(), SessionError> {
        let (file, topic, t) = (self.file, self.topic, self.t);
        let text = cdr::decode_string(data).map_err(|e| self.undecoded(e))?;
        if events.last().is_some_and(|&(last, _)| t < last) {
            let last = events[events.len() - 1].0;
            return Err(backwards(file, topic, t, last));
        }
        events.push((t, text.to_string()));
        Ok(())
    }
}
fn backwards(file: &Path, topic: &str, t: u64, last: u64) -> SessionError {
    SessionError::topic(
        file,
        topic,
        Some(t),
        format!(
            "time goes backwards: the previous message was at {} s",
            crate::session::error::bag_time(last)
        ),
    )
}

/// Why a MultiArray's length does not fit the spec's sensors on its topic.
fn length_message(spec: &ImportSpec, tt: &TactileTopic, got: usize) -> String {
    let parts: Vec<String> = tt
        .sensors
        .iter()
        .map(|&s| {
            let sensor = &spec.sensors[s];
            let r = sensor.range_in_message();
            format!(
                "`{}` ({} taxels at {}..{})",
                sensor.sensor.name,
                sensor.sensor.layout.taxel_count(),
                r.start,
                r.end
            )
        })
        .collect();
    format!(
        "the array holds {got} values, but the spec's layout{} {} read{} {}",
        if parts.len() > 1 { "s" } else { "" },
        parts.join(" and "),
        if parts.len() > 1 { "" } else { "s" },
        tt.width
    )
}
