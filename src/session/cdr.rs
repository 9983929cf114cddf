//! ROS 2 CDR decoding of exactly the messages a tactile recording uses: the four numeric
//! `std_msgs` MultiArrays, `sensor_msgs/msg/JointState` and `std_msgs/msg/String`.
//!
//! A ROS 2 message on the wire (and in a bag) is a 4-byte encapsulation header — 0x0000
//! big-endian or 0x0001 little-endian plain CDR, then two option bytes — followed by the
//! fields in order, each primitive aligned to its size counted from the end of the header.
//! Sequences and strings are a `uint32` length, then the elements; a string's length
//! counts its terminating NUL. Before decoding, the message definition stored in the bag
//! is checked to declare exactly the fields decoded here, so a custom message that only
//! borrows a standard name is refused rather than misread.

/// Why a message definition is not the standard one, or a message does not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    #[error("the bag's definition of {ty} is not UTF-8")]
    DefinitionNotUtf8 { ty: &'static str },
    /// A line of the definition of message `ty` that is not `TYPE NAME`.
    #[error("{ty}: `{line}` is not a field")]
    NotAField { ty: String, line: String },
    /// A definition of `ty` (a message nested `inside` another) with other fields.
    #[error(
        "the bag defines {ty}{} as `{got}`, not the standard `{want}`",
        inside.map(|o| format!(" (inside {o})")).unwrap_or_default()
    )]
    NotStandard {
        ty: String,
        inside: Option<&'static str>,
        got: String,
        want: String,
    },
    #[error("the bag's IDL definition of {ty} does not declare `{field}`")]
    IdlUndeclared {
        ty: &'static str,
        field: &'static str,
    },
    #[error(
        "{ty} is stored with schema encoding `{encoding}`, not a ROS 2 message definition \
         (ros2msg or ros2idl)"
    )]
    SchemaEncoding { ty: &'static str, encoding: String },
    #[error("the message has {len} bytes, too few for a CDR header")]
    NoHeader { len: usize },
    #[error("CDR encapsulation 0x{:02x}{:02x} is not plain CDR (0x0000 or 0x0001)", .0[0], .0[1])]
    Encapsulation([u8; 2]),
    #[error("the message ends inside `{field}` (byte {at} of {len})")]
    EndsInside {
        field: &'static str,
        at: usize,
        len: usize,
    },
    #[error("`{field}` claims {count} elements but only {left} bytes are left")]
    Overlong {
        field: &'static str,
        count: usize,
        left: usize,
    },
    #[error("`{field}` is not NUL-terminated")]
    NotNulTerminated { field: &'static str },
    #[error("`{field}` is not UTF-8")]
    NotUtf8 { field: &'static str },
    #[error("layout.data_offset is {offset} but the array holds {len} values")]
    DataOffset { offset: usize, len: usize },
}

/// Element type of a MultiArray's `data`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayKind {
    F32,
    F64,
    I16,
    I32,
}

impl ArrayKind {
    fn size(self) -> usize {
        match self {
            ArrayKind::I16 => 2,
            ArrayKind::F32 | ArrayKind::I32 => 4,
            ArrayKind::F64 => 8,
        }
    }
}

/// The message types the importer reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MsgType {
    MultiArray(ArrayKind),
    JointState,
    String,
}

/// The tactile types, as the spec's documentation lists them.
pub const TACTILE_TYPES: &str = "std_msgs/msg/Float32MultiArray, Float64MultiArray, \
Int16MultiArray or Int32MultiArray";

impl MsgType {
    /// The type of a schema name: `pkg/msg/Type` (ROS 2) or `pkg/Type`.
    pub fn from_name(name: &str) -> Option<MsgType> {
        let short = match name.split('/').collect::<Vec<_>>()[..] {
            [pkg, "msg", ty] | [pkg, ty] => (pkg, ty),
            _ => return None,
        };
        Some(match short {
            ("std_msgs", "Float32MultiArray") => MsgType::MultiArray(ArrayKind::F32),
            ("std_msgs", "Float64MultiArray") => MsgType::MultiArray(ArrayKind::F64),
            ("std_msgs", "Int16MultiArray") => MsgType::MultiArray(ArrayKind::I16),
            ("std_msgs", "Int32MultiArray") => MsgType::MultiArray(ArrayKind::I32),
            ("sensor_msgs", "JointState") => MsgType::JointState,
            ("std_msgs", "String") => MsgType::String,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            MsgType::MultiArray(ArrayKind::F32) => "std_msgs/msg/Float32MultiArray",
            MsgType::MultiArray(ArrayKind::F64) => "std_msgs/msg/Float64MultiArray",
            MsgType::MultiArray(ArrayKind::I16) => "std_msgs/msg/Int16MultiArray",
            MsgType::MultiArray(ArrayKind::I32) => "std_msgs/msg/Int32MultiArray",
            MsgType::JointState => "sensor_msgs/msg/JointState",
            MsgType::String => "std_msgs/msg/String",
        }
    }

    /// The top-level fields (type without package, name) the decoder reads.
    fn fields(self) -> Vec<(&'static str, &'static str)> {
        match self {
            MsgType::MultiArray(kind) => vec![
                ("MultiArrayLayout", "layout"),
                (
                    match kind {
                        ArrayKind::F32 => "float32[]",
                        ArrayKind::F64 => "float64[]",
                        ArrayKind::I16 => "int16[]",
                        ArrayKind::I32 => "int32[]",
                    },
                    "data",
                ),
            ],
            MsgType::JointState => vec![
                ("Header", "header"),
                ("string[]", "name"),
                ("float64[]", "position"),
                ("float64[]", "velocity"),
                ("float64[]", "effort"),
            ],
            MsgType::String => vec![("string", "data")],
        }
    }
}

/// The nested types the decoder relies on, checked when the definition includes them.
const NESTED: [(&str, &[(&str, &str)]); 4] = [
    (
        "MultiArrayLayout",
        &[("MultiArrayDimension[]", "dim"), ("uint32", "data_offset")],
    ),
    (
        "MultiArrayDimension",
        &[
            ("string", "label"),
            ("uint32", "size"),
            ("uint32", "stride"),
        ],
    ),
    ("Header", &[("Time", "stamp"), ("string", "frame_id")]),
    ("Time", &[("int32", "sec"), ("uint32", "nanosec")]),
];

/// A field type without its package (`std_msgs/Header` → `Header`); ROS 1's `time`, which
/// some writers still emit for a header's stamp, is `builtin_interfaces/Time`.
fn short_type(t: &str) -> &str {
    let t = t.rsplit('/').next().unwrap_or(t);
    if t == "time" { "Time" } else { t }
}

/// The (type, name) of each field of one `.msg` section, constants left out.
/// The fields of the definition of message `ty`.
fn msg_fields(ty: &str, section: &str) -> Result<Vec<(String, String)>, CdrError> {
    let mut out = Vec::new();
    for line in section.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if tokens.len() < 2 {
            return Err(CdrError::NotAField {
                ty: ty.to_string(),
                line: line.to_string(),
            });
        }
        if tokens[1].contains('=') || tokens.get(2).is_some_and(|t| t.starts_with('=')) {
            continue;
        }
        out.push((short_type(tokens[0]).to_string(), tokens[1].to_string()));
    }
    Ok(out)
}

fn describe(fields: &[(impl AsRef<str>, impl AsRef<str>)]) -> String {
    let parts: Vec<String> = fields
        .iter()
        .map(|(t, n)| format!("{} {}", t.as_ref(), n.as_ref()))
        .collect();
    parts.join("; ")
}

/// Check the definition a bag stores for `ty` against the fields the decoder reads.
pub fn check_schema(ty: MsgType, encoding: &str, text: &[u8]) -> Result<(), CdrError> {
    let text =
        std::str::from_utf8(text).map_err(|_| CdrError::DefinitionNotUtf8 { ty: ty.name() })?;
    match encoding {
        "ros2msg" => {
            // Sections: the message itself, then `MSG: pkg/Type` blocks separated by lines
            // of `=`.
            let mut sections = text.split('\n').fold(vec![String::new()], |mut acc, line| {
                if line.trim_start().starts_with("==") {
                    acc.push(String::new());
                } else if let Some(last) = acc.last_mut() {
                    last.push_str(line);
                    last.push('\n');
                }
                acc
            });
            let main = sections.remove(0);
            let want = ty.fields();
            let got = msg_fields(ty.name(), &main)?;
            let same = got.len() == want.len()
                && got.iter().zip(&want).all(|(g, w)| g.0 == w.0 && g.1 == w.1);
            if !same {
                return Err(CdrError::NotStandard {
                    ty: ty.name().to_string(),
                    inside: None,
                    got: describe(&got),
                    want: describe(&want),
                });
            }
            for section in &sections {
                let mut lines = section.lines().skip_while(|l| l.trim().is_empty());
                let Some(name) = lines
                    .next()
                    .and_then(|l| l.trim().strip_prefix("MSG:"))
                    .map(|n| short_type(n.trim()).to_string())
                else {
                    continue;
                };
                let Some((_, nested)) = NESTED.iter().find(|(n, _)| *n == name) else {
                    continue;
                };
                let body: String = lines.map(|l| format!("{l}\n")).collect();
                let got = msg_fields(&name, &body)?;
                let same = got.len() == nested.len()
                    && got
                        .iter()
                        .zip(nested.iter())
                        .all(|(g, w)| g.0 == w.0 && g.1 == w.1);
                if !same {
                    return Err(CdrError::NotStandard {
                        ty: name,
                        inside: Some(ty.name()),
                        got: describe(&got),
                        want: describe(nested),
                    });
                }
            }
            Ok(())
        }
        "ros2idl" => {
            // An IDL definition: each field the decoder reads must be declared by name.
            for (_, name) in ty.fields() {
                let declared = text
                    .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ';'))
                    .any(|w| w == format!("{name};"));
                if !declared {
                    return Err(CdrError::IdlUndeclared {
                        ty: ty.name(),
                        field: name,
                    });
                }
            }
            Ok(())
        }
        other => Err(CdrError::SchemaEncoding {
            ty: ty.name(),
            encoding: other.to_string(),
        }),
    }
}

/// A cursor over one CDR message.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    little: bool,
}

const HEADER: usize = 4;

impl<'a> Reader<'a> {
    fn new(buf: &'a [u8]) -> Result<Self, CdrError> {
        if buf.len() < HEADER {
            return Err(CdrError::NoHeader { len: buf.len() });
        }
        let little = match [buf[0], buf[1]] {
            [0, 0] => false,
            [0, 1] => true,
            [a, b] => return Err(CdrError::Encapsulation([a, b])),
        };
        Ok(Reader {
            buf,
            pos: HEADER,
            little,
        })
    }

    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CdrError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        match end {
            Some(end) => {
                let s = &self.buf[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(CdrError::EndsInside {
                field: what,
                at: self.pos,
                len: self.buf.len(),
            }),
        }
    }

    fn align(&mut self, n: usize) {
        let rel = self.pos - HEADER;
        self.pos += (n - rel % n) % n;
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, CdrError> {
        self.align(4);
        let b: [u8; 4] = self.take(4, what)?.try_into().unwrap_or_default();
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// A sequence length, checked against the bytes left so a damaged length cannot
    /// ask for a huge allocation.
    fn len(&mut self, elem: usize, what: &'static str) -> Result<usize, CdrError> {
        let n = self.u32(what)? as usize;
        let left = self.buf.len().saturating_sub(self.pos);
        if n.saturating_mul(elem) > left {
            return Err(CdrError::Overlong {
                field: what,
                count: n,
                left,
            });
        }
        Ok(n)
    }

    fn string(&mut self, what: &'static str) -> Result<&'a str, CdrError> {
        let n = self.len(1, what)?;
        let bytes = self.take(n, what)?;
        // The length counts the terminating NUL; an empty string may still be length 0.
        let bytes = match bytes.split_last() {
            Some((0, rest)) => rest,
            Some(_) => return Err(CdrError::NotNulTerminated { field: what }),
            None => bytes,
        };
        std::str::from_utf8(bytes).map_err(|_| CdrError::NotUtf8 { field: what })
    }

    fn skip_sequence(&mut self, elem: usize, what: &'static str) -> Result<(), CdrError> {
        let n = self.len(elem, what)?;
        if n > 0 {
            self.align(elem);
        }
        self.take(n * elem, what).map(|_| ())
    }

    fn f64_sequence(&mut self, what: &'static str) -> Result<Vec<f64>, CdrError> {
        let n = self.len(8, what)?;
        if n > 0 {
            self.align(8);
        }
        let bytes = self.take(n * 8, what)?;
        Ok(bytes
            .chunks_exact(8)
            .map(|c| {
                let b: [u8; 8] = c.try_into().unwrap_or_default();
                if self.little {
                    f64::from_le_bytes(b)
                } else {
                    f64::from_be_bytes(b)
                }
            })
            .collect())
    }
}

/// Decode a MultiArray, putting its values after `layout.data_offset` into `out`
/// (cleared first).
pub fn decode_multiarray(data: &[u8], kind: ArrayKind, out: &mut Vec<f64>) -> Result<(), CdrError> {
    let mut r = Reader::new(data)?;
    let dims = r.len(12, "layout.dim")?;
    for _ in 0..dims {
        r.string("layout.dim.label")?;
        r.u32("layout.dim.size")?;
        r.u32("layout.dim.stride")?;
    }
    let offset = r.u32("layout.data_offset")? as usize;
    let size = kind.size();
    let n = r.len(size, "data")?;
    if n > 0 {
        r.align(size);
    }
    let bytes = r.take(n * size, "data")?;
    if offset > n {
        return Err(CdrError::DataOffset { offset, len: n });
    }
    out.clear();
    out.reserve(n - offset);
    let little = r.little;
    let values = bytes.chunks_exact(size).skip(offset);
    macro_rules! push {
        ($t:ty) => {
            out.extend(values.map(|c| {
                let b = c.try_into().unwrap_or_default();
                f64::from(if little {
                    <$t>::from_le_bytes(b)
                } else {
                    <$t>::from_be_bytes(b)
                })
            }))
        };
    }
    match kind {
        ArrayKind::F32 => push!(f32),
        ArrayKind::F64 => push!(f64),
        ArrayKind::I16 => push!(i16),
        ArrayKind::I32 => push!(i32),
    }
    Ok(())
}

/// The fields of a `JointState` the importer uses.
pub struct JointState<'a> {
    pub names: Vec<&'a str>,
    pub positions: Vec<f64>,
}

pub fn decode_joint_state(data: &[u8]) -> Result<JointState<'_>, CdrError> {
    let mut r = Reader::new(data)?;
    r.u32("header.stamp.sec")?;
    r.u32("header.stamp.nanosec")?;
    r.string("header.frame_id")?;
    let n = r.len(4, "name")?;
    let names = (0..n)
        .map(|_| r.string("name"))
        .collect::<Result<Vec<_>, _>>()?;
    let positions = r.f64_sequence("position")?;
    r.skip_sequence(8, "velocity")?;
    r.skip_sequence(8, "effort")?;
    Ok(JointState { names, positions })
}

pub fn decode_string(data: &[u8]) -> Result<&str, CdrError> {
    Reader::new(data)?.string("data")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Float32MultiArray with one dimension labelled "ab", written by hand in
    /// little-endian CDR.
    fn float32_message() -> Vec<u8> {
        let mut m = vec![0, 1, 0, 0];
        m.extend(1u32.to_le_bytes()); // dim: 1 element
        m.extend(3u32.to_le_bytes()); // label "ab\0"
        m.extend(b"ab\0");
        m.push(0); // pad to 4
        m.extend(2u32.to_le_bytes()); // size
        m.extend(2u32.to_le_bytes()); // stride
        m.extend(0u32.to_le_bytes()); // data_offset
        m.extend(2u32.to_le_bytes()); // data: 2 elements
        m.extend(1.5f32.to_le_bytes());
        m.extend((-2.0f32).to_le_bytes());
        m
    }

    #[test]
    fn decodes_a_hand_written_float32_array() {
        let mut out = Vec::new();
        decode_multiarray(&float32_message(), ArrayKind::F32, &mut out).unwrap();
        assert_eq!(out, vec![1.5, -2.0]);
    }

    #[test]
    fn a_cut_message_is_an_error_not_a_panic() {
        let m = float32_message();
        let mut out = Vec::new();
        for n in 0..m.len() {
            assert!(decode_multiarray(&m[..n], ArrayKind::F32, &mut out).is_err());
        }
    }

    #[test]
    fn the_standard_definition_passes_and_a_look_alike_fails() {
        let std = "# doc\nMultiArrayLayout  layout        # layout\nfloat32[]  data\n\
                   ================\nMSG: std_msgs/MultiArrayLayout\n\
                   MultiArrayDimension[] dim\nuint32 data_offset\n";
        let ty = MsgType::MultiArray(ArrayKind::F32);
        assert_eq!(check_schema(ty, "ros2msg", std.as_bytes()), Ok(()));
        let other = "MultiArrayLayout layout\nfloat64[] data\n";
        let e = check_schema(ty, "ros2msg", other.as_bytes()).unwrap_err();
        assert!(
            matches!(&e, CdrError::NotStandard { got, inside: None, .. } if got.contains("float64[] data")),
            "{e:?}"
        );
        assert!(e.to_string().contains("float64[] data"), "{e}");
    }
}
