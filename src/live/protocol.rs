//! The Foxglove WebSocket protocol's wire format, as the client needs it (reference: the
//! foxglove-sdk repository, `rust/foxglove/src/protocol/`; its written spec was retired).
//!
//! - Text frames are JSON objects tagged by `op`. The server sends `serverInfo`,
//!   `advertise` (channels: `id`, `topic`, `encoding`, `schemaName`, `schemaEncoding`,
//!   `schema`), `unadvertise` (`channelIds`) and `status` (`level` 0/1/2, `message`); the
//!   client sends `subscribe` and `unsubscribe`. Other ops are passed over.
//! - Binary frames start with an opcode; `0x01` is message data: `u32` subscription id,
//!   `u64` log time in ns, then the payload, little-endian. Other opcodes are passed over.

use serde::Deserialize;

use super::LiveError;
use crate::error::Kept;

/// The subprotocols the client offers: the SDK and foxglove_bridge ≥ 3.2 accept only the
/// first, older servers only the second.
pub const SUBPROTOCOLS: [&str; 2] = ["foxglove.sdk.v1", "foxglove.websocket.v1"];
/// The subprotocols as the handshake's header offers them (a constant header cannot be
/// malformed).
pub const OFFERED: &str = "foxglove.sdk.v1, foxglove.websocket.v1";

/// A channel as the server advertises it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Channel {
    pub id: u64,
    pub topic: String,
    pub encoding: String,
    #[serde(default)]
    pub schema_name: String,
    #[serde(default)]
    pub schema_encoding: Option<String>,
    #[serde(default)]
    pub schema: String,
}

/// A text message from the server.
#[derive(Clone, Debug, PartialEq)]
pub enum ServerText {
    ServerInfo {
        name: String,
    },
    Advertise(Vec<Channel>),
    Unadvertise(Vec<u64>),
    Status {
        level: u8,
        message: String,
    },
    /// An op the client has no use for (parameters, services, time, …).
    Other(String),
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct Op {
    op: String,
}

#[derive(Deserialize)]
struct ServerInfo {
    #[serde(default)]
    name: String,
}

#[derive(Deserialize)]
struct Advertise {
    channels: Vec<Channel>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct Unadvertise {
    channel_ids: Vec<u64>,
}

#[derive(Deserialize)]
struct Status {
    level: u8,
    message: String,
}

/// Parse a text frame; the error says which op was malformed and why.
pub fn parse_text(text: &str) -> Result<ServerText, LiveError> {
    let op: Op = serde_json::from_str(text).map_err(|e| LiveError::NotAnOp(Kept::new(e)))?;
    let bad = |e: serde_json::Error| LiveError::MalformedOp {
        op: op.op.clone(),
        source: Kept::new(e),
    };
    Ok(match op.op.as_str() {
        "serverInfo" => ServerText::ServerInfo {
            name: serde_json::from_str::<ServerInfo>(text).map_err(bad)?.name,
        },
        "advertise" => ServerText::Advertise(
            serde_json::from_str::<Advertise>(text)
                .map_err(bad)?
                .channels,
        ),
        "unadvertise" => ServerText::Unadvertise(
            serde_json::from_str::<Unadvertise>(text)
                .map_err(bad)?
                .channel_ids,
        ),
        "status" => {
            let s: Status = serde_json::from_str(text).map_err(bad)?;
            ServerText::Status {
                level: s.level,
                message: s.message,
            }
        }
        _ => ServerText::Other(op.op),
    })
}

/// The opcode of message data in a binary frame.
pub const MESSAGE_DATA: u8 = 0x01;

/// One message of a subscribed channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MessageData<'a> {
    pub subscription: u32,
    pub log_time: u64,
    pub payload: &'a [u8],
}

/// Parse a binary frame: `Ok(None)` for an opcode other than message data.
pub fn parse_binary(frame: &[u8]) -> Result<Option<MessageData<'_>>, LiveError> {
    let Some((&opcode, rest)) = frame.split_first() else {
        return Err(LiveError::EmptyBinary);
    };
    if opcode != MESSAGE_DATA {
        return Ok(None);
    }
    let (Some((id, rest)), true) = (rest.split_first_chunk::<4>(), rest.len() >= 12) else {
        return Err(LiveError::ShortMessageData { len: frame.len() });
    };
    let (time, payload) = rest.split_first_chunk::<8>().unwrap_or((&[0; 8], &[]));
    Ok(Some(MessageData {
        subscription: u32::from_le_bytes(*id),
        log_time: u64::from_le_bytes(*time),
        payload,
    }))
}

/// The `subscribe` op for (subscription id, channel id) pairs.
pub fn subscribe(pairs: &[(u32, u64)]) -> String {
    let subs: Vec<serde_json::Value> = pairs
        .iter()
        .map(|&(id, channel)| serde_json::json!({"id": id, "channelId": channel}))
        .collect();
    serde_json::json!({"op": "subscribe", "subscriptions": subs}).to_string()
}

/// The `unsubscribe` op for subscription ids.
pub fn unsubscribe(ids: &[u32]) -> String {
    serde_json::json!({"op": "unsubscribe", "subscriptionIds": ids}).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn server_ops_parse() {
        let adv = r#"{"op":"advertise","channels":[{"id":3,"topic":"/tactile/index",
            "encoding":"cdr","schemaName":"std_msgs/msg/Float64MultiArray",
            "schemaEncoding":"ros2msg","schema":"float64[] data"}]}"#;
        let ServerText::Advertise(channels) = parse_text(adv).unwrap() else {
            panic!("not an advertise")
        };
        assert_eq!(channels[0].id, 3);
        assert_eq!(channels[0].schema_encoding.as_deref(), Some("ros2msg"));
        assert_eq!(
            parse_text(r#"{"op":"unadvertise","channelIds":[3,4]}"#).unwrap(),
            ServerText::Unadvertise(vec![3, 4])
        );
        assert_eq!(
            parse_text(r#"{"op":"status","level":2,"message":"oops"}"#).unwrap(),
            ServerText::Status {
                level: 2,
                message: "oops".into()
            }
        );
        assert_eq!(
            parse_text(r#"{"op":"serverInfo","name":"sdk","capabilities":[]}"#).unwrap(),
            ServerText::ServerInfo { name: "sdk".into() }
        );
        assert_eq!(
            parse_text(r#"{"op":"time"}"#).unwrap(),
            ServerText::Other("time".into())
        );
        let err = parse_text(r#"{"op":"advertise","channels":[{"id":"x"}]}"#).unwrap_err();
        assert!(
            matches!(&err, LiveError::MalformedOp { op, .. } if op == "advertise"),
            "{err:?}"
        );
        assert!(err.to_string().contains("`advertise`"), "{err}");
        assert!(matches!(parse_text("not json"), Err(LiveError::NotAnOp(_))));
    }

    #[test]
    fn message_data_is_little_endian() {
        let mut frame = vec![MESSAGE_DATA];
        frame.extend(7u32.to_le_bytes());
        frame.extend(1_700_000_000_123_456_789u64.to_le_bytes());
        frame.extend([9, 8, 7]);
        let m = parse_binary(&frame).unwrap().unwrap();
        assert_eq!(m.subscription, 7);
        assert_eq!(m.log_time, 1_700_000_000_123_456_789);
        assert_eq!(m.payload, &[9, 8, 7]);
        assert_eq!(
            parse_binary(&frame[..12]),
            Err(LiveError::ShortMessageData { len: 12 })
        );
        assert_eq!(parse_binary(&[]), Err(LiveError::EmptyBinary));
        assert_eq!(parse_binary(&[0x02, 0, 0]).unwrap(), None);
    }

    #[test]
    fn the_header_offers_every_subprotocol() {
        assert_eq!(OFFERED, SUBPROTOCOLS.join(", "));
    }

    #[test]
    fn subscribe_names_channel_ids() {
        let v: serde_json::Value = serde_json::from_str(&subscribe(&[(1, 40)])).unwrap();
        assert_eq!(v["op"], "subscribe");
        assert_eq!(v["subscriptions"][0]["channelId"], 40);
        assert_eq!(v["subscriptions"][0]["id"], 1);
    }
}
