//! Why a live stream could not connect, read a message, cut a grasp, or publish a session.
//! A lower error (the socket's, the WebSocket's, the JSON parser's, the session layer's, a
//! model's) is kept as the source; a protocol violation names what was wrong (the channel,
//! the op, the field, the event). The error is `Clone` and `PartialEq` (lower errors held
//! in [`Kept`]) because the status and the grasp reports that carry it are.

use std::net::SocketAddr;
use std::time::Duration;

use crate::error::Kept;
use crate::models::ModelError;
use crate::session::SessionError;
use crate::session::cdr::{ArrayKind, CdrError};
use crate::session::shorten;
use crate::session::spec::LabelError;

use super::protocol::SUBPROTOCOLS;

/// A lower error of any type: the SDK's errors under `serve`, a file that is read and
/// compiled again by the tests without that feature.
type AnyError = Kept<dyn std::error::Error + Send + Sync>;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LiveError {
    // Connecting.
    #[error("`{url}` is not a WebSocket address: {source}")]
    Address {
        url: String,
        #[source]
        source: Kept<tungstenite::Error>,
    },
    #[error("`{url}`: only ws:// is supported (no TLS)")]
    NotWs { url: String },
    #[error("{host}:{port}: {source}")]
    Resolve {
        host: String,
        port: u16,
        #[source]
        source: Kept<std::io::Error>,
    },
    #[error("{host}:{port} resolves to no address")]
    NoAddress { host: String, port: u16 },
    /// The TCP connection or its options.
    #[error("{addr}: {source}")]
    Socket {
        addr: SocketAddr,
        #[source]
        source: Kept<std::io::Error>,
    },
    #[error("the WebSocket handshake with {addr} failed: {source}")]
    Handshake {
        addr: SocketAddr,
        #[source]
        source: Kept<tungstenite::Error>,
    },
    /// The handshake's response did not come before the socket's read timeout.
    #[error("the WebSocket handshake with {addr} failed: no answer within {waited:?}")]
    HandshakeTimeout { addr: SocketAddr, waited: Duration },
    #[error(
        "the server at {addr} chose subprotocol `{chosen}`, not one offered ({})",
        SUBPROTOCOLS.join(", ")
    )]
    Subprotocol { addr: SocketAddr, chosen: String },

    // The connection.
    #[error("the connection ended: {0}")]
    Ended(#[source] Kept<tungstenite::Error>),
    #[error("the server closed the connection")]
    Closed,
    #[error("subscribing failed: {0}")]
    Subscribe(#[source] Kept<tungstenite::Error>),
    /// The engine dropped the queue the socket thread fills.
    #[error("the engine has stopped")]
    EngineStopped,
    /// Discovery's error, with the stream it was reading.
    #[error("{url}: {source}")]
    Discovery {
        url: String,
        #[source]
        source: Kept<LiveError>,
    },
    #[error("{url} advertised no channel within {wait:?}")]
    NoChannel { url: String, wait: Duration },

    // The wire format.
    #[error("a text message is not an op: {0}")]
    NotAnOp(#[source] Kept<serde_json::Error>),
    #[error("a malformed `{op}` message: {source}")]
    MalformedOp {
        op: String,
        #[source]
        source: Kept<serde_json::Error>,
    },
    #[error("an empty binary message")]
    EmptyBinary,
    #[error("message data of {len} bytes, too short for its subscription id and log time")]
    ShortMessageData { len: usize },

    // A channel the spec reads.
    #[error(
        "channel `{topic}`: its schema is `{}`; the spec reads it as {reads}",
        shorten(schema)
    )]
    Schema {
        topic: String,
        schema: String,
        reads: &'static str,
    },
    /// A CDR channel whose message definition is not the one its type has (the bag
    /// importer's check).
    #[error("channel `{topic}`: {source}")]
    Definition {
        topic: String,
        #[source]
        source: CdrError,
    },
    #[error(
        "channel `{topic}`: messages are encoded as `{}`, not cdr or json",
        shorten(encoding)
    )]
    Encoding { topic: String, encoding: String },

    // A message of a routed channel.
    #[error("the JSON message does not parse: {0}")]
    Json(#[source] Kept<serde_json::Error>),
    /// A field of a JSON message, and what it should have been ("a list", "a number").
    #[error("`{field}` is not {expected}")]
    JsonField {
        field: String,
        expected: &'static str,
    },
    /// A CDR message that does not decode (the bag importer's decoder).
    #[error("{0}")]
    Cdr(#[from] CdrError),
    #[error("{names} joint names but {positions} positions")]
    JointCount { names: usize, positions: usize },
    #[error("joint `{joint}` is not in the message (it has: {})", has.join(", "))]
    MissingJoint { joint: String, has: Vec<String> },
    #[error("joint `{joint}` is at {value}, not a finite number")]
    JointNotFinite { joint: String, value: f64 },
    #[error("the channel's type does not fit its role")]
    RoleMismatch,
    /// A message of a subscribed channel that was skipped, and why.
    #[error("channel `{topic}`: {source}")]
    Message {
        topic: String,
        #[source]
        source: Kept<LiveError>,
    },
    /// A tactile row of the wrong length; `layouts` lists the spec's sensors on the topic.
    #[error(
        "the {kind:?} array holds {got} values, but the spec's layouts ({layouts}) read {width}"
    )]
    RowWidth {
        kind: ArrayKind,
        got: usize,
        layouts: String,
        width: usize,
    },
    #[error("value {index} is {value}, not a finite number")]
    NotFinite { index: usize, value: f64 },
    #[error("sensor `{sensor}` taxel {taxel} reads {value}, outside its range {range}")]
    OutOfRange {
        sensor: String,
        taxel: usize,
        value: f64,
        range: String,
    },

    // Cutting grasps: events and commands by hand.
    #[error(
        "`{}`: the stream's events are not used (grasps are cut by {cutting})",
        shorten(event)
    )]
    EventsUnused {
        event: String,
        cutting: &'static str,
    },
    #[error(
        "`{}`: grasps are cut by contact; give `label:OBJECT[:LABELS]`",
        shorten(command)
    )]
    NotALabel { command: String },
    #[error("no frame has arrived yet")]
    NoFrameYet,
    /// An object or labels the import spec refuses.
    #[error("{0}")]
    Spec(#[from] LabelError),
    #[error(
        "a grasp starts while the one started at {} s has not ended",
        crate::session::bag_time(*open_since)
    )]
    StartWhileOpen { open_since: u64 },
    #[error("a second `key` event in one grasp")]
    SecondKey,
    #[error("the grasp of `{}` ended without a frame", shorten(object))]
    EmptyGrasp { object: String },
    #[error("`{}` comes before any `start`", shorten(event))]
    BeforeStart { event: String },
    #[error(
        "`{}` is not an event: expected start:OBJECT, key or end:LABELS",
        shorten(event)
    )]
    NotAnEvent { event: String },

    // A completed grasp.
    /// The grasp as a session of one grasp, or its recording.
    #[error("{0}")]
    Session(#[from] SessionError),
    /// The model's verdict on a grasp, or its teaching.
    #[error("{0}")]
    Model(#[source] Kept<ModelError>),

    // Publishing a session.
    #[error("--rate {rate} is not a positive speed-up")]
    Rate { rate: f64 },
    #[error(
        "class `{}` of label set `{set}` holds `,` `:` or a line break, which an event cannot carry",
        shorten(class)
    )]
    EventUnsafeClass { class: String, set: String },
    #[error("two sensors share the topic `{topic}`; rename one")]
    SharedTopic { topic: String },
    #[error("channel `{topic}`: {source}")]
    ServeChannel {
        topic: String,
        #[source]
        source: AnyError,
    },
    #[error("the server on {host}:{port} did not start: {source}")]
    ServeStart {
        host: String,
        port: u16,
        #[source]
        source: AnyError,
    },
}

impl From<ModelError> for LiveError {
    fn from(e: ModelError) -> Self {
        LiveError::Model(Kept::new(e))
    }
}

impl LiveError {
    /// A channel the SDK's server refused (its error kept).
    pub fn serve_channel(topic: &str, e: impl std::error::Error + Send + Sync + 'static) -> Self {
        LiveError::ServeChannel {
            topic: topic.to_string(),
            source: Kept::any(e),
        }
    }

    /// The SDK's server that did not start (its error kept).
    pub fn serve_start(
        host: &str,
        port: u16,
        e: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        LiveError::ServeStart {
            host: host.to_string(),
            port,
            source: Kept::any(e),
        }
    }
}
