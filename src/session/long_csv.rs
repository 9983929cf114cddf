//! Importer of a long-format CSV with an import spec: one row per frame, for recordings
//! from anything else (MATLAB, LabVIEW, Python).
//!
//! Columns are found by name in the header, in any order; others are ignored:
//! `grasp` (any id; a grasp's rows are consecutive), `time` (seconds, any origin, never
//! decreasing within a grasp), `object`, one column per label set of the spec, the taxels
//! `<sensor>_1` … `<sensor>_<n>` of each sensor, one column per joint name, and optionally
//! `key` (1 on a grasp's key frame). A frame's `t` is its time from the grasp's first row.
//!
//! Its header and row parser (`table`, `FrameColumns`, `GraspRows`) also reads each
//! file of a folder of trial files (`trial_folder`), one grasp per file.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::error::{parse_number, read_text, shorten};
use super::spec::{ImportSpec, RawGrasp, assemble};
use super::{Frame, Session, SessionError};

/// The most columns a CSV line may hold: room for the largest sensor's taxels
/// ([`super::validate::MAX_TAXELS`]) and as many other columns again. A longer line is
/// refused before its fields are kept.
pub const MAX_COLUMNS: usize = 2 * super::validate::MAX_TAXELS;

/// Why a CSV line does not split, or a header does not name the columns a reader needs.
/// The caller names the file and line (a [`SessionError`] keeping this as its source).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CsvError {
    #[error("more than {MAX_COLUMNS} columns, the most a CSV line may hold")]
    TooManyColumns,
    #[error("a quoted field is not closed")]
    UnclosedQuote,
    #[error("text after a closing quote")]
    AfterQuote,
    /// Columns `first` and `second` (1-based) of the header share a name.
    #[error("columns {first} and {second} are both named `{}`", shorten(name))]
    DuplicateColumn {
        first: usize,
        second: usize,
        name: String,
    },
    #[error("no `{0}` column")]
    MissingColumn(String),
    /// A column named like taxel `column` of a sensor whose layout has `taxels`.
    #[error(
        "column `{}` is not a taxel of sensor `{sensor}`, whose layout has {taxels} \
         (`{sensor}_1` … `{sensor}_{taxels}`)",
        shorten(column)
    )]
    NotATaxel {
        column: String,
        sensor: String,
        taxels: usize,
    },
}

/// Split one CSV line into fields: commas separate, a field in double quotes may hold
/// commas and doubled quotes (`""`). More than [`MAX_COLUMNS`] fields are an error.
pub fn split_line(line: &str) -> Result<Vec<Cow<'_, str>>, CsvError> {
    let mut fields = Vec::new();
    let mut rest = line;
    loop {
        if fields.len() == MAX_COLUMNS {
            return Err(CsvError::TooManyColumns);
        }
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
                    None => return Err(CsvError::UnclosedQuote),
                }
            };
            fields.push(Cow::Owned(value));
            let after = after.trim_start();
            match after.strip_prefix(',') {
                Some(next) => rest = next,
                None if after.is_empty() => return Ok(fields),
                None => return Err(CsvError::AfterQuote),
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

/// The columns of a header by name (trimmed), each found in one look-up.
pub(crate) struct ColumnIndex<'a>(HashMap<&'a str, usize>);

impl ColumnIndex<'_> {
    /// The column index of `name`.
    pub(crate) fn find(&self, name: &str) -> Option<usize> {
        self.0.get(name).copied()
    }

    /// The column index of `name`, or an error saying it is missing.
    pub(crate) fn need(&self, name: &str) -> Result<usize, CsvError> {
        self.find(name)
            .ok_or_else(|| CsvError::MissingColumn(name.to_string()))
    }
}

/// Index a header's columns by name. A header naming one column twice is an error (found
/// by name, the second would be silently ignored): it names both columns (1-based) of the
/// first repeated name; empty names are not compared.
pub(crate) fn column_index<S: AsRef<str>>(names: &[S]) -> Result<ColumnIndex<'_>, CsvError> {
    let mut index = HashMap::with_capacity(names.len());
    for (j, b) in names.iter().enumerate() {
        let b = b.as_ref().trim();
        if b.is_empty() {
            continue;
        }
        if let Some(i) = index.insert(b, j) {
            return Err(CsvError::DuplicateColumn {
                first: i + 1,
                second: j + 1,
                name: b.to_string(),
            });
        }
    }
    Ok(ColumnIndex(index))
}

/// The non-empty lines of a text, numbered from 1.
pub(crate) struct Lines<'a>(std::iter::Enumerate<std::str::Lines<'a>>);

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        self.0
            .by_ref()
            .map(|(i, l)| (i + 1, l))
            .find(|(_, l)| !l.trim().is_empty())
    }
}

/// A CSV of frames: its header's line number and column names, and its other lines.
pub(crate) struct Table<'a> {
    pub header_line: usize,
    pub names: Vec<Cow<'a, str>>,
    pub rows: Lines<'a>,
}

/// Split a CSV of frames into its header (a byte-order mark removed) and rows.
pub(crate) fn table<'a>(text: &'a str, path: &Path) -> Result<Table<'a>, SessionError> {
    let mut lines = Lines(text.lines().enumerate());
    let Some((header_line, header)) = lines.next() else {
        return Err(SessionError::file(path, "the file is empty"));
    };
    let names = split_line(header.trim_start_matches('\u{feff}'))
        .map_err(|e| SessionError::line_caused(path, header_line, e))?;
    Ok(Table {
        header_line,
        names,
        rows: lines,
    })
}

/// A row's fields, as many as the header has columns.
pub(crate) fn row_fields<'a>(
    path: &Path,
    no: usize,
    line: &'a str,
    columns: usize,
) -> Result<Vec<Cow<'a, str>>, SessionError> {
    let fields = split_line(line).map_err(|e| SessionError::line_caused(path, no, e))?;
    if fields.len() != columns {
        return Err(SessionError::line(
            path,
            no,
            format!("{} values, expected {columns}", fields.len()),
        ));
    }
    Ok(fields)
}

/// Where a frame's values are in the header: `time` (if there is one), each sensor's
/// taxels, each joint, and `key` (if there is one).
pub(crate) struct FrameColumns {
    pub time: Option<usize>,
    /// Per sensor, the column of each taxel.
    taxels: Vec<Vec<usize>>,
    joints: Vec<usize>,
    key: Option<usize>,
}

/// One row's frame values.
pub(crate) struct Row {
    pub time: Option<f64>,
    pub taxels: Vec<Vec<f64>>,
    pub encoders: Vec<f64>,
    /// `key` is 1 on this row.
    pub key: bool,
}

impl FrameColumns {
    /// Find the spec's columns. A column named like a taxel of a spec sensor that the
    /// layout does not have (`ff_7` for six taxels) is an error: a recording with more
    /// taxels than the spec says would otherwise lose them silently.
    pub(crate) fn find(names: &[Cow<'_, str>], spec: &ImportSpec) -> Result<Self, CsvError> {
        let index = column_index(names)?;
        let taxel_counts: HashMap<&str, usize> = spec
            .sensors
            .iter()
            .map(|s| (s.sensor.name.as_str(), s.sensor.layout.taxel_count()))
            .collect();
        for name in names {
            let name = name.trim();
            let Some((sensor, k)) = name.rsplit_once('_') else {
                continue;
            };
            let Some(&n) = taxel_counts.get(sensor) else {
                continue;
            };
            let is_taxel = k.parse::<usize>().is_ok_and(|k| (1..=n).contains(&k))
                && !k.starts_with(['0', '+']);
            if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) && !is_taxel {
                return Err(CsvError::NotATaxel {
                    column: name.to_string(),
                    sensor: sensor.to_string(),
                    taxels: n,
                });
            }
        }
        let need = |name: &str| index.need(name);
        Ok(FrameColumns {
            time: index.find("time"),
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
            key: index.find("key"),
        })
    }

    /// Read line `no`'s frame values: numbers finite, taxels within their sensor's range,
    /// `key` 1, 0 or empty.
    pub(crate) fn read(
        &self,
        path: &Path,
        no: usize,
        names: &[Cow<'_, str>],
        fields: &[Cow<'_, str>],
        spec: &ImportSpec,
    ) -> Result<Row, SessionError> {
        let name = |c: usize| names[c].trim().to_string();
        let number = |c: usize| parse_number(path, no, &name(c), fields[c].trim());
        let time = self.time.map(number).transpose()?;
        let mut taxels = Vec::with_capacity(self.taxels.len());
        for (s, taxel_cols) in self.taxels.iter().enumerate() {
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
        let encoders = self
            .joints
            .iter()
            .map(|&c| number(c))
            .collect::<Result<Vec<_>, _>>()?;
        let key = match self.key.map(|c| fields[c].trim()) {
            None | Some("" | "0") => false,
            Some("1") => true,
            Some(other) => {
                return Err(SessionError::line_field(
                    path,
                    no,
                    "key",
                    format!("`{}` is not 1, 0 or empty", shorten(other)),
                ));
            }
        };
        Ok(Row {
            time,
            taxels,
            encoders,
            key,
        })
    }
}

/// A grasp's frames as its rows give them: a frame's `t` is its time from the first row's,
/// never going back, and at most one row is the key frame.
#[derive(Default)]
pub(crate) struct GraspRows {
    origin: f64,
    pub frames: Vec<Frame>,
    pub key_frame: Option<usize>,
    key_line: Option<usize>,
}

impl GraspRows {
    /// Add line `no`'s frame at `time` (seconds); `whose` names the grasp in errors
    /// (``grasp `g1` ``, `the file`).
    pub(crate) fn push(
        &mut self,
        path: &Path,
        no: usize,
        whose: &str,
        time: f64,
        row: Row,
    ) -> Result<(), SessionError> {
        if self.frames.is_empty() {
            self.origin = time;
        }
        let t = time - self.origin;
        if let Some(prev) = self.frames.last()
            && t < prev.t
        {
            return Err(SessionError::line_field(
                path,
                no,
                "time",
                format!(
                    "time goes backwards within {whose}: {time} after {}",
                    prev.t + self.origin
                ),
            ));
        }
        if row.key {
            if let Some(first) = self.key_line {
                return Err(SessionError::line_field(
                    path,
                    no,
                    "key",
                    format!("{whose} already has its key frame on line {first}"),
                ));
            }
            self.key_line = Some(no);
            self.key_frame = Some(self.frames.len());
        }
        self.frames.push(Frame {
            t,
            taxels: row.taxels,
            encoders: row.encoders,
        });
        Ok(())
    }
}

/// The grasp being read: its id, object, classes and first line, and its rows so far.
struct Open {
    id: String,
    line: usize,
    object: String,
    classes: Vec<usize>,
    rows: GraspRows,
}

impl Open {
    fn close(self) -> RawGrasp {
        RawGrasp {
            object: self.object,
            classes: self.classes,
            frames: self.rows.frames,
            key_frame: self.rows.key_frame,
            trial: None,
        }
    }
}

/// Import a long-format CSV as the spec describes.
pub fn import_long_csv(path: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    parse_long_csv(&read_text(path)?, path, spec)
}

/// Parse long-format CSV text (`path` names it in errors).
pub fn parse_long_csv(text: &str, path: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    let Table {
        header_line: header_no,
        names,
        rows: lines,
    } = table(text, path)?;
    let sets = spec.recorded_label_sets();
    let (grasp_col, object_col, label_cols, cols) = (|| {
        let index = column_index(&names)?;
        let grasp = index.need("grasp")?;
        index.need("time")?;
        let object = index.need("object")?;
        let labels = sets
            .iter()
            .map(|l| index.need(&l.name))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((grasp, object, labels, FrameColumns::find(&names, spec)?))
    })()
    .map_err(|e: CsvError| SessionError::line_caused(path, header_no, e))?;
    let mut done: Vec<RawGrasp> = Vec::new();
    let mut done_ids: HashSet<String> = HashSet::new();
    let mut open: Option<Open> = None;
    for (no, line) in lines {
        let fields = row_fields(path, no, line, names.len())?;
        let field = |c: usize| fields[c].trim();
        let id = field(grasp_col);
        if id.is_empty() {
            return Err(SessionError::line_field(
                path,
                no,
                "grasp",
                "empty grasp id",
            ));
        }
        let object = field(object_col);
        let classes = sets
            .iter()
            .zip(&label_cols)
            .map(|(set, &c)| {
                spec.class_index(set, field(c))
                    .map_err(|e| SessionError::line_field_caused(path, no, &set.name, e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let row = cols.read(path, no, &names, &fields, spec)?;
        if open.as_ref().is_none_or(|o| o.id != id) {
            if done_ids.contains(id) {
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
                .map_err(|e| SessionError::line_field_caused(path, no, "object", e))?;
            if let Some(o) = open.take() {
                done_ids.insert(o.id.clone());
                done.push(o.close());
            }
            open = Some(Open {
                id: id.to_string(),
                line: no,
                object: object.to_string(),
                classes: classes.clone(),
                rows: GraspRows::default(),
            });
        }
        let Some(o) = open.as_mut() else {
            continue;
        };
        if object != o.object {
            return Err(SessionError::line_field(
                path,
                no,
                "object",
                format!(
                    "`{}` differs from `{}` on the grasp's first line ({})",
                    shorten(object),
                    o.object,
                    o.line
                ),
            ));
        }
        if let Some(k) = classes.iter().zip(&o.classes).position(|(a, b)| a != b) {
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
        // `time` is a required column here, so every row has one.
        let time = row.time.unwrap_or_default();
        let whose = format!("grasp `{}`", o.id);
        o.rows.push(path, no, &whose, time, row)?;
    }
    if let Some(o) = open {
        done.push(o.close());
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
        assert_eq!(split_line(r#"a,"open"#), Err(CsvError::UnclosedQuote));
        assert_eq!(split_line(r#""x"y"#), Err(CsvError::AfterQuote));
    }
}
