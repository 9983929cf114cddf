//! The native session format: versioned JSON.
//!
//! ```json
//! {
//! "format": "tactile-workbench-session",
//! "version": 1,
//! "session": {
//!  "meta": {"name": "...", "source": "...", "licence": "...", "frame_rate_hz": 10.0},
//!  "sensors": [
//!   {"name": "thumb", "layout": {"kind": "grid", "rows": 4, "cols": 7}, "unit": "kPa",
//!    "transform": {"kind": "identity"}}
//!  ],
//!  "encoders": ["joint 7"],
//!  "label_sets": [{"name": "outcome", "classes": ["success", "failure"]}],
//!  "grasps": [
//!   {"object": "mug", "trial": 1, "labels": [0], "key_frame": 0,
//!    "frames": [{"t": 0.0, "taxels": [[0.0, 1.5, ...]], "encoders": [12.0]}]}
//!  ]
//! }
//! }
//! ```
//!
//! One grasp per line, so that an error's line number points at the grasp. Reading checks
//! the format tag and version before anything else, then validates the whole session.

use std::io::Write;
use std::path::Path;

use serde::Deserialize;
use serde::de::DeserializeOwned;

use super::error::open_json;
use super::{FORMAT_VERSION, Location, Session, SessionError, validate};
use crate::fsutil;

pub const FORMAT_TAG: &str = "tactile-workbench-session";

#[derive(Deserialize)]
struct Header {
    format: Option<String>,
    version: Option<serde_json::Value>,
}

#[derive(Deserialize)]
struct File {
    session: Session,
}

pub(crate) fn json_error(path: &Path, e: serde_json::Error) -> SessionError {
    let message = match e.classify() {
        serde_json::error::Category::Eof => format!("the file ends too early (truncated?): {e}"),
        _ => e.to_string(),
    };
    // serde_json appends " at line L column C" itself; keep the message without it.
    let message = match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message,
    };
    SessionError {
        path: path.to_path_buf(),
        location: if e.line() > 0 {
            Location::LineColumn {
                line: e.line(),
                column: e.column(),
            }
        } else {
            Location::File
        },
        message,
        source: None,
    }
    .with_source(e)
}

/// Parse a native session from text (`path` names it in errors).
pub fn from_str(text: &str, path: &Path) -> Result<Session, SessionError> {
    let text = crate::fsutil::without_bom(text);
    if text.trim().is_empty() {
        return Err(SessionError::file(path, "the file is empty"));
    }
    let json = |e: serde_json::Error| json_error(path, e);
    check_header(serde_json::from_str(text).map_err(json)?, path)?;
    let file: File = serde_json::from_str(text).map_err(json)?;
    validate(&file.session, path)?;
    Ok(file.session)
}

/// Read a native session file as it is parsed: the header first (one pass that keeps
/// nothing of the session), then the session. At most [`crate::fsutil::max_bytes::SESSION`].
pub fn load(path: &Path) -> Result<Session, SessionError> {
    fn parse<T: DeserializeOwned>(path: &Path) -> Result<T, SessionError> {
        let reader = open_json(path, crate::fsutil::max_bytes::SESSION, "session file")?;
        serde_json::from_reader(reader).map_err(|e| json_error(path, e))
    }
    check_header(parse(path)?, path)?;
    let file: File = parse(path)?;
    validate(&file.session, path)?;
    Ok(file.session)
}

/// The format tag and version, before anything else.
fn check_header(header: Header, path: &Path) -> Result<(), SessionError> {
    match header.format.as_deref() {
        Some(FORMAT_TAG) => {}
        Some(other) => {
            return Err(SessionError::field(
                path,
                "format",
                format!("`{other}` is not a tactile-workbench session"),
            ));
        }
        None => {
            return Err(SessionError::field(
                path,
                "format",
                format!("missing; expected \"{FORMAT_TAG}\" (is this a session file?)"),
            ));
        }
    }
    match header.version {
        Some(serde_json::Value::Number(n)) if n.as_u64() == Some(FORMAT_VERSION as u64) => {}
        Some(v) => {
            return Err(SessionError::field(
                path,
                "version",
                format!(
                    "unsupported format version {v}; this build reads version {FORMAT_VERSION}"
                ),
            ));
        }
        None => return Err(SessionError::field(path, "version", "missing")),
    }
    Ok(())
}

/// Serialise a session in the native format.
pub fn to_writer(session: &Session, w: &mut impl Write) -> std::io::Result<()> {
    head(session, w)?;
    list(w, &session.grasps)?;
    tail(w)
}

/// A grasp as its line of the native format.
pub fn grasp_line(grasp: &super::Grasp) -> String {
    // Serialising plain data to a String cannot fail.
    serde_json::to_string(grasp).unwrap_or_default()
}

/// Serialise `session`'s header with `lines` (each from [`grasp_line`]) as its grasps, the
/// session's own grasps left out: a recording that grows writes each grasp's line once.
pub fn with_grasp_lines(
    session: &Session,
    lines: &[String],
    w: &mut impl Write,
) -> std::io::Result<()> {
    head(session, w)?;
    for (i, line) in lines.iter().enumerate() {
        writeln!(w, "  {line}{}", if i + 1 < lines.len() { "," } else { "" })?;
    }
    tail(w)
}

/// Everything before the grasps.
fn head(session: &Session, w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "{{")?;
    writeln!(w, "\"format\": \"{FORMAT_TAG}\",")?;
    writeln!(w, "\"version\": {FORMAT_VERSION},")?;
    writeln!(w, "\"session\": {{")?;
    write!(w, " \"meta\": ")?;
    json(w, &session.meta)?;
    writeln!(w, ",")?;
    writeln!(w, " \"sensors\": [")?;
    list(w, &session.sensors)?;
    writeln!(w, " ],")?;
    write!(w, " \"encoders\": ")?;
    json(w, &session.encoders)?;
    writeln!(w, ",")?;
    write!(w, " \"label_sets\": ")?;
    json(w, &session.label_sets)?;
    writeln!(w, ",")?;
    writeln!(w, " \"grasps\": [")
}

/// Everything after the grasps.
fn tail(w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, " ]")?;
    writeln!(w, "}}")?;
    writeln!(w, "}}")
}

fn list<T: serde::Serialize>(w: &mut impl Write, items: &[T]) -> std::io::Result<()> {
    for (i, item) in items.iter().enumerate() {
        write!(w, "  ")?;
        serde_json::to_writer(&mut *w, item)?;
        writeln!(w, "{}", if i + 1 < items.len() { "," } else { "" })?;
    }
    Ok(())
}

fn json<T: serde::Serialize>(w: &mut impl Write, v: &T) -> std::io::Result<()> {
    serde_json::to_writer(&mut *w, v).map_err(std::io::Error::from)
}

/// The native text of a session.
pub fn to_string(session: &Session) -> String {
    let mut buf = Vec::new();
    // Writing to a Vec cannot fail.
    let _ = to_writer(session, &mut buf);
    String::from_utf8(buf).unwrap_or_default()
}

/// Write a session file atomically (temporary file, then rename).
pub fn save(session: &Session, path: &Path) -> Result<(), SessionError> {
    fsutil::write_atomic_with(path, |w| to_writer(session, w))
        .map_err(|e| SessionError::io(path, e))
}
