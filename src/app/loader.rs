//! Opening sessions off the UI thread: native files, the BTS3 CSV, the iCub folder,
//! recordings imported with a spec, and the sample sessions bundled into the binary.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};

use serde::{Deserialize, Serialize};

use crate::session::{self, Session};

/// The sample sessions, compiled in so a fresh clone opens them with no other step.
pub const BUNDLED: [(&str, &str); 2] = [
    (
        "grasp-stability.json",
        include_str!("../../sample-sessions/grasp-stability.json"),
    ),
    (
        "object-recognition.json",
        include_str!("../../sample-sessions/object-recognition.json"),
    ),
];

/// Where a session came from (what is persisted to reopen it next time).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Source {
    Bundled(String),
    File(PathBuf),
    /// A ROS 2 bag or long-format CSV read with its import spec.
    Imported {
        recording: PathBuf,
        spec: PathBuf,
    },
}

/// How a project's session list writes an imported recording's spec after its path.
const WITH_SPEC: &str = " with spec ";

impl Source {
    /// The source a `label` names (as a project file lists its sessions).
    pub fn from_label(label: &str) -> Source {
        match label.strip_prefix("sample: ") {
            Some(name) if BUNDLED.iter().any(|(n, _)| *n == name) => {
                Source::Bundled(name.to_string())
            }
            _ => match label.rsplit_once(WITH_SPEC) {
                Some((recording, spec)) => Source::Imported {
                    recording: PathBuf::from(recording),
                    spec: PathBuf::from(spec),
                },
                None => Source::File(PathBuf::from(label)),
            },
        }
    }

    /// Why a project may not open this source, if it may not (see
    /// [`crate::project::session_path_refusal`]); an import spec must not lie in a system
    /// folder either.
    pub fn refusal(&self) -> Option<String> {
        match self {
            Source::Bundled(_) => None,
            Source::File(p) => crate::project::session_path_refusal(p),
            Source::Imported { recording, spec } => crate::project::session_path_refusal(recording)
                .or_else(|| {
                    crate::project::session_path_refusal(spec)
                        .filter(|why| why.contains("system folder"))
                }),
        }
    }

    pub fn label(&self) -> String {
        match self {
            Source::Bundled(name) => format!("sample: {name}"),
            Source::File(p) => p.display().to_string(),
            Source::Imported { recording, spec } => {
                format!("{}{WITH_SPEC}{}", recording.display(), spec.display())
            }
        }
    }
}

/// A session ready to show, with what every view needs precomputed once.
pub struct LoadedSession {
    pub source: Source,
    pub session: Arc<Session>,
    /// Pressure range over the whole session, so colours mean the same in every frame.
    pub pressure_range: (f64, f64),
}

fn pressure_range(s: &Session) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for g in &s.grasps {
        for f in &g.frames {
            for (k, values) in f.taxels.iter().enumerate() {
                for (i, &v) in values.iter().enumerate() {
                    let p = s.pressure(k, i, v);
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        (0.0, 1.0)
    } else if hi - lo < 1e-9 {
        (lo, lo + 1.0)
    } else {
        (lo.min(0.0), hi)
    }
}

/// Read a session from any supported source: a native `.json`, a BTS3 `.csv`, or an iCub
/// dataset folder.
pub fn open(source: &Source) -> Result<LoadedSession, String> {
    let session = match source {
        Source::Bundled(name) => {
            let text = BUNDLED
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, t)| *t)
                .ok_or_else(|| format!("no bundled sample named {name}"))?;
            session::native::from_str(text, Path::new(name)).map_err(|e| e.to_string())?
        }
        Source::File(path) => session::open(path).map_err(|e| e.to_string())?,
        Source::Imported { recording, spec } => {
            session::import_with_spec(recording, spec).map_err(|e| e.to_string())?
        }
    };
    Ok(LoadedSession {
        source: source.clone(),
        pressure_range: pressure_range(&session),
        session: Arc::new(session),
    })
}

/// Loads on a worker thread; the UI polls `try_recv` each frame.
pub struct Loader {
    tx: Sender<(Source, Result<LoadedSession, String>)>,
    rx: Receiver<(Source, Result<LoadedSession, String>)>,
    pub pending: Vec<Source>,
}

impl Default for Loader {
    fn default() -> Self {
        let (tx, rx) = channel();
        Loader {
            tx,
            rx,
            pending: Vec::new(),
        }
    }
}

impl Loader {
    pub fn request(&mut self, source: Source, ctx: &egui::Context) {
        if self.pending.contains(&source) {
            return;
        }
        self.pending.push(source.clone());
        let tx = self.tx.clone();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            // A panic in a parser must not take the window down: report it as an error.
            let result = std::panic::catch_unwind(|| open(&source))
                .unwrap_or_else(|_| Err(format!("{}: the reader crashed", source.label())));
            let _ = tx.send((source, result));
            ctx.request_repaint();
        });
    }

    /// Finished loads since the last call.
    pub fn poll(&mut self) -> Vec<(Source, Result<LoadedSession, String>)> {
        let done: Vec<_> = self.rx.try_iter().collect();
        self.pending.retain(|p| !done.iter().any(|(s, _)| s == p));
        done
    }
}
