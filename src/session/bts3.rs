//! Importer of the BioTac SP grasp-stability set (BTS3) CSVs, e.g. the palm-down
//! `datasets/bts3/biotac-palmdown-grasps.csv`; a session is named after its file, since
//! the set's files (palm down, palm side) share one format.
//!
//! One CSV row per grasp: `object,slipped,ff_biotac_1..24,mf_biotac_1..24,th_biotac_1..24`.
//! A grasp is a single static reading at the grasp (one frame, the key frame). Electrode
//! values fall under contact, so the pressure-like value is the session's resting
//! baseline minus the reading, with the baseline of each electrode taken as its largest
//! reading over the session (the least-contacted state recorded): pressures are ≥ 0 and
//! a linear map of the raw value, which the z-scoring of the analyses does not change.

use std::path::Path;

use super::error::{parse_number, read_text, shorten};
use super::{
    Frame, Grasp, LabelSet, Layout, Sensor, Session, SessionError, SessionMeta, ValueTransform,
    file_name, file_stem, validate,
};

pub const FINGERS: [&str; 3] = ["ff", "mf", "th"];
pub const ELECTRODES: usize = 24;
/// An electrode reading is a 12-bit ADC value: 0–4095.
pub const READING_RANGE: [f64; 2] = [0.0, 4095.0];
/// The dataset authors' 8 × 9 placement of electrodes 1..24 (LAYOUTS.md).
const ROWS: [usize; ELECTRODES] = [
    0, 1, 3, 3, 4, 4, 4, 5, 6, 7, 0, 1, 3, 3, 4, 4, 4, 5, 6, 7, 1, 2, 2, 3,
];
const COLS: [usize; ELECTRODES] = [
    7, 6, 8, 7, 6, 8, 7, 5, 7, 7, 1, 2, 0, 1, 2, 0, 1, 3, 1, 1, 4, 5, 3, 4,
];

/// The BioTac SP electrode layout on its 8 × 9 grid.
pub fn biotac_layout() -> Layout {
    Layout::SparseGrid {
        rows: 8,
        cols: 9,
        cells: ROWS
            .iter()
            .zip(COLS.iter())
            .map(|(&r, &c)| [r, c])
            .collect(),
    }
}

fn expected_header() -> Vec<String> {
    let mut h = vec!["object".to_string(), "slipped".to_string()];
    for f in FINGERS {
        for e in 1..=ELECTRODES {
            h.push(format!("{f}_biotac_{e}"));
        }
    }
    h
}

/// Import a BTS3 CSV.
pub fn import_bts3(path: &Path) -> Result<Session, SessionError> {
    parse_bts3(&read_text(path)?, path)
}

/// Parse the CSV text (`path` names it in errors).
pub fn parse_bts3(text: &str, path: &Path) -> Result<Session, SessionError> {
    let mut lines = text.lines().enumerate();
    let header = match lines.next() {
        Some((_, h)) if !h.trim().is_empty() => h.trim_start_matches('\u{feff}'),
        _ => return Err(SessionError::file(path, "the file is empty")),
    };
    let expected = expected_header();
    check_header(header, &expected, path)?;

    let mut grasps = Vec::new();
    let mut trial_counts: Vec<(String, u32)> = Vec::new();
    for (i, line) in lines {
        let line_no = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let Row {
            object,
            failed,
            taxels,
        } = parse_row(line, line_no, &expected, path)?;
        let trial = match trial_counts.iter_mut().find(|(o, _)| o == object) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                trial_counts.push((object.to_string(), 1));
                1
            }
        };
        grasps.push(Grasp {
            object: object.to_string(),
            trial: Some(trial),
            labels: vec![usize::from(failed)],
            frames: vec![Frame {
                t: 0.0,
                taxels,
                encoders: Vec::new(),
            }],
            key_frame: 0,
        });
    }
    if grasps.is_empty() {
        return Err(SessionError::file(
            path,
            "the file has a header but no grasps",
        ));
    }

    let session = Session {
        meta: SessionMeta {
            name: format!("BioTac SP grasp stability ({})", file_stem(path)),
            source: format!("BTS3 BioTac SP grasps, imported from {}", file_name(path)),
            licence: String::new(),
            citation: String::new(),
            frame_rate_hz: None,
            notes:
                "One static reading per grasp. Pressure = per-electrode session maximum − reading."
                    .into(),
        },
        sensors: sensors(&grasps),
        encoders: Vec::new(),
        label_sets: vec![LabelSet {
            name: "outcome".into(),
            classes: vec!["success".into(), "failure".into()],
        }],
        grasps,
    };
    validate(&session, path)?;
    Ok(session)
}

/// The header's columns are the expected ones, in order.
fn check_header(header: &str, expected: &[String], path: &Path) -> Result<(), SessionError> {
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    if names.len() != expected.len() {
        return Err(SessionError::line(
            path,
            1,
            format!(
                "header has {} columns, expected {} (object, slipped, 3 × 24 electrodes)",
                names.len(),
                expected.len()
            ),
        ));
    }
    // Names are matched regardless of case (`Object`, `FF_biotac_1`): CSV headers are
    // case-free, and spreadsheet tools capitalise them.
    for (i, (got, want)) in names.iter().zip(expected).enumerate() {
        if !got.eq_ignore_ascii_case(want) {
            return Err(SessionError::line(
                path,
                1,
                format!("column {} is `{}`, expected `{want}`", i + 1, shorten(got)),
            ));
        }
    }
    Ok(())
}

/// One grasp's row: its object, whether it slipped, and each finger's readings.
struct Row<'a> {
    object: &'a str,
    failed: bool,
    taxels: Vec<Vec<f64>>,
}

/// A grasp's row (line `line_no`), every field checked.
fn parse_row<'a>(
    line: &'a str,
    line_no: usize,
    expected: &[String],
    path: &Path,
) -> Result<Row<'a>, SessionError> {
    let n_cols = expected.len();
    let fields: Vec<&str> = line.split(',').collect();
    if fields.len() != n_cols {
        return Err(SessionError::line(
            path,
            line_no,
            format!("{} values, expected {n_cols}", fields.len()),
        ));
    }
    let object = fields[0].trim();
    if object.is_empty() {
        return Err(SessionError::line_field(
            path,
            line_no,
            "object",
            "empty object name",
        ));
    }
    let failed = match fields[1].trim() {
        "0" => false,
        "1" => true,
        other => {
            return Err(SessionError::line_field(
                path,
                line_no,
                "slipped",
                format!("`{}` is not 0 or 1", shorten(other)),
            ));
        }
    };
    let mut taxels = Vec::with_capacity(FINGERS.len());
    for f in 0..FINGERS.len() {
        let mut values = Vec::with_capacity(ELECTRODES);
        for e in 0..ELECTRODES {
            let col = 2 + f * ELECTRODES + e;
            let v = parse_number(path, line_no, &expected[col], fields[col])?;
            let [lo, hi] = READING_RANGE;
            if !(lo..=hi).contains(&v) {
                return Err(SessionError::line_field(
                    path,
                    line_no,
                    &expected[col],
                    format!("reading {v} is outside the BioTac SP electrode range {lo}–{hi}"),
                ));
            }
            values.push(v);
        }
        taxels.push(values);
    }
    Ok(Row {
        object,
        failed,
        taxels,
    })
}

/// The three fingers' sensors, each electrode's baseline its largest reading over the
/// grasps.
fn sensors(grasps: &[Grasp]) -> Vec<Sensor> {
    (0..FINGERS.len())
        .map(|f| {
            let baseline = (0..ELECTRODES)
                .map(|e| {
                    grasps
                        .iter()
                        .map(|g| g.frames[0].taxels[f][e])
                        .fold(f64::NEG_INFINITY, f64::max)
                })
                .collect();
            Sensor {
                name: FINGERS[f].to_string(),
                layout: biotac_layout(),
                unit: "raw electrode reading".into(),
                transform: ValueTransform::BaselineMinus { baseline },
                range: Some(READING_RANGE),
            }
        })
        .collect()
}
