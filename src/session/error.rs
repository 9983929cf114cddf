//! Errors from reading and checking session files: always the file, and where in it.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::error::Kept;

/// Where in a file a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (missing, unreadable, empty).
    File,
    /// A line of a text file (1-based), optionally a named field on it.
    Line { line: usize, field: Option<String> },
    /// A JSON position (1-based line and column).
    LineColumn { line: usize, column: usize },
    /// A field path inside the session, e.g. `grasps[3].frames[2].taxels[1]`.
    Field(String),
    /// A topic of a ROS 2 bag, and the bag time (ns) of the message at fault, if one is.
    Topic { topic: String, time_ns: Option<u64> },
}

/// A bag time (ns since the epoch) as seconds with all nine decimals.
pub fn bag_time(ns: u64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}

/// A problem with a session file: the file, where in it, and what. When a lower error (the
/// file system's, the JSON parser's) is the cause, its text is the message and it is kept
/// as the `source()`; two errors are equal when they say the same (file, place, message).
#[derive(Debug, Clone)]
pub struct SessionError {
    pub path: PathBuf,
    pub location: Location,
    pub message: String,
    pub source: Option<Kept<dyn std::error::Error + Send + Sync>>,
}

impl PartialEq for SessionError {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && self.location == other.location && self.message == other.message
    }
}

impl Eq for SessionError {}

impl SessionError {
    pub fn file(path: &Path, message: impl Into<String>) -> Self {
        SessionError {
            path: path.to_path_buf(),
            location: Location::File,
            message: message.into(),
            source: None,
        }
    }

    pub fn line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        SessionError {
            path: path.to_path_buf(),
            location: Location::Line { line, field: None },
            message: message.into(),
            source: None,
        }
    }

    pub fn line_field(
        path: &Path,
        line: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SessionError {
            path: path.to_path_buf(),
            location: Location::Line {
                line,
                field: Some(field.into()),
            },
            message: message.into(),
            source: None,
        }
    }

    pub fn field(path: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        SessionError {
            path: path.to_path_buf(),
            location: Location::Field(field.into()),
            message: message.into(),
            source: None,
        }
    }

    pub fn topic(
        path: &Path,
        topic: &str,
        time_ns: Option<u64>,
        message: impl Into<String>,
    ) -> Self {
        SessionError {
            path: path.to_path_buf(),
            location: Location::Topic {
                topic: topic.to_string(),
                time_ns,
            },
            message: message.into(),
            source: None,
        }
    }

    /// A lower error about a line as a whole (one that does not split, a header missing a
    /// column): its text is the message, and it is kept.
    pub fn line_caused(
        path: &Path,
        line: usize,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::line(path, line, source.to_string()).with_source(source)
    }

    /// A lower error about a field of a line (a class the spec does not have): its text is
    /// the message, and it is kept.
    pub fn line_field_caused(
        path: &Path,
        line: usize,
        field: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::line_field(path, line, field, source.to_string()).with_source(source)
    }

    /// A lower error about a field of a JSON file (a spec's layout that does not parse): its
    /// text is the message, and it is kept.
    pub fn field_caused(
        path: &Path,
        field: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::field(path, field, source.to_string()).with_source(source)
    }

    /// The file system's error, kept as the source.
    pub fn io(path: &Path, err: std::io::Error) -> Self {
        Self::caused(path, err)
    }

    /// A lower error about the file as a whole: its text is the message, and it is kept.
    pub fn caused(path: &Path, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        Self::file(path, source.to_string()).with_source(source)
    }

    /// A lower error about a topic of a bag, or its message at `time_ns` (a definition or
    /// message that does not decode): its text is the message, and it is kept.
    pub fn topic_caused(
        path: &Path,
        topic: &str,
        time_ns: Option<u64>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::topic(path, topic, time_ns, source.to_string()).with_source(source)
    }

    /// `self` with `source` kept as its cause.
    pub fn with_source(mut self, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        self.source = Some(Kept::any(source));
        self
    }
}

impl fmt::Display for SessionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match &self.location {
            Location::File => write!(f, "{p}: {}", self.message),
            Location::Line { line, field: None } => write!(f, "{p}:{line}: {}", self.message),
            Location::Line {
                line,
                field: Some(field),
            } => write!(f, "{p}:{line}: field `{field}`: {}", self.message),
            Location::LineColumn { line, column } => {
                write!(f, "{p}:{line}:{column}: {}", self.message)
            }
            Location::Field(field) => write!(f, "{p}: `{field}`: {}", self.message),
            Location::Topic {
                topic,
                time_ns: Some(t),
            } => write!(
                f,
                "{p}: topic `{topic}`, message at {} s: {}",
                bag_time(*t),
                self.message
            ),
            Location::Topic {
                topic,
                time_ns: None,
            } => write!(f, "{p}: topic `{topic}`: {}", self.message),
        }
    }
}

impl std::error::Error for SessionError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.source {
            Some(kept) => Some(&**kept),
            None => None,
        }
    }
}

/// Parse one number of a text format: finite, or an error naming the field.
pub(crate) fn parse_number(
    path: &Path,
    line: usize,
    field: &str,
    text: &str,
) -> Result<f64, SessionError> {
    let t = text.trim();
    if t.is_empty() {
        return Err(SessionError::line_field(path, line, field, "empty value"));
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(SessionError::line_field(
            path,
            line,
            field,
            format!("`{t}` is not a finite number ({v})"),
        )),
        Err(_) => Err(SessionError::line_field(
            path,
            line,
            field,
            format!("`{}` is not a number", shorten(t)),
        )),
    }
}

/// Read a text file, naming the line of the first byte that is not UTF-8.
pub(crate) fn read_text(path: &Path) -> Result<String, SessionError> {
    let bytes = std::fs::read(path).map_err(|e| SessionError::io(path, e))?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&c| c == b'\n').count() + 1;
        SessionError::line(path, line, "the file is not valid UTF-8 text")
    })
}

/// A JSON file of the session layer opened to be parsed as it is read
/// ([`crate::fsutil::open_json`]: at most `max_bytes`, past a byte-order mark). Its first
/// block is looked at as [`read_text`] would: an empty file, or bytes that are not UTF-8,
/// are named so rather than as a JSON syntax error.
pub(crate) fn open_json(
    path: &Path,
    max_bytes: u64,
    what: &str,
) -> Result<std::io::BufReader<std::fs::File>, SessionError> {
    use std::io::BufRead;
    let io = |e: std::io::Error| SessionError::io(path, e);
    let mut r = crate::fsutil::open_json(path, max_bytes, what).map_err(io)?;
    let block = r.capacity();
    let head = r.fill_buf().map_err(io)?;
    if head.len() < block && head.iter().all(u8::is_ascii_whitespace) {
        return Err(SessionError::file(path, "the file is empty"));
    }
    if let Err(e) = std::str::from_utf8(head)
        && e.error_len().is_some()
    {
        let valid = &head[..e.valid_up_to()];
        let line = valid.iter().filter(|&&c| c == b'\n').count() + 1;
        return Err(SessionError::line(
            path,
            line,
            "the file is not valid UTF-8 text",
        ));
    }
    Ok(r)
}

/// Keep messages readable when a field holds a long run of garbage.
pub(crate) fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let head: String = s.chars().take(MAX).collect();
        format!("{head}…")
    }
}
