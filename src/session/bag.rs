//! Reading a ROS 2 bag stored as MCAP: a `.mcap` file, or a bag folder as `ros2 bag record`
//! writes it (`metadata.yaml` and one or more `.mcap` files, read in the order the metadata
//! lists them). Only the topics the spec names are decoded, each checked against its
//! definition in the bag; the others are skipped whatever their type.
//!
//! Time is the bag time of a message (its MCAP log time, ns since the epoch): every topic
//! then shares one clock, which is also the clock of a windows CSV.

use std::borrow::Cow;
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::SessionError;
use super::cdr::{self, ArrayKind, MsgType, TACTILE_TYPES};
use super::error::{read_text, shorten};
use super::spec::ImportSpec;

/// What the importer does with a topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Index into `Bag::tactile`.
    Tactile(usize),
    Joints,
    Events,
}

/// The messages of one tactile topic: one row of `width` values per stamp.
#[derive(Debug, Default)]
pub struct TactileTopic {
    pub topic: String,
    /// Indices of the spec's sensors read from this topic.
    pub sensors: Vec<usize>,
    /// Values per message: the end of the last sensor's slice.
    pub width: usize,
    pub stamps: Vec<u64>,
    pub values: Vec<f64>,
}

impl TactileTopic {
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.width..(i + 1) * self.width]
    }
}

/// The named joints' positions, one row per `JointState` message.
#[derive(Debug, Default)]
pub struct JointTopic {
    pub topic: String,
    pub stamps: Vec<u64>,
    pub values: Vec<f64>,
}

/// The decoded topics of a bag.
#[derive(Debug, Default)]
pub struct Bag {
    pub tactile: Vec<TactileTopic>,
    pub joints: Option<JointTopic>,
    /// (bag time, text) of each message of the events topic.
    pub events: Vec<(u64, String)>,
    /// First and last bag time of any message.
    pub span: Option<(u64, u64)>,
}

/// The `.mcap` files of a bag: the file itself, or those a bag folder's metadata.yaml lists.
pub fn bag_files(path: &Path) -> Result<Vec<PathBuf>, SessionError> {
    if !path.is_dir() {
        if !path.is_file() {
            return Err(SessionError::file(path, "no such file or folder"));
        }
        return Ok(vec![path.to_path_buf()]);
    }
    let meta = path.join("metadata.yaml");
    if !meta.is_file() {
        return Err(SessionError::file(
            path,
            "no metadata.yaml: not a ROS 2 bag folder as `ros2 bag record` writes it",
        ));
    }
    let text = read_text(&meta)?;
    let files = metadata_files(&text, &meta)?;
    files
        .into_iter()
        .map(|(line, name)| {
            let f = path.join(&name);
            if !name.ends_with(".mcap") {
                Err(SessionError::line(
                    &meta,
                    line,
                    format!("`{}` is not an .mcap file", shorten(&name)),
                ))
            } else if !f.is_file() {
                Err(SessionError::line(
                    &meta,
                    line,
                    format!("lists `{}`, which is not in the folder", shorten(&name)),
                ))
            } else {
                Ok(f)
            }
        })
        .collect()
}

/// A scalar of a `key: value` line, unquoted.
fn unquote(v: &str) -> &str {
    let v = v.trim();
    v.strip_prefix('\'')
        .and_then(|s| s.strip_suffix('\''))
        .or_else(|| v.strip_prefix('"').and_then(|s| s.strip_suffix('"')))
        .unwrap_or(v)
}

/// The storage checks and the split files, in order, of a rosbag2 metadata.yaml, with
/// the line of each. rosbag2 writes this file itself in a fixed block style, so the few
/// keys needed are read line by line rather than with a YAML parser.
fn metadata_files(text: &str, meta: &Path) -> Result<Vec<(usize, String)>, SessionError> {
    let lines: Vec<&str> = text.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let value_of = |key: &str| {
        lines.iter().enumerate().find_map(|(i, l)| {
            l.trim_start()
                .strip_prefix(key)
                .and_then(|rest| rest.strip_prefix(':'))
                .map(|v| (i + 1, unquote(v)))
        })
    };
    if let Some((line, storage)) = value_of("storage_identifier")
        && storage != "mcap"
    {
        return Err(SessionError::line(
            meta,
            line,
            format!(
                "the bag is stored as `{}`; only MCAP bags are read (convert it with \
                 `ros2 bag convert`)",
                shorten(storage)
            ),
        ));
    }
    if let Some((line, mode)) = value_of("compression_mode")
        && !mode.is_empty()
    {
        return Err(SessionError::line(
            meta,
            line,
            format!(
                "the bag is compressed per {} (compression_mode {}); decompress it with \
                 `ros2 bag decompress`, or record with MCAP's own chunk compression",
                mode.to_lowercase(),
                shorten(mode)
            ),
        ));
    }
    let Some(key) = lines
        .iter()
        .position(|l| l.trim_start().starts_with("relative_file_paths:"))
    else {
        return Err(SessionError::file(meta, "no `relative_file_paths` list"));
    };
    let rest = lines[key].trim_start()["relative_file_paths:".len()..].trim();
    let mut files = Vec::new();
    if let Some(flow) = rest.strip_prefix('[') {
        let inner = flow.strip_suffix(']').ok_or_else(|| {
            SessionError::line(meta, key + 1, "the list of files is not closed on its line")
        })?;
        files.extend(
            inner
                .split(',')
                .map(unquote)
                .filter(|s| !s.is_empty())
                .map(|s| (key + 1, s.to_string())),
        );
    } else {
        let key_indent = indent(lines[key]);
        for (i, l) in lines.iter().enumerate().skip(key + 1) {
            match l.trim_start().strip_prefix('-') {
                Some(item) if indent(l) >= key_indent => {
                    files.push((i + 1, unquote(item).to_string()))
                }
                _ => break,
            }
        }
    }
    if files.is_empty() {
        return Err(SessionError::line(meta, key + 1, "the bag lists no files"));
    }
    Ok(files)
}

/// The MCAP library's error, in words about the file.
fn mcap_error(file: &Path, e: &mcap::McapError) -> SessionError {
    use mcap::McapError as E;
    let what = match e {
        E::BadMagic => "not an MCAP file, or its start or end is missing (bad magic bytes)".into(),
        E::UnexpectedEof | E::UnexpectedEoc | E::BadFooter => {
            format!("the bag is truncated ({e})")
        }
        _ => format!("the bag is damaged: {e}"),
    };
    SessionError::file(file, what)
}

/// The topics the spec reads, with the role of each.
fn roles(spec: &ImportSpec, events: Option<&str>) -> Result<Vec<(String, Role)>, SessionError> {
    let mut out: Vec<(String, Role)> = Vec::new();
    let mut tactile = 0;
    for (s, sensor) in spec.sensors.iter().enumerate() {
        let Some(topic) = &sensor.topic else {
            return Err(SessionError::field(
                &spec.path,
                format!("sensors[{s}].topic"),
                format!(
                    "sensor `{}` needs the topic it is read from",
                    sensor.sensor.name
                ),
            ));
        };
        if !out.iter().any(|(t, _)| t == topic) {
            out.push((topic.clone(), Role::Tactile(tactile)));
            tactile += 1;
        }
    }
    let mut add = |topic: &str, role: Role, field: &str| {
        if out.iter().any(|(t, _)| t == topic) {
            return Err(SessionError::field(
                &spec.path,
                field,
                format!("topic `{topic}` is already read for another purpose"),
            ));
        }
        out.push((topic.to_string(), role));
        Ok(())
    };
    if let Some(j) = &spec.joints {
        let Some(topic) = &j.topic else {
            return Err(SessionError::field(
                &spec.path,
                "joints.topic",
                "the JointState topic of the joints is missing",
            ));
        };
        add(topic, Role::Joints, "joints.topic")?;
    }
    if let Some(topic) = events {
        add(topic, Role::Events, "grasps.events")?;
    }
    Ok(out)
}

/// The spec's topic of each role, and the types it may have.
fn allowed(role: Role) -> &'static str {
    match role {
        Role::Tactile(_) => TACTILE_TYPES,
        Role::Joints => "sensor_msgs/msg/JointState",
        Role::Events => "std_msgs/msg/String",
    }
}

fn type_fits(role: Role, ty: MsgType) -> bool {
    matches!(
        (role, ty),
        (Role::Tactile(_), MsgType::MultiArray(_))
            | (Role::Joints, MsgType::JointState)
            | (Role::Events, MsgType::String)
    )
}

/// A channel as first seen in a file: its role and element type, once checked.
#[derive(Clone, Copy)]
struct Checked {
    role: Role,
    kind: Option<ArrayKind>,
}

/// Read the topics the spec names from every file of the bag at `path`.
pub fn read(path: &Path, spec: &ImportSpec, events: Option<&str>) -> Result<Bag, SessionError> {
    let files = bag_files(path)?;
    let roles = roles(spec, events)?;
    let mut bag = Bag::default();
    for (topic, role) in &roles {
        match role {
            Role::Tactile(_) => {
                let sensors: Vec<usize> = (0..spec.sensors.len())
                    .filter(|&s| spec.sensors[s].topic.as_deref() == Some(topic))
                    .collect();
                let width = sensors
                    .iter()
                    .map(|&s| spec.sensors[s].range_in_message().end)
                    .max()
                    .unwrap_or(0);
                bag.tactile.push(TactileTopic {
                    topic: topic.clone(),
                    sensors,
                    width,
                    ..Default::default()
                });
            }
            Role::Joints => {
                bag.joints = Some(JointTopic {
                    topic: topic.clone(),
                    ..Default::default()
                })
            }
            Role::Events => {}
        }
    }
    // Every topic of the bag with its type, to name them when a spec topic is missing.
    let mut seen: Vec<(String, String)> = Vec::new();
    for file in &files {
        read_file(file, spec, &roles, &mut bag, &mut seen)?;
    }
    for (topic, role) in &roles {
        let messages = match role {
            Role::Tactile(i) => bag.tactile[*i].stamps.len(),
            Role::Joints => bag.joints.as_ref().map_or(0, |j| j.stamps.len()),
            Role::Events => bag.events.len(),
        };
        if messages == 0 && seen.iter().any(|(t, _)| t == topic) {
            let what = match role {
                Role::Tactile(_) => "tactile topic",
                Role::Joints => "joint topic",
                Role::Events => "events topic",
            };
            return Err(SessionError::topic(
                path,
                topic,
                None,
                format!("the spec's {what} is in the bag but holds no messages"),
            ));
        }
        if !seen.iter().any(|(t, _)| t == topic) {
            let listed: Vec<String> = seen.iter().map(|(t, ty)| format!("{t} ({ty})")).collect();
            let what = match role {
                Role::Tactile(_) => "tactile topic",
                Role::Joints => "joint topic",
                Role::Events => "events topic",
            };
            return Err(SessionError::topic(
                path,
                topic,
                None,
                format!(
                    "the spec's {what} is not in the bag; its topics are: {}",
                    if listed.is_empty() {
                        "none".to_string()
                    } else {
                        listed.join(", ")
                    }
                ),
            ));
        }
    }
    Ok(bag)
}

/// Reads one MCAP file of the bag, streaming: the file is never held whole, and at most one
/// chunk is decompressed at a time.
///
/// - With a summary section holding chunk indexes (rosbag2 and the MCAP writers write
///   one), the channels come from the summary and only the chunks whose message indexes
///   name a channel the spec reads are read; the others (a camera's) are skipped unread.
/// - Without one, the data section is scanned in order: messages of other channels and
///   records the importer does not need are skipped by seeking past them.
///
/// The MCAP library (0.26) reserves the sizes a damaged file claims before checking them (a
/// chunk's uncompressed size, a record's length inside a chunk, a string's length): a
/// failed allocation aborts the process, which no `catch_unwind` can turn into an error
/// (fuzzing found a chunk claiming 116 TB and a 2.4 GB string). So the records are framed
/// here, every length checked against the bytes that hold it, chunks are decompressed
/// growing with what they really hold, and the library parses only records whose fields
/// are known to fit.
fn read_file(
    file: &Path,
    spec: &ImportSpec,
    roles: &[(String, Role)],
    bag: &mut Bag,
    seen: &mut Vec<(String, String)>,
) -> Result<(), SessionError> {
    let io = |e: std::io::Error| SessionError::io(file, &e);
    let f = File::open(file).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut input = BufReader::with_capacity(1 << 16, f);
    let magic = mcap::MAGIC;
    let mut head = [0u8; 8];
    if len < 8 || input.read_exact(&mut head).is_err() || head != *magic {
        return Err(mcap_error(file, &mcap::McapError::BadMagic));
    }
    let ends_with_magic = len >= 16
        && input.seek(SeekFrom::Start(len - 8)).is_ok()
        && input.read_exact(&mut head).is_ok()
        && head == *magic;
    if !ends_with_magic {
        return Err(SessionError::file(
            file,
            "the bag is truncated (its end magic bytes are missing)",
        ));
    }
    let mut reader = FileReader {
        file,
        spec,
        roles,
        bag,
        seen,
        links: mcap::read::ChannelAccumulator::default(),
        checked: HashMap::new(),
        scratch: Vec::new(),
        joint_names: spec.encoder_names(),
        body: Vec::new(),
    };
    match reader.chunk_indexes(&mut input, len)? {
        Some(chunks) => reader.indexed(&mut input, &chunks),
        None => reader.linear(&mut input, len - 8),
    }
}

/// Where a chunk is, which channels it holds messages of, and their time span, from the
/// summary's chunk index.
struct ChunkAt {
    offset: u64,
    length: u64,
    times: (u64, u64),
    channels: Vec<u16>,
}

/// A chunk index record's fields the importer uses, each checked to lie in the body:
/// message start and end time, chunk offset and length, and the channels of its message
/// indexes.
fn parse_chunk_index(body: &[u8]) -> Option<ChunkAt> {
    let u64_at = |at: usize| {
        body.get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
    };
    let map_len = body.get(32..36)?;
    let map_len = u32::from_le_bytes(map_len.try_into().ok()?) as usize;
    let map = body.get(36..36usize.checked_add(map_len)?)?;
    if map.len() % 10 != 0 {
        return None;
    }
    Some(ChunkAt {
        times: (u64_at(0)?, u64_at(8)?),
        offset: u64_at(16)?,
        length: u64_at(24)?,
        channels: map
            .chunks_exact(10)
            .map(|e| u16::from_le_bytes([e[0], e[1]]))
            .collect(),
    })
}

/// Whether every indexed chunk lies in the data section and starts with a chunk record of
/// the indexed length, in order and without overlap: a summary left stale by an edit of
/// the file, or damaged, is not followed.
fn chunks_sound(
    input: &mut BufReader<File>,
    len: u64,
    chunks: &[ChunkAt],
) -> Result<bool, SessionError> {
    let mut next = 8;
    for c in chunks {
        let inside = c.offset >= next
            && c.length >= 9
            && c.offset.checked_add(c.length).is_some_and(|e| e <= len - 8);
        if !inside {
            return Ok(false);
        }
        let mut head = [0u8; 9];
        if input.seek(SeekFrom::Start(c.offset)).is_err() || input.read_exact(&mut head).is_err() {
            return Ok(false);
        }
        let body = u64::from_le_bytes(head[1..].try_into().unwrap_or_default());
        if head[0] != CHUNK || body != c.length - 9 {
            return Ok(false);
        }
        next = c.offset + c.length;
    }
    Ok(true)
}

/// A record's opcode and body length at the reader's position, the length checked against
/// the `left` bytes before the end of the section.
fn record_header(input: &mut impl Read, file: &Path, left: u64) -> Result<(u8, u64), SessionError> {
    // The file's end magic is checked first: a record running past its section is damage.
    let mut head = [0u8; 9];
    if left < 9 || input.read_exact(&mut head).is_err() {
        return Err(overrun(file, "a record's length", left.saturating_sub(1)));
    }
    let len = u64::from_le_bytes(head[1..].try_into().unwrap_or_default());
    if len > left - 9 {
        return Err(overrun(
            file,
            &format!("a record (opcode {:#04x}) of {len} bytes", head[0]),
            left - 9,
        ));
    }
    Ok((head[0], len))
}

fn overrun(file: &Path, what: &str, left: u64) -> SessionError {
    SessionError::file(
        file,
        format!("the bag is damaged: {what} runs past the end of its section ({left} bytes left)"),
    )
}

/// The state of reading one file: channel ids are per file.
struct FileReader<'r> {
    file: &'r Path,
    spec: &'r ImportSpec,
    roles: &'r [(String, Role)],
    bag: &'r mut Bag,
    seen: &'r mut Vec<(String, String)>,
    /// Schemas and channels as defined so far, linked and checked by the library.
    links: mcap::read::ChannelAccumulator<'static>,
    /// Per channel id: what the importer does with its messages (`None`: skipped).
    checked: HashMap<u16, Option<Checked>>,
    scratch: Vec<f64>,
    joint_names: Vec<String>,
    /// The body of the record being read (a message, a chunk's compressed records).
    body: Vec<u8>,
}

/// The footer's opcode and the summary's records the importer reads.
const FOOTER: u8 = 0x02;
const SCHEMA: u8 = 0x03;
const CHANNEL: u8 = 0x04;
const MESSAGE: u8 = 0x05;
const CHUNK: u8 = 0x06;
const CHUNK_INDEX: u8 = 0x08;

impl FileReader<'_> {
    /// The summary's chunk indexes, in file order, with its schemas and channels defined;
    /// `None` when the file has no summary, it indexes no chunk, or it does not agree with
    /// the file (damaged, or stale after an edit): the file is then scanned instead, as if
    /// it had none.
    fn chunk_indexes(
        &mut self,
        input: &mut BufReader<File>,
        len: u64,
    ) -> Result<Option<Vec<ChunkAt>>, SessionError> {
        let file = self.file;
        let io = |e: std::io::Error| SessionError::io(file, &e);
        // The footer: opcode, length 20, summary start, summary offset start, CRC.
        const FOOTER_LEN: u64 = 9 + 20;
        if len < 16 + FOOTER_LEN {
            return Ok(None);
        }
        let footer_at = len - 8 - FOOTER_LEN;
        let mut footer = [0u8; FOOTER_LEN as usize];
        input.seek(SeekFrom::Start(footer_at)).map_err(io)?;
        input.read_exact(&mut footer).map_err(io)?;
        let word =
            |at: usize| u64::from_le_bytes(footer[at..at + 8].try_into().unwrap_or_default());
        let summary_start = word(9);
        if footer[0] != FOOTER || word(1) != 20 || summary_start < 8 || summary_start >= footer_at {
            return Ok(None);
        }
        let offsets_start = word(17);
        let end = if (summary_start..=footer_at).contains(&offsets_start) {
            offsets_start
        } else {
            footer_at
        };
        input.seek(SeekFrom::Start(summary_start)).map_err(io)?;
        let chunks = match self.summary(input, summary_start, end) {
            Ok(chunks) if !chunks.is_empty() && chunks_sound(input, len, &chunks)? => chunks,
            _ => {
                // Forget what the summary defined: the scan defines it again.
                self.links = mcap::read::ChannelAccumulator::default();
                self.checked.clear();
                return Ok(None);
            }
        };
        Ok(Some(chunks))
    }

    /// The summary section's schemas and channels (defined) and chunk indexes (returned,
    /// in file order).
    fn summary(
        &mut self,
        input: &mut BufReader<File>,
        start: u64,
        end: u64,
    ) -> Result<Vec<ChunkAt>, SessionError> {
        let file = self.file;
        let mut chunks = Vec::new();
        let mut pos = start;
        while pos < end {
            let (opcode, len) = record_header(input, file, end - pos)?;
            pos += 9 + len;
            match opcode {
                SCHEMA | CHANNEL => {
                    let body = self.read_body(input, len)?;
                    let r = self.definition(opcode, &body);
                    self.body = body;
                    r?;
                }
                CHUNK_INDEX => {
                    let body = self.read_body(input, len)?;
                    let chunk = parse_chunk_index(&body);
                    self.body = body;
                    chunks.push(chunk.ok_or_else(|| {
                        SessionError::file(file, "the bag is damaged: a chunk index does not fit")
                    })?);
                }
                _ => input
                    .seek_relative(len as i64)
                    .map_err(|e| SessionError::io(file, &e))?,
            }
        }
        chunks.sort_by_key(|c| c.offset);
        Ok(chunks)
    }

    /// Reads the chunks that hold messages of the spec's channels, in file order; a chunk
    /// whose index names none of them is skipped, its time span kept for the bag's.
    fn indexed(
        &mut self,
        input: &mut BufReader<File>,
        chunks: &[ChunkAt],
    ) -> Result<(), SessionError> {
        let file = self.file;
        let io = |e: std::io::Error| SessionError::io(file, &e);
        for chunk in chunks {
            // A chunk without message indexes may hold anything: it is read.
            let wanted = chunk.channels.is_empty()
                || chunk
                    .channels
                    .iter()
                    .any(|&id| matches!(self.wanted(id), Ok(true) | Err(_)));
            if !wanted {
                self.bag.span = Some(widen(self.bag.span, chunk.times.0, chunk.times.1));
                continue;
            }
            // `chunks_sound` checked that a chunk record of this length is there.
            input.seek(SeekFrom::Start(chunk.offset + 9)).map_err(io)?;
            self.chunk(input, chunk.length - 9)?;
        }
        Ok(())
    }

    /// Scans the data section from after the start magic up to `end` (or its data end
    /// record), reading what the spec needs and seeking past the rest.
    fn linear(&mut self, input: &mut BufReader<File>, end: u64) -> Result<(), SessionError> {
        let file = self.file;
        let io = |e: std::io::Error| SessionError::io(file, &e);
        input.seek(SeekFrom::Start(8)).map_err(io)?;
        let mut pos = 8;
        while pos < end {
            let (opcode, len) = record_header(input, file, end - pos)?;
            pos += 9 + len;
            match opcode {
                DATA_END => break,
                SCHEMA | CHANNEL => {
                    let body = self.read_body(input, len)?;
                    self.definition(opcode, &body)?;
                    self.body = body;
                }
                MESSAGE => self.streamed_message(input, len)?,
                CHUNK => self.chunk(input, len)?,
                _ => input.seek_relative(len as i64).map_err(io)?,
            }
        }
        Ok(())
    }

    /// The next `len` bytes, in the reused body buffer (taken; give it back after use).
    fn read_body(&mut self, input: &mut impl Read, len: u64) -> Result<Vec<u8>, SessionError> {
        let mut body = std::mem::take(&mut self.body);
        body.clear();
        body.resize(len as usize, 0);
        input
            .read_exact(&mut body)
            .map_err(|e| SessionError::io(self.file, &e))?;
        Ok(body)
    }

    /// A schema or channel record, checked to fit and linked by the library.
    fn definition(&mut self, opcode: u8, body: &[u8]) -> Result<(), SessionError> {
        self.records_in(opcode, body, false)
    }

    /// A message record of the data section: its header read, its data only when the spec
    /// reads its channel.
    fn streamed_message(
        &mut self,
        input: &mut BufReader<File>,
        len: u64,
    ) -> Result<(), SessionError> {
        let file = self.file;
        let mut head = [0u8; 22];
        if len < 22 {
            return Err(SessionError::file(
                file,
                format!(
                    "the bag is damaged: a fixed-size field does not fit in its record (opcode \
                     {MESSAGE:#04x})"
                ),
            ));
        }
        input
            .read_exact(&mut head)
            .map_err(|e| SessionError::io(file, &e))?;
        let word = |at: usize| u64::from_le_bytes(head[at..at + 8].try_into().unwrap_or_default());
        let header = mcap::records::MessageHeader {
            channel_id: u16::from_le_bytes([head[0], head[1]]),
            sequence: u32::from_le_bytes([head[2], head[3], head[4], head[5]]),
            log_time: word(6),
            publish_time: word(14),
        };
        if self.wanted(header.channel_id)? {
            let data = self.read_body(input, len - 22)?;
            let r = self.message(&header, &data);
            self.body = data;
            r
        } else {
            self.bag.span = Some(widen(self.bag.span, header.log_time, header.log_time));
            input
                .seek_relative((len - 22) as i64)
                .map_err(|e| SessionError::io(file, &e))
        }
    }

    /// A chunk record of `len` bytes at the reader's position: its header checked, its
    /// records decompressed (alone in memory) and read.
    fn chunk(&mut self, input: &mut BufReader<File>, len: u64) -> Result<(), SessionError> {
        let body = self.read_body(input, len)?;
        let r = self.records_in(CHUNK, &body, false);
        self.body = body;
        r
    }

    /// Whether the spec reads the messages of channel `id` (checked the first time).
    fn wanted(&mut self, id: u16) -> Result<bool, SessionError> {
        Ok(self.checked_channel(id)?.is_some())
    }

    fn checked_channel(&mut self, id: u16) -> Result<Option<Checked>, SessionError> {
        if let Some(c) = self.checked.get(&id) {
            return Ok(*c);
        }
        let Some(channel) = self.links.get(id) else {
            return Err(SessionError::file(
                self.file,
                format!("a message refers to channel {id}, which the bag never defines"),
            ));
        };
        let c = check_channel(self.file, &channel, self.roles, self.seen)?;
        self.checked.insert(id, c);
        Ok(c)
    }

    /// Reads the records of one decompressed chunk, up to its end.
    fn chunk_contents(&mut self, mut rest: &[u8]) -> Result<(), SessionError> {
        let file = self.file;
        while !rest.is_empty() {
            // A record: opcode (1 byte), body length (u64), body.
            let (opcode, after) = (rest[0], &rest[1..]);
            let Some((len, after)) = after.split_first_chunk::<8>() else {
                return Err(truncated(file, true, "a record's length", after.len()));
            };
            let len = u64::from_le_bytes(*len);
            if len > after.len() as u64 {
                return Err(truncated(
                    file,
                    true,
                    &format!("a record (opcode {opcode:#04x}) of {len} bytes"),
                    after.len(),
                ));
            }
            let (body, after) = after.split_at(len as usize);
            rest = after;
            self.records_in(opcode, body, true)?;
        }
        Ok(())
    }

    /// One record (its body), checked to fit before the library parses it; records the
    /// importer does not use are passed over.
    fn records_in(&mut self, opcode: u8, body: &[u8], in_chunk: bool) -> Result<(), SessionError> {
        use mcap::records::Record;
        let file = self.file;
        let damaged = |e: mcap::McapError| mcap_error(file, &e);
        let Some(&(_, fields)) = FIELDS.iter().find(|(op, _)| *op == opcode) else {
            return Ok(());
        };
        fields_fit(fields, body).map_err(|what| {
            SessionError::file(
                file,
                format!(
                    "the bag is damaged: {what} does not fit in its record (opcode {opcode:#04x})"
                ),
            )
        })?;
        match mcap::parse_record(opcode, body).map_err(damaged)? {
            Record::Schema { header, data } => self
                .links
                .add_schema(header, Cow::Owned(data.into_owned()))
                .map_err(damaged)?,
            Record::Channel(channel) => {
                let id = channel.id;
                self.links.add_channel(channel).map_err(damaged)?;
                // Every channel is listed, with or without messages.
                if let Some(c) = self.links.get(id) {
                    note_topic(self.seen, &c);
                }
            }
            Record::Message { header, data } => self.message(&header, &data)?,
            Record::Chunk { .. } if in_chunk => {
                return Err(SessionError::file(
                    file,
                    "the bag is damaged: a chunk inside a chunk",
                ));
            }
            Record::Chunk { header, data } => {
                let inner = chunk_records(file, &header, &data)?;
                self.chunk_contents(&inner)?;
            }
            _ => {}
        }
        Ok(())
    }

    fn message(
        &mut self,
        header: &mcap::records::MessageHeader,
        data: &[u8],
    ) -> Result<(), SessionError> {
        let (file, spec, roles) = (self.file, self.spec, self.roles);
        let bag = &mut *self.bag;
        let t = header.log_time;
        bag.span = Some(widen(bag.span, t, t));
        let checked = self.checked_channel(header.channel_id)?;
        let bag = &mut *self.bag;
        let scratch = &mut self.scratch;
        let Some(Checked { role, kind }) = checked else {
            return Ok(());
        };
        let topic = roles
            .iter()
            .find(|(_, r)| *r == role)
            .map_or("", |(t, _)| t.as_str());
        let at = |m: String| SessionError::topic(file, topic, Some(t), m);
        match role {
            Role::Tactile(i) => {
                let kind = kind.unwrap_or(ArrayKind::F64);
                cdr::decode_multiarray(data, kind, scratch).map_err(at)?;
                let tt = &mut bag.tactile[i];
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
            }
            Role::Joints => {
                let js = cdr::decode_joint_state(data).map_err(at)?;
                if js.positions.len() != js.names.len() {
                    return Err(at(format!(
                        "{} joint names but {} positions",
                        js.names.len(),
                        js.positions.len()
                    )));
                }
                let Some(jt) = bag.joints.as_mut() else {
                    return Ok(());
                };
                if jt.stamps.last().is_some_and(|&last| t < last) {
                    return Err(backwards(file, topic, t, jt.stamps[jt.stamps.len() - 1]));
                }
                for name in &self.joint_names {
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
            }
            Role::Events => {
                let text = cdr::decode_string(data).map_err(at)?;
                if bag.events.last().is_some_and(|&(last, _)| t < last) {
                    let last = bag.events[bag.events.len() - 1].0;
                    return Err(backwards(file, topic, t, last));
                }
                bag.events.push((t, text.to_string()));
            }
        }
        Ok(())
    }
}

/// The data end record's opcode: the data section ends there.
const DATA_END: u8 = 0x0F;

/// A record field, for checking that a body holds what its lengths claim.
#[derive(Clone, Copy)]
enum Field {
    Fixed(usize),
    /// u32 length, then bytes (a string, or a schema's data).
    Bytes,
    /// u32 length, then string pairs filling it.
    Map,
}

/// The records the importer reads, with their fields up to the last length-prefixed one
/// (what follows it, a message's or chunk's data, is the rest of the body).
const FIELDS: [(u8, &[Field]); 4] = [
    // Schema: id, name, encoding, data.
    (
        0x03,
        &[Field::Fixed(2), Field::Bytes, Field::Bytes, Field::Bytes],
    ),
    // Channel: id, schema id, topic, message encoding, metadata.
    (
        0x04,
        &[Field::Fixed(4), Field::Bytes, Field::Bytes, Field::Map],
    ),
    // Message: channel id, sequence, log time, publish time, data.
    (0x05, &[Field::Fixed(22)]),
    // Chunk: start and end time, uncompressed size and CRC, compression, compressed size.
    (0x06, &[Field::Fixed(28), Field::Bytes, Field::Fixed(8)]),
];

/// Checks that every length-prefixed field of a record lies inside its body, so the library
/// never reserves a length the body cannot hold; names the first that does not.
fn fields_fit(fields: &[Field], body: &[u8]) -> Result<(), &'static str> {
    fn bytes(rest: &mut &[u8]) -> Result<(), &'static str> {
        let (len, after) = rest.split_first_chunk::<4>().ok_or("a length")?;
        let len = u32::from_le_bytes(*len) as usize;
        *rest = after.get(len..).ok_or("a string or data")?;
        Ok(())
    }
    let mut rest = body;
    for field in fields {
        match *field {
            Field::Fixed(n) => rest = rest.get(n..).ok_or("a fixed-size field")?,
            Field::Bytes => bytes(&mut rest)?,
            Field::Map => {
                let (len, after) = rest.split_first_chunk::<4>().ok_or("a map's length")?;
                let len = u32::from_le_bytes(*len) as usize;
                let mut map = after.get(..len).ok_or("a map")?;
                while !map.is_empty() {
                    bytes(&mut map)?;
                    bytes(&mut map)?;
                }
                rest = &after[len..];
            }
        }
    }
    Ok(())
}

/// A record or its length running past the end of the file or of a chunk (`left` bytes
/// left).
fn truncated(file: &Path, in_chunk: bool, what: &str, left: usize) -> SessionError {
    let (kind, where_) = if in_chunk {
        ("damaged", "a chunk")
    } else {
        ("truncated", "the file")
    };
    SessionError::file(
        file,
        format!("the bag is {kind}: {what} runs past the end of {where_} ({left} bytes left)"),
    )
}

/// What a chunk may hold before the first bytes are out: its claimed size is not trusted.
const CHUNK_RESERVE: u64 = 1 << 24;

/// A chunk's records, decompressed: the output grows with what the data holds and must end
/// at exactly the size the chunk claims.
fn chunk_records<'c>(
    file: &Path,
    header: &mcap::records::ChunkHeader,
    data: &'c [u8],
) -> Result<Cow<'c, [u8]>, SessionError> {
    use std::io::Read;
    let claim = header.uncompressed_size;
    let damaged = |what: String| SessionError::file(file, format!("the bag is damaged: {what}"));
    match header.compression.as_str() {
        "" => Ok(Cow::Borrowed(data)),
        "zstd" => {
            let mut out = Vec::with_capacity(claim.min(CHUNK_RESERVE) as usize);
            zstd::stream::read::Decoder::with_buffer(data)
                .and_then(|d| d.take(claim.saturating_add(1)).read_to_end(&mut out))
                .map_err(|e| damaged(format!("a zstd chunk does not decompress ({e})")))?;
            if out.len() as u64 != claim {
                return Err(damaged(format!(
                    "a zstd chunk of {} bytes claims {claim} bytes uncompressed but holds {}",
                    data.len(),
                    if out.len() as u64 > claim {
                        "more".to_string()
                    } else {
                        out.len().to_string()
                    }
                )));
            }
            Ok(Cow::Owned(out))
        }
        other => Err(SessionError::file(
            file,
            format!(
                "a chunk is compressed with `{}`; the importer reads zstd and uncompressed chunks",
                shorten(other)
            ),
        )),
    }
}

/// The time span `span` widened to hold `first..=last`.
fn widen(span: Option<(u64, u64)>, first: u64, last: u64) -> (u64, u64) {
    match span {
        Some((a, b)) => (a.min(first), b.max(last)),
        None => (first, last),
    }
}

fn backwards(file: &Path, topic: &str, t: u64, last: u64) -> SessionError {
    SessionError::topic(
        file,
        topic,
        Some(t),
        format!(
            "time goes backwards: the previous message was at {} s",
            super::error::bag_time(last)
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

/// Lists a channel's topic and type among the bag's topics (once); returns the type.
fn note_topic(seen: &mut Vec<(String, String)>, channel: &mcap::Channel<'_>) -> String {
    let schema_name = channel
        .schema
        .as_ref()
        .map(|s| s.name.clone())
        .unwrap_or_else(|| "no schema".into());
    if !seen.iter().any(|(t, _)| *t == channel.topic) {
        seen.push((channel.topic.clone(), schema_name.clone()));
    }
    schema_name
}

/// Check a channel the first time it appears: a spec topic must have a supported type
/// whose definition in the bag matches the decoder, in CDR.
fn check_channel(
    file: &Path,
    channel: &mcap::Channel<'_>,
    roles: &[(String, Role)],
    seen: &mut Vec<(String, String)>,
) -> Result<Option<Checked>, SessionError> {
    let schema_name = note_topic(seen, channel);
    let Some(&(_, role)) = roles.iter().find(|(t, _)| *t == channel.topic) else {
        return Ok(None);
    };
    let err = |m: String| SessionError::topic(file, &channel.topic, None, m);
    let ty = MsgType::from_name(&schema_name).filter(|&ty| type_fits(role, ty));
    let Some(ty) = ty else {
        return Err(err(format!(
            "its message type is {}; the spec reads it as {}",
            shorten(&schema_name),
            allowed(role)
        )));
    };
    if channel.message_encoding != "cdr" {
        return Err(err(format!(
            "messages are encoded as `{}`, not ROS 2 CDR",
            shorten(&channel.message_encoding)
        )));
    }
    if let Some(schema) = &channel.schema {
        cdr::check_schema(ty, &schema.encoding, &schema.data).map_err(err)?;
    }
    Ok(Some(Checked {
        role,
        kind: match ty {
            MsgType::MultiArray(k) => Some(k),
            _ => None,
        },
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_lists_files_indented_or_not_and_in_flow_style() {
        let p = Path::new("metadata.yaml");
        let rosbag2 = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
                       relative_file_paths:\n    - b_0.mcap\n    - \"b_1.mcap\"\n  duration:\n";
        let names = |v: Vec<(usize, String)>| v.into_iter().map(|(_, n)| n).collect::<Vec<_>>();
        assert_eq!(
            names(metadata_files(rosbag2, p).unwrap()),
            ["b_0.mcap", "b_1.mcap"]
        );
        let compact = "x:\n  relative_file_paths:\n  - a.mcap\n  - 'c.mcap'\n  ros_distro: r\n";
        assert_eq!(
            names(metadata_files(compact, p).unwrap()),
            ["a.mcap", "c.mcap"]
        );
        let flow = "relative_file_paths: [a.mcap, b.mcap]\n";
        assert_eq!(
            names(metadata_files(flow, p).unwrap()),
            ["a.mcap", "b.mcap"]
        );
        let sqlite = "storage_identifier: sqlite3\nrelative_file_paths:\n- a.db3\n";
        let e = metadata_files(sqlite, p).unwrap_err().to_string();
        assert!(
            e.contains("metadata.yaml:1:") && e.contains("sqlite3"),
            "{e}"
        );
    }
}
