//! The stream's socket thread: connects with both subprotocols offered, subscribes to the
//! channels the spec reads as they are advertised, decodes their messages and hands them
//! on through a bounded queue. When the server goes away it reconnects with back-off,
//! subscribing again; the status says what it is doing.
//!
//! The queue is bounded and the thread waits when it is full: the recording never loses a
//! message to overload (TCP then slows the server, which may drop for slow clients as its
//! own policy says); the waits are counted. A malformed message (bad frame, bad CDR, wrong
//! length, unknown schema) is counted with its reason and skipped, never a panic.

use std::collections::HashMap;
use std::io::ErrorKind;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tungstenite::client::IntoClientRequest;
use tungstenite::handshake::HandshakeError;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

use crate::error::Kept;

use super::LiveError;
use super::channels::{Plan, Route, Sample};
use super::protocol::{self, Channel, OFFERED, SUBPROTOCOLS, ServerText};

/// Messages the queue holds before the socket thread waits.
pub const QUEUE: usize = 4096;
/// How often the socket thread looks at its stop flag while the stream is quiet.
const POLL: Duration = Duration::from_millis(20);
/// Reconnect back-off: from the first to the last, doubling.
const BACKOFF: (Duration, Duration) = (Duration::from_millis(50), Duration::from_millis(800));
/// How long the handshake waits for the server's answer.
const HANDSHAKE: Duration = Duration::from_secs(2);

/// A decoded message of a subscribed channel, at its log time (ns).
#[derive(Clone, Debug, PartialEq)]
pub struct Incoming {
    pub t: u64,
    pub sample: Sample,
}

/// The connection's state.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum State {
    #[default]
    Connecting,
    /// Connected to the server of this name with this subprotocol.
    Connected {
        server: String,
        subprotocol: String,
    },
    /// Lost (or never made); the next attempt is under way after back-off.
    Reconnecting {
        attempt: u32,
        error: LiveError,
    },
    Stopped,
}

/// What the socket thread counts and last saw; read by the engine and the window.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClientStatus {
    pub state: State,
    /// Messages of subscribed channels decoded, malformed, and refused channels.
    pub messages: u64,
    pub malformed: u64,
    pub last_malformed: Option<LiveError>,
    /// Channels of the spec's topics whose type or definition does not fit.
    pub refused: Vec<LiveError>,
    /// Times the queue was full and the thread waited for the engine.
    pub waits: u64,
    pub reconnects: u64,
    /// The server's latest `status` message: level (0 info, 1 warning, 2 error) and text.
    pub server_status: Option<(u8, String)>,
    /// Topics subscribed on the current connection.
    pub subscribed: Vec<String>,
}

/// The socket thread and the queue it fills.
pub struct Client {
    pub queue: Receiver<Incoming>,
    pub status: Arc<Mutex<ClientStatus>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Client {
    /// Start the socket thread on `url` (`ws://HOST:PORT`), reading what `plan` names.
    pub fn start(url: &str, plan: Plan) -> Client {
        let (tx, rx) = sync_channel(QUEUE);
        let status = Arc::new(Mutex::new(ClientStatus::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (url, status, stop) = (url.to_string(), status.clone(), stop.clone());
            std::thread::Builder::new()
                .name("live-socket".into())
                .spawn(move || run(&url, &plan, &tx, &status, &stop))
                .ok()
        };
        Client {
            queue: rx,
            status,
            stop,
            thread,
        }
    }

    pub fn status(&self) -> ClientStatus {
        lock(&self.status).clone()
    }

    /// Stop the socket thread and wait for it (its queue keeps what it had sent).
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        lock(&self.status).state = State::Stopped;
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        self.stop();
    }
}

pub(crate) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Connect, read until the connection ends, and again after back-off, until stopped.
fn run(
    url: &str,
    plan: &Plan,
    tx: &SyncSender<Incoming>,
    status: &Mutex<ClientStatus>,
    stop: &AtomicBool,
) {
    let mut attempt = 0u32;
    let mut delay = BACKOFF.0;
    while !stop.load(Ordering::Relaxed) {
        let error = match connect(url) {
            Ok((ws, subprotocol)) => {
                if attempt > 0 {
                    lock(status).reconnects += 1;
                }
                attempt = 0;
                delay = BACKOFF.0;
                {
                    let mut s = lock(status);
                    s.state = State::Connected {
                        server: String::new(),
                        subprotocol,
                    };
                    s.subscribed.clear();
                }
                match Connection::new(ws, plan).read(tx, status, stop) {
                    Ok(()) => break,
                    Err(e) => e,
                }
            }
            Err(e) => e,
        };
        if stop.load(Ordering::Relaxed) {
            break;
        }
        attempt += 1;
        lock(status).state = State::Reconnecting { attempt, error };
        let until = Instant::now() + delay;
        while Instant::now() < until && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(POLL.min(until.saturating_duration_since(Instant::now())));
        }
        delay = (delay * 2).min(BACKOFF.1);
    }
    lock(status).state = State::Stopped;
}

/// The handshake, both subprotocols offered; the socket then reads with a short timeout so
/// that the thread sees its stop flag.
pub(crate) fn connect(url: &str) -> Result<(WebSocket<TcpStream>, String), LiveError> {
    let mut request = url.into_client_request().map_err(|e| LiveError::Address {
        url: url.to_string(),
        source: Kept::new(e),
    })?;
    request
        .headers_mut()
        .insert("Sec-WebSocket-Protocol", HeaderValue::from_static(OFFERED));
    let uri = request.uri();
    if uri.scheme_str() != Some("ws") {
        return Err(LiveError::NotWs {
            url: url.to_string(),
        });
    }
    let host = uri.host().unwrap_or_default().trim_matches(['[', ']']);
    let port = uri.port_u16().unwrap_or(80);
    let addr: SocketAddr = (host, port)
        .to_socket_addrs()
        .map_err(|e| LiveError::Resolve {
            host: host.to_string(),
            port,
            source: Kept::new(e),
        })?
        .next()
        .ok_or_else(|| LiveError::NoAddress {
            host: host.to_string(),
            port,
        })?;
    let io = |e: std::io::Error| LiveError::Socket {
        addr,
        source: Kept::new(e),
    };
    let stream = TcpStream::connect_timeout(&addr, Duration::from_secs(1)).map_err(io)?;
    stream.set_nodelay(true).map_err(io)?;
    stream.set_read_timeout(Some(HANDSHAKE)).map_err(io)?;
    let (ws, response) = tungstenite::client(request, stream).map_err(|e| match e {
        HandshakeError::Failure(e) => LiveError::Handshake {
            addr,
            source: Kept::new(e),
        },
        // The blocking socket's read timeout, mid-handshake.
        HandshakeError::Interrupted(_) => LiveError::HandshakeTimeout {
            addr,
            waited: HANDSHAKE,
        },
    })?;
    let subprotocol = response
        .headers()
        .get("Sec-WebSocket-Protocol")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string();
    if !SUBPROTOCOLS.contains(&subprotocol.as_str()) {
        return Err(LiveError::Subprotocol {
            addr,
            chosen: subprotocol,
        });
    }
    ws.get_ref().set_read_timeout(Some(POLL)).map_err(io)?;
    Ok((ws, subprotocol))
}

/// One connection's channels and subscriptions (ids are per connection).
struct Connection<'p> {
    ws: WebSocket<TcpStream>,
    plan: &'p Plan,
    /// Subscription id → the channel's topic and how its messages are read.
    subscriptions: HashMap<u32, (String, Route)>,
    /// Channel id → subscription id.
    by_channel: HashMap<u64, u32>,
    next: u32,
}

impl<'p> Connection<'p> {
    fn new(ws: WebSocket<TcpStream>, plan: &'p Plan) -> Connection<'p> {
        Connection {
            ws,
            plan,
            subscriptions: HashMap::new(),
            by_channel: HashMap::new(),
            next: 1,
        }
    }

    /// Read until the thread is stopped, or the connection ends (why it ended).
    fn read(
        mut self,
        tx: &SyncSender<Incoming>,
        status: &Mutex<ClientStatus>,
        stop: &AtomicBool,
    ) -> Result<(), LiveError> {
        while !stop.load(Ordering::Relaxed) {
            let message = match self.ws.read() {
                Ok(m) => m,
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                {
                    continue;
                }
                Err(e) => return Err(LiveError::Ended(Kept::new(e))),
            };
            match message {
                Message::Text(text) => self.text(text.as_str(), status)?,
                Message::Binary(bytes) => self.binary(&bytes, tx, status, stop)?,
                Message::Close(_) => return Err(LiveError::Closed),
                _ => {}
            }
        }
        let _ = self.ws.close(None);
        let _ = self.ws.flush();
        Ok(())
    }

    fn malformed(status: &Mutex<ClientStatus>, why: LiveError) {
        let mut s = lock(status);
        s.malformed += 1;
        s.last_malformed = Some(why);
    }

    /// A JSON op: channels advertised are subscribed when the spec reads their topic.
    fn text(&mut self, text: &str, status: &Mutex<ClientStatus>) -> Result<(), LiveError> {
        match protocol::parse_text(text) {
            Err(why) => Self::malformed(status, why),
            Ok(ServerText::ServerInfo { name }) => {
                if let State::Connected { server, .. } = &mut lock(status).state {
                    *server = name;
                }
            }
            Ok(ServerText::Advertise(channels)) => self.advertise(&channels, status)?,
            Ok(ServerText::Unadvertise(ids)) => {
                let mut s = lock(status);
                for id in ids {
                    if let Some(sub) = self.by_channel.remove(&id)
                        && let Some((topic, _)) = self.subscriptions.remove(&sub)
                    {
                        s.subscribed.retain(|t| *t != topic);
                    }
                }
            }
            Ok(ServerText::Status { level, message }) => {
                lock(status).server_status = Some((level, message));
            }
            Ok(ServerText::Other(_)) => {}
        }
        Ok(())
    }

    fn advertise(
        &mut self,
        channels: &[Channel],
        status: &Mutex<ClientStatus>,
    ) -> Result<(), LiveError> {
        let mut pairs = Vec::new();
        for channel in channels {
            if self.by_channel.contains_key(&channel.id) {
                continue;
            }
            match self.plan.route(channel) {
                Ok(Some(route)) => {
                    let id = self.next;
                    self.next += 1;
                    self.subscriptions
                        .insert(id, (channel.topic.clone(), route));
                    self.by_channel.insert(channel.id, id);
                    pairs.push((id, channel.id));
                }
                Ok(None) => {}
                Err(why) => {
                    let mut s = lock(status);
                    if !s.refused.contains(&why) {
                        s.refused.push(why);
                    }
                }
            }
        }
        if pairs.is_empty() {
            return Ok(());
        }
        self.ws
            .send(Message::text(protocol::subscribe(&pairs)))
            .map_err(|e| LiveError::Subscribe(Kept::new(e)))?;
        let mut s = lock(status);
        for (id, _) in pairs {
            if let Some((topic, _)) = self.subscriptions.get(&id) {
                s.subscribed.push(topic.clone());
            }
        }
        Ok(())
    }

    /// Message data: decoded and queued, waiting while the queue is full.
    fn binary(
        &mut self,
        frame: &[u8],
        tx: &SyncSender<Incoming>,
        status: &Mutex<ClientStatus>,
        stop: &AtomicBool,
    ) -> Result<(), LiveError> {
        let data = match protocol::parse_binary(frame) {
            Ok(Some(d)) => d,
            Ok(None) => return Ok(()),
            Err(why) => {
                Self::malformed(status, why);
                return Ok(());
            }
        };
        let Some((topic, route)) = self.subscriptions.get(&data.subscription) else {
            // Messages of a subscription just ended may still arrive.
            return Ok(());
        };
        let sample = match self.plan.decode(route, data.payload) {
            Ok(s) => s,
            Err(why) => {
                Self::malformed(
                    status,
                    LiveError::Message {
                        topic: topic.clone(),
                        source: Kept::new(why),
                    },
                );
                return Ok(());
            }
        };
        lock(status).messages += 1;
        let mut item = Incoming {
            t: data.log_time,
            sample,
        };
        loop {
            match tx.try_send(item) {
                Ok(()) => return Ok(()),
                Err(TrySendError::Full(back)) => {
                    item = back;
                    lock(status).waits += 1;
                    if stop.load(Ordering::Relaxed) {
                        return Ok(());
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(TrySendError::Disconnected(_)) => return Err(LiveError::EngineStopped),
            }
        }
    }
}
