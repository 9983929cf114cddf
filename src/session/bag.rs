//! Reading a ROS 2 bag stored as MCAP: a `.mcap` file, or a bag folder as `ros2 bag record`
//! writes it (`metadata.yaml` and one or more `.mcap` files, read in the order the metadata
//! lists them). Only the topics the spec names are decoded, each checked against its
//! definition in the bag; the others are skipped whatever their type.
//!
//! Time is the bag time of a message (its MCAP log time, ns since the epoch): every topic
//! then shares one clock, which is also the clock of a windows CSV.

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

/// The most a chunk may expand: zstd's densest block (run-length, 4 bytes for 128 KiB) is
/// 32 768 : 1, and LZ4 cannot reach it.
const MAX_CHUNK_EXPANSION: u64 = 1 << 15;

/// The MCAP library (0.26) reserves the uncompressed size a chunk claims before decompressing
/// it, unchecked, so a damaged size aborts the process on a failed allocation, which no
/// `catch_unwind` can turn into an error (fuzzing found a chunk claiming 116 TB,
/// `fuzz/findings/mcap-abort-huge-buffer.mcap`). The library's top-level reader bounds
/// records by the file's size and leaves chunks compressed, so every chunk's claim is
/// checked with it first.
fn check_chunk_sizes(file: &Path, bytes: &[u8]) -> Result<(), SessionError> {
    let mut records = mcap::read::LinearReader::new(bytes).map_err(|e| mcap_error(file, &e))?;
    loop {
        let next = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| records.next()))
            .map_err(|_| SessionError::file(file, "the bag is damaged: a record does not fit"))?;
        let Some(record) = next else {
            return Ok(());
        };
        if let mcap::records::Record::Chunk { header, data } =
            record.map_err(|e| mcap_error(file, &e))?
        {
            let compressed = data.len() as u64;
            let most = if header.compression.is_empty() {
                compressed
            } else {
                compressed.saturating_mul(MAX_CHUNK_EXPANSION)
            };
            if header.uncompressed_size > most {
                return Err(SessionError::file(
                    file,
                    format!(
                        "the bag is damaged: a chunk of {compressed} bytes ({}) claims {} \
                         bytes uncompressed, more than it can hold",
                        if header.compression.is_empty() {
                            "uncompressed"
                        } else {
                            header.compression.as_str()
                        },
                        header.uncompressed_size
                    ),
                ));
            }
        }
    }
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

fn read_file(
    file: &Path,
    spec: &ImportSpec,
    roles: &[(String, Role)],
    bag: &mut Bag,
    seen: &mut Vec<(String, String)>,
) -> Result<(), SessionError> {
    let bytes = std::fs::read(file).map_err(|e| SessionError::io(file, &e))?;
    check_chunk_sizes(file, &bytes)?;
    let mut stream = mcap::read::RawMessageStream::new(&bytes).map_err(|e| mcap_error(file, &e))?;
    // Channel ids are per file.
    let mut channels: HashMap<u16, Option<Checked>> = HashMap::new();
    let mut scratch: Vec<f64> = Vec::new();
    let joint_names = spec.encoder_names();
    loop {
        // The MCAP library (0.26) panics on some damaged chunks — it reserves an inner
        // record's length before checking it (found by fuzzing, tests/fixtures/ros2/bad/
        // damaged-chunk.mcap): a damaged bag is an error, never a crash. Only the
        // library's step is guarded, so a fault of our own still shows.
        let next = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| stream.next()))
            .map_err(|_| {
                SessionError::file(
                    file,
                    "the bag is damaged: a chunk's records do not fit in it",
                )
            })?;
        let Some(next) = next else {
            break;
        };
        let msg = next.map_err(|e| mcap_error(file, &e))?;
        let id = msg.header.channel_id;
        let t = msg.header.log_time;
        bag.span = Some(match bag.span {
            Some((a, b)) => (a.min(t), b.max(t)),
            None => (t, t),
        });
        let checked = match channels.get(&id) {
            Some(c) => *c,
            None => {
                let Some(channel) = stream.get_channel(id) else {
                    return Err(SessionError::file(
                        file,
                        format!("a message refers to channel {id}, which the bag never defines"),
                    ));
                };
                let c = check_channel(file, &channel, roles, seen)?;
                channels.insert(id, c);
                c
            }
        };
        let Some(Checked { role, kind }) = checked else {
            continue;
        };
        let topic = roles
            .iter()
            .find(|(_, r)| *r == role)
            .map_or("", |(t, _)| t.as_str());
        let at = |m: String| SessionError::topic(file, topic, Some(t), m);
        match role {
            Role::Tactile(i) => {
                let kind = kind.unwrap_or(ArrayKind::F64);
                cdr::decode_multiarray(&msg.data, kind, &mut scratch).map_err(at)?;
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
                tt.values.extend_from_slice(&scratch);
            }
            Role::Joints => {
                let js = cdr::decode_joint_state(&msg.data).map_err(at)?;
                if js.positions.len() != js.names.len() {
                    return Err(at(format!(
                        "{} joint names but {} positions",
                        js.names.len(),
                        js.positions.len()
                    )));
                }
                let Some(jt) = bag.joints.as_mut() else {
                    continue;
                };
                if jt.stamps.last().is_some_and(|&last| t < last) {
                    return Err(backwards(file, topic, t, jt.stamps[jt.stamps.len() - 1]));
                }
                for name in &joint_names {
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
                let text = cdr::decode_string(&msg.data).map_err(at)?;
                if bag.events.last().is_some_and(|&(last, _)| t < last) {
                    let last = bag.events[bag.events.len() - 1].0;
                    return Err(backwards(file, topic, t, last));
                }
                bag.events.push((t, text.to_string()));
            }
        }
    }
    Ok(())
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
