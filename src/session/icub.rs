//! Importer of the iCub grasp dataset (`datasets/icub-grasp/`, Soh & Demiris), the data of
//! the second paper: 10 objects × 20 grasps, 5 fingertips × 12 taxels + 9 encoders, 10 Hz.
//!
//! Each `<object>_<trial>.txt` starts with a line to ignore (`-10000`), then 7 lines per
//! time step: 9 joint encoders (degrees), the device's per-finger `max(255 − reading)`
//! (lagging; recomputed from the taxels when needed, so not imported), and 12 raw taxel
//! readings for the thumb, index, middle, ring and little finger. Raw readings fall under
//! pressure; the pressure-like value is 255 − reading, as in the paper.

use std::path::{Path, PathBuf};

use super::error::{parse_number, read_text};
use super::{
    Frame, Grasp, LabelSet, Layout, Sensor, Session, SessionError, SessionMeta, TaxelPos,
    ValueTransform, file_name, key_frame_by_pressure, validate,
};

pub const FINGERS: [&str; 5] = ["thumb", "index", "middle", "ring", "little"];
pub const TAXELS: usize = 12;
pub const ENCODERS: usize = 9;
/// A raw taxel reading is one byte of capacitance: 0–255.
pub const READING_RANGE: [f64; 2] = [0.0, 255.0];
const LINES_PER_STEP: usize = 7;
pub const TRIALS: u32 = 20;
/// The ten objects of the paper (`full_coke` is unreliable, per the dataset's README).
pub const CLASSES: [&str; 10] = [
    "blue_bear",
    "book",
    "empty_coke",
    "empty_vitamin_water",
    "full_vitamin_water",
    "lotion",
    "med_coke",
    "med_vitamin_water",
    "monkey_toy",
    "none",
];
pub const UNRELIABLE_CLASS: &str = "full_coke";

/// The notice the dataset asks to keep intact, used when its README is not beside the data.
const COPYRIGHT: &str = "iCub Grasp Dataset. Copyright 2012 Harold Soh. \
You can use and distribute this dataset freely as long as you keep the copyright \
information intact.";
const CITATION: &str = "Harold Soh, Yanyu Su and Yiannis Demiris, \"Online Spatio-Temporal \
Gaussian Process Experts with Application to Tactile Classification\", IEEE/RSJ International \
Conference on Intelligent Robots and Systems, 2012. Harold Soh and Yiannis Demiris, \
\"Iteratively Learning Objects by Touch: Online Discriminative and Generative Models for \
Tactile-based Recognition\", IEEE Transactions on Haptics, 2014.";

/// The iCub fingertip: taxel centres and outline used by the iCub skin display.
pub fn fingertip_layout() -> Layout {
    let p = |x: f64, y: f64| TaxelPos { x, y };
    Layout::Points {
        positions: vec![
            p(-15.0, 10.0),
            p(-15.0, 35.0),
            p(-41.0, 35.0),
            p(-30.0, 64.0),
            p(-11.0, 58.0),
            p(0.0, 82.0),
            p(11.0, 58.0),
            p(30.0, 64.0),
            p(41.0, 35.0),
            p(15.0, 35.0),
            p(15.0, 10.0),
            p(41.0, 10.0),
        ],
        outline: vec![
            p(53.0, 0.0),
            p(53.0, 45.0),
            p(40.0, 74.0),
            p(0.0, 94.0),
            p(-40.0, 74.0),
            p(-53.0, 45.0),
            p(-53.0, 0.0),
        ],
        radius: 10.0,
    }
}

#[derive(Clone, Debug, Default)]
pub struct IcubOptions {
    /// Also import `full_coke` (off by default: the dataset's README calls it unreliable).
    pub include_full_coke: bool,
}

/// Parse one trial file into frames.
pub fn parse_trial(text: &str, path: &Path) -> Result<Vec<Frame>, SessionError> {
    let mut lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    if lines.is_empty() {
        return Err(SessionError::file(path, "the file is empty"));
    }
    // The first line is a marker to ignore, but it must be the marker, not data.
    let (first_no, first) = lines.remove(0);
    if first.split_whitespace().count() != 1 {
        return Err(SessionError::line(
            path,
            first_no,
            "expected the single-value header line (-10000)",
        ));
    }
    if lines.is_empty() {
        return Err(SessionError::file(path, "the file has no time steps"));
    }
    if !lines.len().is_multiple_of(LINES_PER_STEP) {
        let (last_no, _) = lines[lines.len() - 1];
        return Err(SessionError::line(
            path,
            last_no,
            format!(
                "truncated: the last time step has {} of its {LINES_PER_STEP} lines",
                lines.len() % LINES_PER_STEP
            ),
        ));
    }
    let mut frames = Vec::with_capacity(lines.len() / LINES_PER_STEP);
    for (step, block) in lines.chunks(LINES_PER_STEP).enumerate() {
        let row = |k: usize, n: usize, what: &str| -> Result<Vec<f64>, SessionError> {
            let (no, text) = block[k];
            let fields: Vec<&str> = text.split_whitespace().collect();
            if fields.len() != n {
                return Err(SessionError::line(
                    path,
                    no,
                    format!("{what}: {} values, expected {n}", fields.len()),
                ));
            }
            fields
                .iter()
                .enumerate()
                .map(|(i, f)| parse_number(path, no, &format!("{what}[{i}]"), f))
                .collect()
        };
        let encoders = row(0, ENCODERS, "encoders")?;
        row(1, FINGERS.len(), "finger maxima")?;
        let mut taxels = Vec::with_capacity(FINGERS.len());
        for (f, name) in FINGERS.iter().enumerate() {
            let what = format!("{name} taxels");
            let values = row(2 + f, TAXELS, &what)?;
            let [lo, hi] = READING_RANGE;
            if let Some(i) = values.iter().position(|v| !(lo..=hi).contains(v)) {
                return Err(SessionError::line_field(
                    path,
                    block[2 + f].0,
                    format!("{what}[{i}]"),
                    format!(
                        "reading {} is outside the iCub taxel range {lo}–{hi}",
                        values[i]
                    ),
                ));
            }
            taxels.push(values);
        }
        frames.push(Frame {
            t: step as f64 * 0.1,
            taxels,
            encoders,
        });
    }
    Ok(frames)
}

/// The folder holding the trial files: `dir` itself or its `iCubGraspDataset` child.
fn data_dir(dir: &Path) -> PathBuf {
    let child = dir.join("iCubGraspDataset");
    if child.is_dir() {
        child
    } else {
        dir.to_path_buf()
    }
}

/// The copyright section of the dataset's README, verbatim, when it is there.
fn readme_notice(dir: &Path, data: &Path) -> Option<String> {
    let readme = [dir.join("README.txt"), data.join("../README.txt")]
        .into_iter()
        .find(|p| p.is_file())?;
    let text = std::fs::read_to_string(readme).ok()?;
    let head: Vec<&str> = text.lines().take(3).collect();
    let start = text.find("== Copyright and Usage ==")?;
    Some(format!(
        "{}\n\n{}",
        head.join("\n"),
        text[start..].trim_end()
    ))
}

/// Import the dataset from its folder: the paper's 10 classes × trials 1–20.
/// Whether `dir` looks like the iCub grasp dataset (it holds the first class's first trial).
pub fn is_dataset(dir: &Path) -> bool {
    data_dir(dir)
        .join(format!("{}_1.txt", CLASSES[0]))
        .is_file()
}

pub fn import_icub(dir: &Path) -> Result<Session, SessionError> {
    import_icub_with(dir, &IcubOptions::default())
}

pub fn import_icub_with(dir: &Path, options: &IcubOptions) -> Result<Session, SessionError> {
    if !dir.is_dir() {
        return Err(SessionError::file(
            dir,
            "not a folder (expected the iCub grasp dataset)",
        ));
    }
    let data = data_dir(dir);
    let mut classes: Vec<&str> = CLASSES.to_vec();
    if options.include_full_coke {
        classes.push(UNRELIABLE_CLASS);
    }
    let sensors: Vec<Sensor> = FINGERS
        .iter()
        .map(|name| Sensor {
            name: name.to_string(),
            layout: fingertip_layout(),
            unit: "raw capacitance (0–255, falls under pressure)".into(),
            transform: ValueTransform::Reversed { offset: 255.0 },
            range: Some(READING_RANGE),
        })
        .collect();
    let mut grasps = Vec::with_capacity(classes.len() * TRIALS as usize);
    for (c, class) in classes.iter().enumerate() {
        for trial in 1..=TRIALS {
            let path = data.join(format!("{class}_{trial}.txt"));
            if !path.is_file() {
                return Err(SessionError::file(
                    &path,
                    format!(
                        "missing trial {trial} of `{class}` (the paper uses trials 1–{TRIALS})"
                    ),
                ));
            }
            let frames = parse_trial(&read_text(&path)?, &path)?;
            grasps.push(Grasp {
                object: class.to_string(),
                trial: Some(trial),
                labels: vec![c],
                key_frame: key_frame_by_pressure(&sensors, &frames),
                frames,
            });
        }
    }
    let session = Session {
        meta: SessionMeta {
            name: "iCub grasp dataset".into(),
            source: format!(
                "iCub grasp dataset (Soh & Demiris), imported from {}",
                file_name(dir)
            ),
            licence: readme_notice(dir, &data).unwrap_or_else(|| COPYRIGHT.to_string()),
            citation: CITATION.into(),
            frame_rate_hz: Some(10.0),
            notes: format!(
                "Trials 1–{TRIALS} of each class{}. Pressure = 255 − reading. Key frame: the step \
                 of greatest total pressure.",
                if options.include_full_coke {
                    ", including the unreliable full_coke"
                } else {
                    "; full_coke left out as the dataset's README advises"
                }
            ),
        },
        sensors,
        encoders: (7..7 + ENCODERS).map(|j| format!("joint {j:02}")).collect(),
        label_sets: vec![LabelSet {
            name: "object".into(),
            classes: classes.iter().map(|s| s.to_string()).collect(),
        }],
        grasps,
    };
    validate(&session, &data)?;
    Ok(session)
}
