//! `live`: read a robot's stream (Foxglove WebSocket protocol), print a line per grasp with
//! the model's verdict, record the grasps; `serve`: publish a recorded session as such a
//! stream on the Foxglove SDK's server (with the `serve` feature).

use std::io::BufRead;
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;

use crate::live::client::State;
use crate::live::{Live, LiveOptions, Snapshot};
use crate::session::ImportSpec;

#[derive(Args, Debug)]
pub struct LiveArgs {
    /// The server, e.g. ws://127.0.0.1:8765 (foxglove_bridge, a Foxglove SDK server,
    /// `tactile-workbench serve`).
    pub url: String,
    /// The import spec naming the topics (as for bags; `docs/live.md`).
    #[arg(long)]
    pub spec: PathBuf,
    /// A model file (`fit`): its verdict on each grasp.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Teach the model with each labelled grasp (DS, GS, DU, GU), saving it after each.
    #[arg(long, requires = "model")]
    pub teach: bool,
    /// Record the grasps to this session file (each appended to its journal as it ends).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Stop after this many seconds (default: run until interrupted).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Cut grasps by hand: each line of standard input is `start:OBJECT`, `key` or
    /// `end:LABELS` (under contact cutting, `label:OBJECT[:LABELS]` for the next grasp).
    #[arg(long)]
    pub by_hand: bool,
}

#[derive(Args, Debug)]
pub struct ServeArgs {
    /// The session to publish.
    pub session: PathBuf,
    /// Speed-up over the recording's own time.
    #[arg(long, default_value_t = 1.0)]
    pub rate: f64,
    /// The port (0: any free one, printed).
    #[arg(long, default_value_t = 8765)]
    pub port: u16,
    /// The address to listen on.
    #[arg(long, default_value = "127.0.0.1")]
    pub host: String,
    /// Write the import spec that reads the stream back (for `live --spec`).
    #[arg(long)]
    pub write_spec: Option<PathBuf>,
}

fn state_line(s: &Snapshot) -> String {
    match &s.status.state {
        State::Connecting => "connecting".into(),
        State::Connected {
            server,
            subprotocol,
        } => format!("connected to `{server}` ({subprotocol})"),
        State::Reconnecting { attempt, error } => {
            format!("reconnecting (attempt {attempt}): {error}")
        }
        State::Stopped => "stopped".into(),
    }
}

pub fn live(a: LiveArgs) -> anyhow::Result<()> {
    if let Some(out) = &a.record {
        let mut inputs = vec![a.spec.as_path()];
        inputs.extend(a.model.as_deref());
        super::refuse_input_as_output(Some(out), &inputs)?;
    }
    if let Some(d) = a.duration
        && !(d.is_finite() && d > 0.0)
    {
        anyhow::bail!("--duration {d} is not a positive number of seconds");
    }
    let spec = ImportSpec::load(&a.spec)?;
    let mut live = Live::start(LiveOptions {
        url: a.url.clone(),
        spec,
        by_hand: a.by_hand,
        model: a.model.clone().map(|m| (m, a.teach)),
        record: a.record.clone(),
        trace_seconds: 10.0,
    })
    .with_context(|| format!("starting the live stream from {}", a.url))?;
    let commands = a.by_hand.then(|| {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        rx
    });
    let deadline = a
        .duration
        .map(|d| Instant::now() + Duration::from_secs_f64(d));
    let snapshot = live.snapshot();
    let mut last_state = String::new();
    while deadline.is_none_or(|d| Instant::now() < d) {
        for r in live.step(Duration::from_millis(50)) {
            println!("{}", r.line());
        }
        if let Some(rx) = &commands {
            while let Ok(line) = rx.try_recv() {
                match live.by_hand(&line) {
                    Ok(Some(r)) => println!("{}", r.line()),
                    Ok(None) => {}
                    Err(e) => eprintln!("`{line}`: {e}"),
                }
            }
        }
        let state = state_line(&crate::live::client::lock(&snapshot));
        if state != last_state {
            eprintln!("{state}");
            last_state = state;
        }
    }
    let (reports, s) = live.finish();
    for r in reports {
        println!("{}", r.line());
    }
    let st = &s.status;
    eprintln!(
        "{} grasps{}; {} messages, {} malformed{}, {} frames left out, {} reconnects, \
         {} queue waits",
        s.grasps,
        a.record
            .as_ref()
            .map(|p| format!(", {} recorded to {}", s.recorded, p.display()))
            .unwrap_or_default(),
        st.messages,
        st.malformed,
        st.last_malformed
            .as_ref()
            .map(|m| format!(" (last: {m})"))
            .unwrap_or_default(),
        s.left_out,
        st.reconnects,
        st.waits
    );
    for r in &st.refused {
        eprintln!("refused {r}");
    }
    if let Some(f) = &s.failed {
        anyhow::bail!("{f}");
    }
    Ok(())
}

#[cfg(feature = "serve")]
pub fn serve(a: ServeArgs) -> anyhow::Result<()> {
    use crate::live::publish::Stream;
    use crate::live::serve::Server;
    use std::sync::atomic::AtomicBool;

    if let Some(out) = &a.write_spec {
        super::refuse_input_as_output(Some(out), &[a.session.as_path()])?;
    }
    let session = crate::session::open(&a.session)
        .with_context(|| format!("opening {}", a.session.display()))?;
    let stream = Stream::new(&session, a.rate)?;
    if let Some(out) = &a.write_spec {
        let text = serde_json::to_string_pretty(&stream.spec())?;
        crate::fsutil::write_atomic(out, text.as_bytes())?;
        println!("wrote {}", out.display());
    }
    let mut server = Server::start(&a.host, a.port, &stream.topics)?;
    println!(
        "serving {} grasps of {} on ws://{}:{} at {}×; waiting for a client",
        session.grasps.len(),
        a.session.display(),
        a.host,
        server.port(),
        a.rate
    );
    let never = AtomicBool::new(false);
    server.wait_for_subscriptions(stream.topics.len(), &never);
    server.play(&stream, 0..session.grasps.len(), &never, |g| {
        println!("grasp {} of {}", g + 1, session.grasps.len());
    });
    server.stop();
    Ok(())
}

#[cfg(not(feature = "serve"))]
pub fn serve(_: ServeArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "this build has no Foxglove server: build with `--features serve` \
         (cargo build --release --features serve)"
    )
}
