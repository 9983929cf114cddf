//! Importer of a long-format CSV with an import spec: one row per frame, for recordings
//! from anything else (MATLAB, LabVIEW, Python).
//!
//! Columns are found by name in the header, in any order; others are ignored:
//! `grasp` (any id; a grasp's rows are consecutive), `time` (seconds, any origin, never
//! decreasing within a grasp), `object`, one column per label set of the spec, the taxels
//! `<sensor>_1` … `<sensor>_<n>` of each sensor, one column per joint name, and optionally
//! `key` (1 on a grasp's key frame). A frame's `t` is its time from the grasp's first row.

use std::borrow::Cow;
use std::path::Path;

use super::error::{parse_number, read_text, shorten};
use super::spec::{ImportSpec, RawGrasp, assemble};
use super::{Frame, Session, SessionError};

/// Split one CSV line into fields: commas separate, a field in double quotes may hold
/// commas and doubled quotes (`""`).
pub fn split_line(line: &str) -> Result<Vec<Cow<'_, str>>, String> {
    let mut fields = Vec::new();
    let mut rest = line;
    loop {
        let trimmed = rest.trim_start();
        if let Some(quoted) = trimmed.strip_prefix('"') {
            let mut value = String::new();
            let mut chars = quoted.char_indices();
            let after = loop {
                match chars.next() {
                    Some((i, '"')) => {
                        if quoted[i + 1..].starts_with('"') {
                            value.push('"');
                            chars.next();
                        } else {
                            break &quoted[i + 1..];
                        }
                    }
                    Some((_, c)) => value.push(c),
                    None => return Err("a quoted field is not closed".into()),
                }
            };
            fields.push(Cow::Owned(value));
            let after = after.trim_start();
            match after.strip_prefix(',') {
                Some(next) => rest = next,
                None if after.is_empty() => return Ok(fields),
                None => return Err("text after a closing quote".into()),
            }
        } else {
            match rest.split_once(',') {
                Some((field, next)) => {
                    fields.push(Cow::Borrowed(field));
                    rest = next;
                }
                None => {
                    fields.push(Cow::Borrowed(rest));
                    return Ok(fields);
                }
            }
        }
    }
}

/// Where each spec field is in the header.
struct Columns {
    grasp: usize,
    time: usize,
    object: usize,
    labels: Vec<usize>,
    /// Per sensor, the column of each taxel.
    taxels: Vec<Vec<usize>>,
    joints: Vec<usize>,
    key: Option<usize>,
}

/// A header naming one column twice: found by name, the second would be silently ignored.
/// Names both columns (1-based) of the first repeated name; empty names are not compared.
pub fn duplicate_column<S: AsRef<str>>(names: &[S]) -> Result<(), String> {
    for (j, b) in names.iter().enumerate() {
        let b = b.as_ref().trim();
        if b.is_empty() {
            continue;
        }
        if let Some(i) = names[..j].iter().position(|a| a.as_ref().trim() == b) {
            return Err(format!(
                "columns {} and {} are both named `{}`",
                i + 1,
                j + 1,
                shorten(b)
            ));
        }
    }
    Ok(())
}

fn columns(names: &[Cow<'_, str>], spec: &ImportSpec) -> Result<Columns, String> {
    duplicate_column(names)?;
    let find = |name: &str| names.iter().position(|n| n.trim() == name);
    let need = |name: &str| find(name).ok_or_else(|| format!("no `{name}` column"));
    Ok(Columns {
        grasp: need("grasp")?,
        time: need("time")?,
        object: need("object")?,
        labels: spec
            .recorded_label_sets()
            .iter()
            .map(|l| need(&l.name))
            .collect::<Result<_, _>>()?,
        taxels: spec
            .sensors
            .iter()
            .map(|s| {
                (1..=s.sensor.layout.taxel_count())
                    .map(|k| need(&format!("{}_{k}", s.sensor.name)))
                    .collect::<Result<_, _>>()
            })
            .collect::<Result<_, _>>()?,
        joints: spec
            .encoder_names()
            .iter()
            .map(|j| need(j))
            .collect::<Result<_, _>>()?,
        key: find("key"),
    })
}

/// The grasp being read: its id, labels and first line, and its frames so far.
struct Open {
    id: String,
    line: usize,
    origin: f64,
    grasp: RawGrasp,
    key_line: Option<usize>,
}

/// Import a long-format CSV as the spec describes.
pub fn import_long_csv(path: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    parse_long_csv(&read_text(path)?, path, spec)
}

/// Parse long-format CSV text (`path` names it in errors).
pub fn parse_long_csv(text: &str, path: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((header_no, header)) = lines.next() else {
        return Err(SessionError::file(path, "the file is empty"));
    };
    let names = split_line(header.trim_start_matches('\u{feff}'))
        .map_err(|m| SessionError::line(path, header_no, m))?;
    let cols = columns(&names, spec).map_err(|m| SessionError::line(path, header_no, m))?;
    let sets = spec.recorded_label_sets();
    let mut done: Vec<RawGrasp> = Vec::new();
    let mut done_ids: Vec<String> = Vec::new();
    let mut open: Option<Open> = None;
    for (no, line) in lines {
        let fields = split_line(line).map_err(|m| SessionError::line(path, no, m))?;
        if fields.len() != names.len() {
            return Err(SessionError::line(
                path,
                no,
                format!("{} values, expected {}", fields.len(), names.len()),
            ));
        }
        let field = |c: usize| fields[c].trim();
        let name = |c: usize| names[c].trim().to_string();
        let number = |c: usize| parse_number(path, no, &name(c), field(c));
        let id = field(cols.grasp);
        if id.is_empty() {
            return Err(SessionError::line_field(
                path,
                no,
                "grasp",
                "empty grasp id",
            ));
        }
        let object = field(cols.object);
        let classes = sets
            .iter()
            .zip(&cols.labels)
            .map(|(set, &c)| {
                spec.class_index(set, field(c))
                    .map_err(|m| SessionError::line_field(path, no, &set.name, m))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let time = number(cols.time)?;
        if open.as_ref().is_none_or(|o| o.id != id) {
            if done_ids.iter().any(|d| d == id) {
                return Err(SessionError::line_field(
                    path,
                    no,
                    "grasp",
                    format!(
                        "grasp `{}` appears again after other grasps (a grasp's rows must be \
                         consecutive)",
                        shorten(id)
                    ),
                ));
            }
            spec.check_object(object)
                .map_err(|m| SessionError::line_field(path, no, "object", m))?;
            if let Some(o) = open.take() {
                done_ids.push(o.id);
                done.push(o.grasp);
            }
            open = Some(Open {
                id: id.to_string(),
                line: no,
                origin: time,
                grasp: RawGrasp {
                    object: object.to_string(),
                    classes: classes.clone(),
                    frames: Vec::new(),
                    key_frame: None,
                },
                key_line: None,
            });
        }
        let Some(o) = open.as_mut() else {
            continue;
        };
        if object != o.grasp.object {
            return Err(SessionError::line_field(
                path,
                no,
                "object",
                format!(
                    "`{}` differs from `{}` on the grasp's first line ({})",
                    shorten(object),
                    o.grasp.object,
                    o.line
                ),
            ));
        }
        if let Some(k) = classes
            .iter()
            .zip(&o.grasp.classes)
            .position(|(a, b)| a != b)
        {
            return Err(SessionError::line_field(
                path,
                no,
                &sets[k].name,
                format!(
                    "the label changes within grasp `{}` (line {})",
                    o.id, o.line
                ),
            ));
        }
        let t = time - o.origin;
        if let Some(prev) = o.grasp.frames.last()
            && t < prev.t
        {
            return Err(SessionError::line_field(
                path,
                no,
                "time",
                format!(
                    "time goes backwards within grasp `{}`: {time} after {}",
                    o.id,
                    prev.t + o.origin
                ),
            ));
        }
        let mut taxels = Vec::with_capacity(cols.taxels.len());
        for (s, taxel_cols) in cols.taxels.iter().enumerate() {
            let sensor = &spec.sensors[s].sensor;
            let mut values = Vec::with_capacity(taxel_cols.len());
            for &c in taxel_cols {
                let v = number(c)?;
                if !sensor.in_range(v) {
                    return Err(SessionError::line_field(
                        path,
                        no,
                        name(c),
                        format!(
                            "reading {v} is outside sensor `{}`'s range {}",
                            sensor.name,
                            sensor.range_text()
                        ),
                    ));
                }
                values.push(v);
            }
            taxels.push(values);
        }
        let encoders = cols
            .joints
            .iter()
            .map(|&c| number(c))
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(c) = cols.key {
            match field(c) {
                "" | "0" => {}
                "1" => {
                    if let Some(first) = o.key_line {
                        return Err(SessionError::line_field(
                            path,
                            no,
                            "key",
                            format!("grasp `{}` already has its key frame on line {first}", o.id),
                        ));
                    }
                    o.key_line = Some(no);
                    o.grasp.key_frame = Some(o.grasp.frames.len());
                }
                other => {
                    return Err(SessionError::line_field(
                        path,
                        no,
                        "key",
                        format!("`{}` is not 1, 0 or empty", shorten(other)),
                    ));
                }
            }
        }
        o.grasp.frames.push(Frame {
            t,
            taxels,
            encoders,
        });
    }
    if let Some(o) = open {
        done.push(o.grasp);
    }
    if done.is_empty() {
        return Err(SessionError::file(
            path,
            "the file has a header but no rows",
        ));
    }
    let how = "One CSV row per frame; a frame's time is from its grasp's first row.";
    assemble(spec, path, "long-format CSV", how, done)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_fields_may_hold_commas_and_quotes() {
        let f = split_line(r#"a, "b, c" ,"say ""hi""",,d"#).unwrap();
        assert_eq!(f, vec!["a", "b, c", "say \"hi\"", "", "d"]);
        assert!(split_line(r#"a,"open"#).is_err());
        assert!(split_line(r#""x"y"#).is_err());
    }
}
