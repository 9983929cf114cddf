//! Reading one MCAP file of a bag, streaming.

use std::borrow::Cow;
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use super::Bag;
use super::messages::At;
use super::records::{
    CHANNEL, CHUNK, CHUNK_INDEX, ChunkAt, DATA_END, FIELDS, FOOTER, MESSAGE, SCHEMA, chunk_records,
    chunks_sound, fields_fit, mcap_error, parse_chunk_index, record_header, truncated,
};
use super::topics::{Checked, Role, check_channel, note_topic};
use crate::session::SessionError;
use crate::session::cdr::ArrayKind;
use crate::session::spec::ImportSpec;

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
pub(super) fn read_file(
    file: &Path,
    spec: &ImportSpec,
    roles: &[(String, Role)],
    bag: &mut Bag,
    seen: &mut Vec<(String, String)>,
) -> Result<(), SessionError> {
    let io = |e: std::io::Error| SessionError::io(file, e);
    let f = File::open(file).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut input = BufReader::with_capacity(1 << 16, f);
    let magic = mcap::MAGIC;
    let mut head = [0u8; 8];
    if len < 8 || input.read_exact(&mut head).is_err() || head != *magic {
        return Err(mcap_error(file, mcap::McapError::BadMagic));
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
        let io = |e: std::io::Error| SessionError::io(file, e);
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
                    .map_err(|e| SessionError::io(file, e))?,
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
        let io = |e: std::io::Error| SessionError::io(file, e);
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
        let io = |e: std::io::Error| SessionError::io(file, e);
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
            .map_err(|e| SessionError::io(self.file, e))?;
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
            .map_err(|e| SessionError::io(file, e))?;
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
                .map_err(|e| SessionError::io(file, e))
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
        let damaged = |e: mcap::McapError| mcap_error(file, e);
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

    /// A message: its time widens the bag's span, and a channel the spec reads has the
    /// message decoded into its topic's rows.
    fn message(
        &mut self,
        header: &mcap::records::MessageHeader,
        data: &[u8],
    ) -> Result<(), SessionError> {
        let (file, spec, roles) = (self.file, self.spec, self.roles);
        let t = header.log_time;
        self.bag.span = Some(widen(self.bag.span, t, t));
        let Some(Checked { role, kind }) = self.checked_channel(header.channel_id)? else {
            return Ok(());
        };
        let topic = roles
            .iter()
            .find(|(_, r)| *r == role)
            .map_or("", |(t, _)| t.as_str());
        let at = At { file, topic, t };
        let bag = &mut *self.bag;
        match role {
            Role::Tactile(i) => at.tactile(
                &mut bag.tactile[i],
                spec,
                kind.unwrap_or(ArrayKind::F64),
                data,
                &mut self.scratch,
            ),
            Role::Joints => at.joint_state(bag.joints.as_mut(), &self.joint_names, data),
            Role::Events => at.event(&mut bag.events, data),
        }
    }
}

/// The time span `span` widened to hold `first..=last`.
fn widen(span: Option<(u64, u64)>, first: u64, last: u64) -> (u64, u64) {
    match span {
        Some((a, b)) => (a.min(first), b.max(last)),
        None => (first, last),
    }
}
