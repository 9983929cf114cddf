//! Reading a ROS 2 bag stored as MCAP: a `.mcap` file, or a bag folder as `ros2 bag record`
//! writes it (`metadata.yaml` and one or more `.mcap` files, read in the order the metadata
//! lists them). Only the topics the spec names are decoded, each checked against its
//! definition in the bag; the others are skipped whatever their type.
//!
//! Time is the bag time of a message (its MCAP log time, ns since the epoch): every topic
//! then shares one clock, which is also the clock of a windows CSV.

use std::borrow::Cow;
use std::collections::HashMap;
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

/// Reads one MCAP file of the bag.
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
    let bytes = std::fs::read(file).map_err(|e| SessionError::io(file, &e))?;
    let magic = mcap::MAGIC;
    if !bytes.starts_with(magic) {
        return Err(mcap_error(file, &mcap::McapError::BadMagic));
    }
    if bytes.len() < 2 * magic.len() || !bytes.ends_with(magic) {
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
    };
    reader.records(&bytes[magic.len()..bytes.len() - magic.len()], false)
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
}

impl FileReader<'_> {
    /// Reads the records of the file's data section, or of one chunk (`in_chunk`), up to the
    /// data end record. The summary section after it repeats what the data section defines.
    fn records(&mut self, mut rest: &[u8], in_chunk: bool) -> Result<(), SessionError> {
        use mcap::records::Record;
        let file = self.file;
        let damaged = |e: mcap::McapError| mcap_error(file, &e);
        while !rest.is_empty() {
            // A record: opcode (1 byte), body length (u64), body.
            let (opcode, after) = (rest[0], &rest[1..]);
            let Some((len, after)) = after.split_first_chunk::<8>() else {
                return Err(truncated(file, in_chunk, "a record's length", after.len()));
            };
            let len = u64::from_le_bytes(*len);
            if len > after.len() as u64 {
                return Err(truncated(
                    file,
                    in_chunk,
                    &format!("a record (opcode {opcode:#04x}) of {len} bytes"),
                    after.len(),
                ));
            }
            let (body, after) = after.split_at(len as usize);
            rest = after;
            let Some(&(_, fields)) = FIELDS.iter().find(|(op, _)| *op == opcode) else {
                if opcode == DATA_END {
                    break;
                }
                continue;
            };
            fields_fit(fields, body).map_err(|what| {
                SessionError::file(
                    file,
                    format!("the bag is damaged: {what} does not fit in its record (opcode {opcode:#04x})"),
                )
            })?;
            match mcap::parse_record(opcode, body).map_err(damaged)? {
                Record::Schema { header, data } => self
                    .links
                    .add_schema(header, Cow::Owned(data.into_owned()))
                    .map_err(damaged)?,
                Record::Channel(channel) => self.links.add_channel(channel).map_err(damaged)?,
                Record::Message { header, data } => self.message(&header, &data)?,
                Record::Chunk { .. } if in_chunk => {
                    return Err(SessionError::file(
                        file,
                        "the bag is damaged: a chunk inside a chunk",
                    ));
                }
                Record::Chunk { header, data } => {
                    let inner = chunk_records(file, &header, &data)?;
                    self.records(&inner, true)?;
                }
                _ => {}
            }
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
        let scratch = &mut self.scratch;
        let id = header.channel_id;
        let t = header.log_time;
        bag.span = Some(match bag.span {
            Some((a, b)) => (a.min(t), b.max(t)),
            None => (t, t),
        });
        let checked = match self.checked.get(&id) {
            Some(c) => *c,
            None => {
                let Some(channel) = self.links.get(id) else {
                    return Err(SessionError::file(
                        file,
                        format!("a message refers to channel {id}, which the bag never defines"),
                    ));
                };
                let c = check_channel(file, &channel, roles, self.seen)?;
                self.checked.insert(id, c);
                c
            }
        };
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

/// Check a channel the first time it appears: a spec topic must have a supported type
/// whose definition in the bag matches the decoder, in CDR.
fn check_channel(
    file: &Path,
    channel: &mcap::Channel<'_>,
    roles: &[(String, Role)],
    seen: &mut Vec<(String, String)>,
) -> Result<Option<Checked>, SessionError> {
    let schema_name = channel
        .schema
        .as_ref()
        .map(|s| s.name.clone())
        .unwrap_or_else(|| "no schema".into());
    if !seen.iter().any(|(t, _)| *t == channel.topic) {
        seen.push((channel.topic.clone(), schema_name.clone()));
    }
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
