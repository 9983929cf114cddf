//! A recording that grows a grasp at a time (`live --record OUT.json`): an append journal
//! beside it, `OUT.json.journal`, while it is written.
//!
//! The journal is JSON lines: the first the session's header (its grasps empty) with the
//! writer's process id, each further line one completed grasp as the recording holds it.
//! A grasp is one append and one fsync, so writing is linear in the grasps, and a kill -9
//! loses at most the grasp being written (a last line cut short is left out). When
//! recording ends, the journal's session is written to `OUT.json` atomically and the
//! journal removed ([`finalise`]). Loading `OUT.json` ([`super::load`]) looks for
//! the journal first: one whose writer is gone (killed) is finalised then, one whose writer
//! still runs is read as it stands, so the recording opens as a normal session at any
//! moment.
//!
//! The object label set grows as objects appear: the header holds the classes known at the
//! first grasp, and a grasp of a new object adds it at the end, as the recorder does.

use std::fs::{self, File, OpenOptions};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{FORMAT_VERSION, Grasp, OBJECT, Session, SessionError, native, validate};
use crate::fsutil;

pub const JOURNAL_TAG: &str = "tactile-workbench-recording-journal";

/// The journal of the recording at `recording`.
pub fn journal_path(recording: &Path) -> PathBuf {
    let mut name = recording.file_name().unwrap_or_default().to_os_string();
    name.push(".journal");
    recording.with_file_name(name)
}

#[derive(Serialize, Deserialize)]
struct Head {
    format: String,
    version: u32,
    /// The writing process: while it runs, the journal is read and left as it is.
    pid: u32,
    session: Session,
}

/// A journal being written.
pub struct Journal {
    path: PathBuf,
    file: File,
    /// Bytes written so far (header included): one line per grasp, nothing rewritten.
    pub written: u64,
}

impl Journal {
    /// Start the journal of `recording` with `header`'s meta, sensors, encoders and label
    /// sets (its grasps are not written). An existing journal is an unfinished recording
    /// and is refused, never overwritten.
    pub fn create(recording: &Path, header: &Session) -> Result<Journal, SessionError> {
        let path = journal_path(recording);
        let io = |e: std::io::Error| SessionError::io(&path, e);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::AlreadyExists => unfinished(&path),
                _ => io(e),
            })?;
        let head = Head {
            format: JOURNAL_TAG.into(),
            version: FORMAT_VERSION,
            pid: std::process::id(),
            session: Session {
                grasps: Vec::new(),
                ..header.clone()
            },
        };
        let mut journal = Journal {
            path: path.clone(),
            file,
            written: 0,
        };
        journal.line(&serde_json::to_string(&head).unwrap_or_default())?;
        // The journal's name survives a power cut too.
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            let _ = File::open(dir).and_then(|d| d.sync_all());
        }
        Ok(journal)
    }

    /// Append a completed grasp (labelled as the recording holds it) and fsync.
    pub fn append(&mut self, grasp: &Grasp) -> Result<(), SessionError> {
        self.line(&native::grasp_line(grasp))
    }

    fn line(&mut self, text: &str) -> Result<(), SessionError> {
        let mut bytes = Vec::with_capacity(text.len() + 1);
        bytes.extend_from_slice(text.as_bytes());
        bytes.push(b'\n');
        self.file
            .write_all(&bytes)
            .and_then(|()| self.file.sync_data())
            .map_err(|e| SessionError::io(&self.path, e))?;
        self.written += bytes.len() as u64;
        Ok(())
    }
}

fn unfinished(journal: &Path) -> SessionError {
    SessionError::file(
        journal,
        "an unfinished recording is here (its writer was stopped before the end): open the \
         recording to finish it, or move the journal away, before recording to this file again",
    )
}

/// Refuse a recording to `recording` while a journal of an earlier one lies beside it.
pub fn check_free(recording: &Path) -> Result<(), SessionError> {
    let path = journal_path(recording);
    if path.exists() {
        return Err(unfinished(&path));
    }
    Ok(())
}

/// The session a journal holds: the header and every complete grasp line, validated.
pub fn read(journal: &Path) -> Result<(Session, u32), SessionError> {
    let mut reader = fsutil::open_json(journal, fsutil::max_bytes::SESSION, "recording journal")
        .map_err(|e| SessionError::io(journal, e))?;
    let mut text = String::new();
    let mut next = |text: &mut String| -> Result<Option<bool>, SessionError> {
        text.clear();
        let n = reader
            .read_line(text)
            .map_err(|e| SessionError::io(journal, e))?;
        Ok((n > 0).then(|| text.ends_with('\n')))
    };
    let json = |line: usize, e: serde_json::Error| SessionError::line(journal, line, e.to_string());
    let head: Head = match next(&mut text)? {
        Some(true) => serde_json::from_str(&text).map_err(|e| json(1, e))?,
        _ => {
            return Err(SessionError::file(
                journal,
                "the journal has no header line",
            ));
        }
    };
    if head.format != JOURNAL_TAG || head.version != FORMAT_VERSION {
        return Err(SessionError::field(
            journal,
            "format",
            format!(
                "`{}` version {} is not a recording journal this build reads",
                head.format, head.version
            ),
        ));
    }
    let mut session = head.session;
    let object = session.label_set(OBJECT);
    let mut line = 1;
    // A last line without its newline was being written when the writer stopped.
    while let Some(true) = next(&mut text)? {
        line += 1;
        let grasp: Grasp = serde_json::from_str(&text).map_err(|e| json(line, e))?;
        if let Some(set) = object {
            let classes = &mut session.label_sets[set].classes;
            let class = match classes.iter().position(|c| *c == grasp.object) {
                Some(c) => c,
                None => {
                    classes.push(grasp.object.clone());
                    classes.len() - 1
                }
            };
            if grasp.labels.get(set) != Some(&class) {
                return Err(SessionError::line_field(
                    journal,
                    line,
                    "labels",
                    format!(
                        "the object label is not `{}`'s class {class} in the recording",
                        grasp.object
                    ),
                ));
            }
        }
        session.grasps.push(grasp);
    }
    validate(&session, journal)?;
    Ok((session, head.pid))
}

/// Whether process `pid` (a journal's writer) still runs. Where the system cannot tell
/// (no `/proc`), it counts as running: the journal is then read, never finalised.
fn running(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
}

/// Write the journal's session to `recording` atomically and remove the journal.
pub fn finalise(recording: &Path) -> Result<Session, SessionError> {
    let (session, _) = read(&journal_path(recording))?;
    settle(recording, session)
}

fn settle(recording: &Path, session: Session) -> Result<Session, SessionError> {
    let journal = journal_path(recording);
    native::save(&session, recording)?;
    fs::remove_file(&journal).map_err(|e| SessionError::io(&journal, e))?;
    Ok(session)
}

/// The recording at `recording` when a journal lies beside it (None otherwise): finalised
/// when its writer is gone, else read as it stands.
pub fn open_unfinished(recording: &Path) -> Option<Result<Session, SessionError>> {
    let journal = journal_path(recording);
    if !journal.is_file() {
        return None;
    }
    Some(read(&journal).and_then(|(session, pid)| {
        if running(pid) {
            Ok(session)
        } else {
            settle(recording, session)
        }
    }))
}
