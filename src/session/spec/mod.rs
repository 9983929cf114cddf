//! The import spec: how a researcher's own recording — a ROS 2 bag or a long-format CSV —
//! becomes a session. JSON, documented with examples in `docs/import.md`:
//!
//! ```json
//! {
//!   "name": "Allegro hand, five objects",
//!   "frame_rate_hz": 100,
//!   "sensors": [
//!     {"name": "index", "topic": "/tactile/index", "layout": "biotac-sp",
//!      "unit": "raw electrode", "range": [0, 4095],
//!      "transform": {"kind": "reversed", "offset": 4095}},
//!     {"name": "thumb", "topic": "/tactile/hand", "slice": [24, 36], "layout": "grid 3x4",
//!      "unit": "kPa"}
//!   ],
//!   "joints": {"topic": "/joint_states", "names": ["index_mcp", "thumb_cmc"]},
//!   "label_sets": [{"name": "outcome", "classes": ["success", "failure"]}],
//!   "grasps": {"events": "/grasp_events"}
//! }
//! ```
//!
//! Reading checks every field and names it in errors (`sensors[1].layout`); what the spec
//! says about the recording (topics, lengths, times) is checked by the readers.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::error::open_json;
use super::native::json_error;
use super::trial_pattern::{TRIAL, TrialPattern};
use super::validate::{MAX_SENSORS, check_layout};
use super::{
    Frame, Grasp, LabelSet, Layout, Sensor, Session, SessionError, SessionMeta, ValueTransform,
    bts3, file_name, file_stem, icub, key_frame_by_pressure, validate,
};
use crate::error::Kept;

/// The largest `sync_tolerance_s`: an hour, far beyond any two topics of one recording.
const MAX_SYNC_TOLERANCE_S: f64 = 3600.0;

pub use super::OBJECT;
pub use error::{LabelError, SpecError};
pub use live::{ContactError, ContactParams, LiveSpec};

mod error;
mod live;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecFile {
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    frame_rate_hz: Option<f64>,
    #[serde(default)]
    sync_tolerance_s: Option<f64>,
    sensors: Vec<SensorFile>,
    #[serde(default)]
    joints: Option<JointsSpec>,
    #[serde(default)]
    label_sets: Vec<LabelSet>,
    #[serde(default)]
    grasps: Option<GraspsFile>,
    #[serde(default)]
    trials: Option<TrialsFile>,
    #[serde(default)]
    live: Option<LiveSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrialsFile {
    pattern: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorFile {
    name: String,
    #[serde(default)]
    topic: Option<String>,
    #[serde(default)]
    slice: Option<[usize; 2]>,
    layout: serde_json::Value,
    unit: String,
    #[serde(default)]
    range: Option<[f64; 2]>,
    #[serde(default)]
    transform: Option<ValueTransform>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GraspsFile {
    #[serde(default)]
    windows: Option<String>,
    #[serde(default)]
    events: Option<String>,
}

/// One sensor of the spec: the session's sensor, and where its values are in a bag.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorSpec {
    pub sensor: Sensor,
    /// The bag topic (required for bags; unused for CSVs).
    pub topic: Option<String>,
    /// The sensor's values in the topic's array, `start..end` (default: the whole array).
    pub slice: Option<[usize; 2]>,
}

impl SensorSpec {
    /// The sensor's values in a message's array.
    pub fn range_in_message(&self) -> std::ops::Range<usize> {
        match self.slice {
            Some([a, b]) => a..b,
            None => 0..self.sensor.layout.taxel_count(),
        }
    }
}

/// The joint encoders: a `sensor_msgs/msg/JointState` topic and the joints taken from it
/// (in the session's encoder order), or the CSV columns of those names.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointsSpec {
    #[serde(default)]
    pub topic: Option<String>,
    pub names: Vec<String>,
}

/// How a bag is cut into grasps.
#[derive(Clone, Debug, PartialEq)]
pub enum GraspCut {
    /// A CSV of windows (`start`, `end` in bag time, `object`, one column per label set,
    /// optionally `key`), its path resolved against the spec's folder.
    Windows(PathBuf),
    /// A `std_msgs/msg/String` topic of `start:OBJECT`, optional `key`, `end:LABELS`.
    Events(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct ImportSpec {
    /// The spec file (errors name it; the windows CSV is found beside it).
    pub path: PathBuf,
    pub name: Option<String>,
    pub frame_rate_hz: Option<f64>,
    /// Bags: how far (ns) another topic's message may lie from a frame and still be its
    /// value (default: half the reference topic's median period).
    pub sync_tolerance_ns: Option<u64>,
    pub sensors: Vec<SensorSpec>,
    pub joints: Option<JointsSpec>,
    /// The label sets as the spec gives them; `object` may be among them to fix its classes.
    pub label_sets: Vec<LabelSet>,
    pub cut: Option<GraspCut>,
    /// Folders of trial files: where a file's object, classes and trial number are in its
    /// path (default: see [`ImportSpec::trial_pattern`]).
    pub trials: Option<TrialPattern>,
    /// Each label set's classes by name: a recording's rows are labelled in one look-up
    /// each, however many classes the spec declares.
    class_indices: HashMap<String, HashMap<String, usize>>,
    /// Live streams: how grasps are cut by contact (defaults when the spec has no `live`).
    pub live: LiveSpec,
}

/// A built-in layout by name: `icub-fingertip`, `biotac-sp`, `grid RxC`.
pub fn layout_by_name(name: &str) -> Option<Layout> {
    let n = name.trim();
    match n {
        "icub-fingertip" => return Some(icub::fingertip_layout()),
        "biotac-sp" => return Some(bts3::biotac_layout()),
        _ => {}
    }
    let dims = n.strip_prefix("grid")?.trim();
    let (r, c) = dims.split_once(['x', 'X', '×'])?;
    let rows = r.trim().parse().ok()?;
    let cols = c.trim().parse().ok()?;
    Some(Layout::Grid { rows, cols })
}

fn layout_of(value: &serde_json::Value) -> Result<Layout, SpecError> {
    match value {
        serde_json::Value::String(name) => {
            layout_by_name(name).ok_or_else(|| SpecError::UnknownLayout { name: name.clone() })
        }
        serde_json::Value::Object(_) => {
            serde_json::from_value(value.clone()).map_err(|e| SpecError::LayoutObject(Kept::new(e)))
        }
        _ => Err(SpecError::NotALayout),
    }
}

/// The first name given twice (one pass, whatever the count).
fn duplicate<'a>(names: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let mut seen = HashSet::new();
    names.into_iter().find(|n| !seen.insert(*n))
}

/// The spec's name, frame rate and sync tolerance checked; the tolerance in ns.
fn check_scalars(file: &SpecFile, path: &Path) -> Result<Option<u64>, SessionError> {
    let err = |field: &str, msg: String| SessionError::field(path, field, msg);
    if let Some(name) = &file.name
        && name.trim().is_empty()
    {
        return Err(err("name", "an empty name".into()));
    }
    if let Some(hz) = file.frame_rate_hz
        && !(hz.is_finite() && hz > 0.0)
    {
        return Err(err(
            "frame_rate_hz",
            format!("{hz} is not a positive frame rate"),
        ));
    }
    match file.sync_tolerance_s {
        None => Ok(None),
        Some(s) if s.is_finite() && (0.0..=MAX_SYNC_TOLERANCE_S).contains(&s) => {
            Ok(Some((s * 1e9).round() as u64))
        }
        Some(s) => Err(err(
            "sync_tolerance_s",
            format!("{s} is not a tolerance in seconds from 0 to {MAX_SYNC_TOLERANCE_S}"),
        )),
    }
}

/// Sensor `s` of the spec, every field checked (errors name `sensors[s].FIELD`).
fn sensor_spec(s: usize, f: SensorFile, path: &Path) -> Result<SensorSpec, SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    let at = |rest: &str| format!("sensors[{s}]{rest}");
    if f.name.trim().is_empty() {
        return Err(err(at(".name"), "an empty sensor name".into()));
    }
    let layout =
        layout_of(&f.layout).map_err(|e| SessionError::field_caused(path, at(".layout"), e))?;
    // The spec is where a layout is wrong: its errors name the spec, not the recording.
    check_layout(s, &f.name, &layout, path)?;
    let n = layout.taxel_count();
    if let Some([a, b]) = f.slice
        && b.checked_sub(a) != Some(n)
    {
        return Err(err(
            at(".slice"),
            format!(
                "[{a}, {b}] holds {} values but the layout has {n} taxels",
                b.saturating_sub(a)
            ),
        ));
    }
    if let Some(t) = &f.topic
        && t.trim().is_empty()
    {
        return Err(err(at(".topic"), "an empty topic".into()));
    }
    if let Some([lo, hi]) = f.range
        && !(lo.is_finite() && hi.is_finite() && lo <= hi)
    {
        return Err(err(
            at(".range"),
            format!("[{lo}, {hi}] is not a range of finite values, low to high"),
        ));
    }
    let transform = f.transform.unwrap_or(ValueTransform::Identity);
    match &transform {
        ValueTransform::BaselineMinus { baseline }
            if baseline.len() != n || baseline.iter().any(|b| !b.is_finite()) =>
        {
            return Err(err(
                at(".transform.baseline"),
                format!(
                    "{} baselines for {n} taxels (each must be finite)",
                    baseline.len()
                ),
            ));
        }
        ValueTransform::Reversed { offset } if !offset.is_finite() => {
            return Err(err(
                at(".transform.offset"),
                "the offset must be finite".into(),
            ));
        }
        _ => {}
    }
    Ok(SensorSpec {
        sensor: Sensor {
            name: f.name,
            layout,
            unit: f.unit,
            transform,
            range: f.range,
        },
        topic: f.topic,
        slice: f.slice,
    })
}

/// The joints: at least one, each named once, and a topic that is not empty.
fn check_joints(j: &JointsSpec, path: &Path) -> Result<(), SessionError> {
    let err = |field: &str, msg: String| SessionError::field(path, field, msg);
    if j.names.is_empty() {
        return Err(err("joints.names", "no joints named".into()));
    }
    if let Some(d) = duplicate(j.names.iter().map(String::as_str)) {
        return Err(err("joints.names", format!("`{d}` is named twice")));
    }
    if let Some(t) = &j.topic
        && t.trim().is_empty()
    {
        return Err(err("joints.topic", "an empty topic".into()));
    }
    Ok(())
}

/// The label sets: each named, with classes listed once, and no two of one name.
fn check_label_sets(sets: &[LabelSet], path: &Path) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    for (l, set) in sets.iter().enumerate() {
        if set.name.trim().is_empty() {
            return Err(err(
                format!("label_sets[{l}].name"),
                "an empty label set name".into(),
            ));
        }
        if set.classes.is_empty() {
            return Err(err(
                format!("label_sets[{l}].classes"),
                format!("label set `{}` has no classes", set.name),
            ));
        }
        if let Some(d) = duplicate(set.classes.iter().map(String::as_str)) {
            return Err(err(
                format!("label_sets[{l}].classes"),
                format!("class `{d}` is listed twice"),
            ));
        }
    }
    if let Some(d) = duplicate(sets.iter().map(|s| s.name.as_str())) {
        return Err(err(
            "label_sets".into(),
            format!("two label sets are named `{d}`"),
        ));
    }
    Ok(())
}

/// How the spec cuts a bag into grasps: a windows CSV (beside the spec) or an events topic.
fn grasp_cut(grasps: GraspsFile, path: &Path) -> Result<GraspCut, SessionError> {
    match grasps {
        GraspsFile {
            windows: Some(w),
            events: None,
        } => {
            let base = path.parent().unwrap_or(Path::new(""));
            Ok(GraspCut::Windows(base.join(w)))
        }
        GraspsFile {
            windows: None,
            events: Some(topic),
        } => Ok(GraspCut::Events(topic)),
        _ => Err(SessionError::field(
            path,
            "grasps",
            "give exactly one of `windows` (a CSV file) or `events` (a topic)",
        )),
    }
}

impl ImportSpec {
    /// Read a spec file as it is parsed (at most [`crate::fsutil::max_bytes::SPEC`]).
    pub fn load(path: &Path) -> Result<ImportSpec, SessionError> {
        let reader = open_json(path, crate::fsutil::max_bytes::SPEC, "spec")?;
        let file = serde_json::from_reader(reader).map_err(|e| json_error(path, e))?;
        Self::from_file(file, path)
    }

    /// Parse spec text (`path` names it in errors and anchors the windows CSV).
    pub fn from_str(text: &str, path: &Path) -> Result<ImportSpec, SessionError> {
        let text = crate::fsutil::without_bom(text);
        if text.trim().is_empty() {
            return Err(SessionError::file(path, "the spec is empty"));
        }
        let file = serde_json::from_str(text).map_err(|e| json_error(path, e))?;
        Self::from_file(file, path)
    }

    /// Check every field of a parsed spec file.
    fn from_file(file: SpecFile, path: &Path) -> Result<ImportSpec, SessionError> {
        let err = |field: String, msg: String| SessionError::field(path, field, msg);
        let sync_tolerance_ns = check_scalars(&file, path)?;
        if file.sensors.is_empty() {
            return Err(err("sensors".into(), "the spec has no sensors".into()));
        }
        if file.sensors.len() > MAX_SENSORS {
            return Err(err(
                "sensors".into(),
                format!(
                    "{} sensors, more than the {MAX_SENSORS} a spec may declare",
                    file.sensors.len()
                ),
            ));
        }
        let sensors = file
            .sensors
            .into_iter()
            .enumerate()
            .map(|(s, f)| sensor_spec(s, f, path))
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(d) = duplicate(sensors.iter().map(|s| s.sensor.name.as_str())) {
            return Err(err(
                "sensors".into(),
                format!("two sensors are named `{d}`"),
            ));
        }
        if let Some(j) = &file.joints {
            check_joints(j, path)?;
        }
        check_label_sets(&file.label_sets, path)?;
        let cut = match file.grasps {
            None => None,
            Some(grasps) => Some(grasp_cut(grasps, path)?),
        };
        let trials = match file.trials {
            None => None,
            Some(t) => Some(
                trial_pattern(&t.pattern, &file.label_sets)
                    .map_err(|e| SessionError::field_caused(path, "trials.pattern", e))?,
            ),
        };
        let class_indices = file
            .label_sets
            .iter()
            .map(|set| {
                let classes = set.classes.iter().cloned().zip(0..).collect();
                (set.name.clone(), classes)
            })
            .collect();
        let live = file.live.unwrap_or_default();
        live.contact
            .check()
            .map_err(|e| SessionError::field_caused(path, e.field(), e))?;
        Ok(ImportSpec {
            path: path.to_path_buf(),
            name: file.name,
            frame_rate_hz: file.frame_rate_hz,
            sync_tolerance_ns,
            sensors,
            joints: file.joints,
            label_sets: file.label_sets,
            cut,
            trials,
            class_indices,
            live,
        })
    }

    /// The pattern of a folder of trial files: the spec's `trials.pattern`, else one folder
    /// per label (`{object}/*.csv`, `{object}/{outcome}/*.csv` with a label set `outcome`).
    pub fn trial_pattern(&self) -> Result<TrialPattern, SessionError> {
        if let Some(p) = &self.trials {
            return Ok(p.clone());
        }
        let mut text = format!("{{{OBJECT}}}/");
        for set in self.recorded_label_sets() {
            text.push_str(&format!("{{{}}}/", set.name));
        }
        text.push_str("*.csv");
        trial_pattern(&text, &self.label_sets).map_err(|e| {
            let e = SpecError::DefaultPattern {
                pattern: text.clone(),
                source: Kept::new(e),
            };
            SessionError::field_caused(&self.path, "trials", e)
        })
    }

    /// The label sets a recording gives a class of, besides the object: their names are
    /// the windows CSV's and the long CSV's columns, and an `end:` event lists them in order.
    pub fn recorded_label_sets(&self) -> Vec<&LabelSet> {
        self.label_sets
            .iter()
            .filter(|l| l.name != OBJECT)
            .collect()
    }

    /// Index of `class` in recorded label set `set` (of [`Self::recorded_label_sets`]), or
    /// an error naming the classes.
    pub fn class_index(&self, set: &LabelSet, class: &str) -> Result<usize, LabelError> {
        let found = self.class_indices.get(&set.name).and_then(|c| c.get(class));
        found.copied().ok_or_else(|| LabelError::NotAClass {
            class: class.to_string(),
            set: set.name.clone(),
            classes: set.classes.clone(),
        })
    }

    /// Check an object name: any non-empty name, or one of the spec's `object` classes.
    pub fn check_object(&self, object: &str) -> Result<(), LabelError> {
        if object.trim().is_empty() {
            return Err(LabelError::EmptyObject);
        }
        let known = |set: &LabelSet| {
            self.class_indices
                .get(&set.name)
                .is_some_and(|c| c.contains_key(object))
        };
        match self.label_sets.iter().find(|l| l.name == OBJECT) {
            Some(set) if !known(set) => Err(LabelError::UnknownObject {
                object: object.to_string(),
                classes: set.classes.clone(),
            }),
            _ => Ok(()),
        }
    }

    /// Encoder names (empty without joints).
    pub fn encoder_names(&self) -> Vec<String> {
        self.joints
            .as_ref()
            .map(|j| j.names.clone())
            .unwrap_or_default()
    }
}

/// Parse a trial pattern whose captures are `object`, `trial` or a label set, and that
/// captures the object and every other label set (a grasp's labels come from its path).
fn trial_pattern(text: &str, label_sets: &[LabelSet]) -> Result<TrialPattern, SpecError> {
    let pattern = TrialPattern::parse(text)?;
    let names: Vec<&str> = pattern.names().collect();
    if let Some(n) = names
        .iter()
        .find(|n| **n != OBJECT && **n != TRIAL && !label_sets.iter().any(|l| l.name == **n))
    {
        return Err(SpecError::UnknownCapture {
            name: n.to_string(),
        });
    }
    let needed = std::iter::once(OBJECT).chain(
        label_sets
            .iter()
            .map(|l| l.name.as_str())
            .filter(|n| *n != OBJECT),
    );
    for n in needed {
        if !names.contains(&n) {
            return Err(SpecError::Uncaptured {
                pattern: text.to_string(),
                name: n.to_string(),
            });
        }
    }
    if !text.to_ascii_lowercase().ends_with(".csv") {
        return Err(SpecError::NotCsv {
            pattern: text.to_string(),
        });
    }
    Ok(pattern)
}

/// A grasp as a reader found it, before the session's label indices are known.
#[derive(Clone, Debug, PartialEq)]
pub struct RawGrasp {
    pub object: String,
    /// One class index per recorded label set, in their order.
    pub classes: Vec<usize>,
    pub frames: Vec<Frame>,
    /// The key frame, where the recording gives it.
    pub key_frame: Option<usize>,
    /// The trial number, where the recording gives it (else grasps of an object are
    /// numbered 1, 2, … in their order).
    pub trial: Option<u32>,
}

/// The median frame interval's rate over all grasps, when there are intervals.
fn measured_rate(grasps: &[RawGrasp]) -> Option<f64> {
    let mut dt: Vec<f64> = grasps
        .iter()
        .flat_map(|g| g.frames.windows(2).map(|w| w[1].t - w[0].t))
        .filter(|d| *d > 0.0)
        .collect();
    if dt.is_empty() {
        return None;
    }
    dt.sort_by(f64::total_cmp);
    let rate = 1.0 / dt[dt.len() / 2];
    // Three significant digits: a rate estimated from stamps is not exact.
    let scale = 10f64.powi(2 - rate.log10().floor() as i32);
    Some((rate * scale).round() / scale)
}

/// Build and validate the session: label sets (`object` first unless the spec places it),
/// key frames (given, or the frame of greatest total pressure), metadata naming the
/// source by file name only.
pub fn assemble(
    spec: &ImportSpec,
    source: &Path,
    kind: &str,
    how: &str,
    grasps: Vec<RawGrasp>,
) -> Result<Session, SessionError> {
    if grasps.is_empty() {
        return Err(SessionError::file(source, "the recording holds no grasps"));
    }
    let sensors: Vec<Sensor> = spec.sensors.iter().map(|s| s.sensor.clone()).collect();
    let mut label_sets = spec.label_sets.clone();
    let object_set = match label_sets.iter().position(|l| l.name == OBJECT) {
        Some(i) => i,
        None => {
            let mut seen = HashSet::new();
            let objects: Vec<String> = grasps
                .iter()
                .filter(|g| seen.insert(g.object.as_str()))
                .map(|g| g.object.clone())
                .collect();
            label_sets.insert(
                0,
                LabelSet {
                    name: OBJECT.into(),
                    classes: objects,
                },
            );
            0
        }
    };
    let rate = spec.frame_rate_hz.or_else(|| measured_rate(&grasps));
    let object_class: HashMap<&str, usize> = label_sets[object_set]
        .classes
        .iter()
        .enumerate()
        .map(|(i, c)| (c.as_str(), i))
        .collect();
    let mut out = Vec::with_capacity(grasps.len());
    // The last trial number of each object whose grasps the recording does not number.
    let mut trials: HashMap<String, u32> = HashMap::new();
    for g in grasps {
        let mut recorded = g.classes.into_iter();
        let labels = (0..label_sets.len())
            .map(|i| {
                if i == object_set {
                    object_class.get(g.object.as_str()).copied().unwrap_or(0)
                } else {
                    recorded.next().unwrap_or(0)
                }
            })
            .collect();
        let trial = match g.trial {
            Some(given) => given,
            None => {
                let n = trials.entry(g.object.clone()).or_insert(0);
                *n += 1;
                *n
            }
        };
        let key_frame = g
            .key_frame
            .unwrap_or_else(|| key_frame_by_pressure(&sensors, &g.frames));
        out.push(Grasp {
            object: g.object,
            trial: Some(trial),
            labels,
            frames: g.frames,
            key_frame,
        });
    }
    let session = Session {
        meta: SessionMeta {
            name: spec.name.clone().unwrap_or_else(|| file_stem(source)),
            source: format!(
                "{kind} {}, imported with the spec {}",
                file_name(source),
                file_name(&spec.path)
            ),
            licence: String::new(),
            citation: String::new(),
            frame_rate_hz: rate,
            notes: format!(
                "{how} Key frame: where the recording marks it, else the frame of greatest \
                 total pressure."
            ),
        },
        sensors,
        encoders: spec.encoder_names(),
        label_sets,
        grasps: out,
    };
    validate(&session, source)?;
    Ok(session)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_layout_names() {
        assert_eq!(
            layout_by_name("grid 3x4"),
            Some(Layout::Grid { rows: 3, cols: 4 })
        );
        assert_eq!(
            layout_by_name("grid 2 × 5"),
            Some(Layout::Grid { rows: 2, cols: 5 })
        );
        assert_eq!(layout_by_name("biotac-sp").unwrap().taxel_count(), 24);
        assert_eq!(layout_by_name("icub-fingertip").unwrap().taxel_count(), 12);
        assert_eq!(layout_by_name("grid 3by4"), None);
    }

    /// Each contact parameter at fault is named by its field, and kept as the source.
    #[test]
    fn contact_parameters_that_cannot_cut_name_their_field() {
        let spec = |live: &str| {
            let text = format!(
                r#"{{"sensors": [{{"name": "a", "layout": "grid 1x2", "unit": "raw"}}],
                    "live": {{"contact": {live}}}}}"#
            );
            ImportSpec::from_str(&text, Path::new("spec.json")).unwrap_err()
        };
        for (live, field, why) in [
            (
                r#"{"min_rise": -1}"#,
                "live.contact.min_rise",
                ContactError::NotNonNegative {
                    field: "live.contact.min_rise",
                    value: -1.0,
                },
            ),
            (
                r#"{"baseline_s": 0}"#,
                "live.contact.baseline_s",
                ContactError::ZeroBaseline,
            ),
            (
                r#"{"onset_sigma": 2, "offset_sigma": 3}"#,
                "live.contact.offset_sigma",
                ContactError::OffsetAboveOnset {
                    offset: 3.0,
                    onset: 2.0,
                },
            ),
        ] {
            let err = spec(live);
            assert_eq!(err.location, crate::session::Location::Field(field.into()));
            let kept = std::error::Error::source(&err)
                .and_then(|s| s.downcast_ref::<ContactError>())
                .unwrap_or_else(|| panic!("the contact error is the source: {err:?}"));
            assert_eq!(kept, &why);
            assert!(err.to_string().ends_with(&why.to_string()), "{err}");
        }
        // The wording a user reads, as it was before the reasons were typed.
        assert_eq!(
            ContactError::ZeroBaseline.to_string(),
            "the time constant must be > 0"
        );
        assert_eq!(
            ContactError::OffsetAboveOnset {
                offset: 3.0,
                onset: 2.0
            }
            .to_string(),
            "3 is above the onset's 2: the offset must be the lower threshold"
        );
    }
}
