//! Serving a session on the Foxglove SDK's own WebSocket server (the `foxglove` crate,
//! behind the `serve` feature): each topic of a [`Stream`] a channel of its own context,
//! messages published at their time of the stream, their log time the wall clock at
//! which the stream had them due. Only this file knows the SDK.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};

use super::LiveError;
use super::publish::{Message, Stream, Topic};

/// Counts the channels clients subscribe to, so that playing waits for a subscriber.
#[derive(Default)]
struct Subscriptions(AtomicUsize);

impl ServerListener for Subscriptions {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.fetch_add(1, Ordering::SeqCst);
    }
    fn on_unsubscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A running server with a channel per topic.
pub struct Server {
    handle: Option<foxglove::WebSocketServerHandle>,
    channels: Vec<Arc<RawChannel>>,
    subscriptions: Arc<Subscriptions>,
    /// The channels' context: the channels and the server hold it weakly only.
    _context: Arc<Context>,
    /// The wall clock (ns) of the stream's start; set when playing starts.
    origin: u64,
}

impl Server {
    /// Start on 127.0.0.1 (or `host`) at `port` (0: any free port).
    pub fn start(host: &str, port: u16, topics: &[Topic]) -> Result<Server, LiveError> {
        let ctx = Context::new();
        let channels = topics
            .iter()
            .map(|t| {
                ChannelBuilder::new(&t.name)
                    .context(&ctx)
                    .message_encoding("cdr")
                    .schema(Schema::new(
                        t.schema_name,
                        "ros2msg",
                        t.definition.as_bytes().to_vec(),
                    ))
                    .build_raw()
                    .map_err(|e| LiveError::serve_channel(&t.name, e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let subscriptions = Arc::new(Subscriptions::default());
        let handle = WebSocketServer::new()
            .name("tactile-workbench serve")
            .context(&ctx)
            .listener(subscriptions.clone())
            .bind(host, port)
            .start_blocking()
            .map_err(|e| LiveError::serve_start(host, port, e))?;
        Ok(Server {
            handle: Some(handle),
            channels,
            subscriptions,
            _context: ctx,
            origin: 0,
        })
    }

    pub fn port(&self) -> u16 {
        self.handle.as_ref().map_or(0, |h| h.port())
    }

    /// Channel subscriptions held by clients.
    pub fn subscriptions(&self) -> usize {
        self.subscriptions.0.load(Ordering::SeqCst)
    }

    /// Wait until clients hold at least `n` subscriptions, or `stop` is set.
    pub fn wait_for_subscriptions(&self, n: usize, stop: &AtomicBool) {
        while self.subscriptions() < n && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Publish `m` when it is due: the stream started at `origin` (ns, wall clock).
    fn publish(&self, m: &Message, started: Instant) {
        let due = started + Duration::from_nanos(m.at);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        if let Some(c) = self.channels.get(m.topic) {
            c.log_with_meta(
                &m.data,
                PartialMetadata {
                    log_time: Some(self.origin + m.at),
                },
            );
        }
    }

    /// Play grasps `grasps` of `stream` in real time (at the stream's rate), calling
    /// `each` after each grasp; stops early when `stop` is set.
    pub fn play(
        &mut self,
        stream: &Stream,
        grasps: std::ops::Range<usize>,
        stop: &AtomicBool,
        mut each: impl FnMut(usize),
    ) {
        let mut at = 0;
        // A grasp's messages are made when the previous grasp's are all published: that
        // grasp is then done.
        let mut done = None;
        let messages = grasps.flat_map(|g| {
            if let Some(d) = done.replace(g) {
                each(d);
            }
            let (messages, next) = stream.grasp(g, at);
            at = next;
            messages
        });
        self.play_messages(messages, stop);
        if let Some(d) = done
            && !stop.load(Ordering::Relaxed)
        {
            each(d);
        }
    }

    /// Publish `messages` (in time order, made as they are due) in real time from now, as
    /// [`Server::play`] does; returns how many were published before `stop` was set.
    pub fn play_messages(
        &mut self,
        messages: impl IntoIterator<Item = Message>,
        stop: &AtomicBool,
    ) -> usize {
        let started = Instant::now();
        self.origin = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let mut published = 0;
        for m in messages {
            if stop.load(Ordering::Relaxed) {
                break;
            }
            self.publish(&m, started);
            published += 1;
        }
        published
    }

    /// Stop the server and wait for it to close its connections.
    pub fn stop(mut self) {
        if let Some(h) = self.handle.take() {
            h.stop().wait_blocking();
        }
    }
}
