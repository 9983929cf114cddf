//! MCAP records framed by hand: every length checked against the bytes that hold it
//! before the MCAP library parses a record, and chunks decompressed growing with what they
//! really hold (the reader of a file says why).

use std::borrow::Cow;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::session::SessionError;
use crate::session::error::shorten;

/// The footer's opcode and the summary's records the importer reads.
pub(super) const FOOTER: u8 = 0x02;
pub(super) const SCHEMA: u8 = 0x03;
pub(super) const CHANNEL: u8 = 0x04;
pub(super) const MESSAGE: u8 = 0x05;
pub(super) const CHUNK: u8 = 0x06;
pub(super) const CHUNK_INDEX: u8 = 0x08;
/// The data end record's opcode: the data section ends there.
pub(super) const DATA_END: u8 = 0x0F;

/// The MCAP library's error, in words about the file.
pub(super) fn mcap_error(file: &Path, e: mcap::McapError) -> SessionError {
    use mcap::McapError as E;
    let what = match e {
        E::BadMagic => "not an MCAP file, or its start or end is missing (bad magic bytes)".into(),
        E::UnexpectedEof | E::UnexpectedEoc | E::BadFooter => {
            format!("the bag is truncated ({e})")
        }
        _ => format!("the bag is damaged: {e}"),
    };
    SessionError::file(file, what).with_source(e)
}

/// A zstd chunk that does not decompress: the decoder's error is kept.
fn undecompressed(file: &Path, e: std::io::Error) -> SessionError {
    SessionError::file(
        file,
        format!("the bag is damaged: a zstd chunk does not decompress ({e})"),
    )
    .with_source(e)
}

/// Where a chunk is, which channels it holds messages of, and their time span, from the
/// summary's chunk index.
pub(super) struct ChunkAt {
    pub(super) offset: u64,
    pub(super) length: u64,
    pub(super) times: (u64, u64),
    pub(super) channels: Vec<u16>,
}

/// A chunk index record's fields the importer uses, each checked to lie in the body:
/// message start and end time, chunk offset and length, and the channels of its message
/// indexes.
pub(super) fn parse_chunk_index(body: &[u8]) -> Option<ChunkAt> {
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
pub(super) fn chunks_sound(
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
pub(super) fn record_header(
    input: &mut impl Read,
    file: &Path,
    left: u64,
) -> Result<(u8, u64), SessionError> {
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

/// A record field, for checking that a body holds what its lengths claim.
#[derive(Clone, Copy)]
pub(super) enum Field {
    Fixed(usize),
    /// u32 length, then bytes (a string, or a schema's data).
    Bytes,
    /// u32 length, then string pairs filling it.
    Map,
}

/// The records the importer reads, with their fields up to the last length-prefixed one
/// (what follows it, a message's or chunk's data, is the rest of the body).
pub(super) const FIELDS: [(u8, &[Field]); 4] = [
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
pub(super) fn fields_fit(fields: &[Field], body: &[u8]) -> Result<(), &'static str> {
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
pub(super) fn truncated(file: &Path, in_chunk: bool, what: &str, left: usize) -> SessionError {
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
pub(super) fn chunk_records<'c>(
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
                .map_err(|e| undecompressed(file, e))?;
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
