//! The session data model: sensors with their layouts, label sets, grasps and frames.
//!
//! Values are stored as recorded (raw); each sensor's `ValueTransform` turns a raw reading
//! into a pressure-like value where more contact means a larger value. Every analysis reads
//! pressures through [`Session::pressure`] / [`Grasp::pressures`], so raw files round-trip
//! exactly and the convention is stated in one place.

use serde::{Deserialize, Serialize};

/// Where a session came from, and what its source requires us to keep.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct SessionMeta {
    pub name: String,
    /// Free text: the dataset, device or simulator that produced the session.
    pub source: String,
    /// Copyright / licence text that must travel with the data (kept verbatim).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub licence: String,
    /// How to cite the source, where it asks to be cited.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub citation: String,
    /// Frames per second of the recording (None for static, single-frame grasps).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub notes: String,
}

/// A taxel's centre in the sensor's own 2D frame (x to the right, y from base to tip).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct TaxelPos {
    pub x: f64,
    pub y: f64,
}

/// How the taxels sit on the sensor.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Layout {
    /// A full rectangular grid, taxels in row-major order (row 0 at the base).
    Grid { rows: usize, cols: usize },
    /// Taxels on some cells of a grid; other cells have no taxel (drawn as background).
    SparseGrid {
        rows: usize,
        cols: usize,
        /// (row, col) of each taxel, in taxel order.
        cells: Vec<[usize; 2]>,
    },
    /// Taxels at free positions inside an outline polygon (e.g. the iCub fingertip).
    Points {
        positions: Vec<TaxelPos>,
        #[serde(default)]
        outline: Vec<TaxelPos>,
        /// Drawing radius of one taxel in the same units.
        radius: f64,
    },
}

impl Layout {
    pub fn taxel_count(&self) -> usize {
        match self {
            Layout::Grid { rows, cols } => rows * cols,
            Layout::SparseGrid { cells, .. } => cells.len(),
            Layout::Points { positions, .. } => positions.len(),
        }
    }

    /// (row, col) of taxel `i` for grid layouts (None for point layouts). This is how
    /// a patch is arranged as an image for basis images and heatmaps.
    pub fn grid_cell(&self, i: usize) -> Option<(usize, usize)> {
        match self {
            Layout::Grid { cols, .. } => Some((i / cols, i % cols)),
            Layout::SparseGrid { cells, .. } => cells.get(i).map(|c| (c[0], c[1])),
            Layout::Points { .. } => None,
        }
    }

    /// Grid shape (rows, cols), if the layout is a grid.
    pub fn grid_shape(&self) -> Option<(usize, usize)> {
        match self {
            Layout::Grid { rows, cols } | Layout::SparseGrid { rows, cols, .. } => {
                Some((*rows, *cols))
            }
            Layout::Points { .. } => None,
        }
    }
}

/// Raw reading → pressure-like value ("more contact = larger value").
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ValueTransform {
    /// The reading already grows with contact.
    Identity,
    /// pressure = offset − reading (iCub: 255 − reading).
    Reversed { offset: f64 },
    /// pressure = baseline[taxel] − reading, one resting baseline per taxel
    /// (BioTac SP electrodes fall under contact).
    BaselineMinus { baseline: Vec<f64> },
}

impl ValueTransform {
    #[inline]
    pub fn apply(&self, taxel: usize, raw: f64) -> f64 {
        match self {
            ValueTransform::Identity => raw,
            ValueTransform::Reversed { offset } => offset - raw,
            ValueTransform::BaselineMinus { baseline } => {
                baseline.get(taxel).copied().unwrap_or(0.0) - raw
            }
        }
    }

    pub fn describe(&self) -> String {
        match self {
            ValueTransform::Identity => "as recorded".into(),
            ValueTransform::Reversed { offset } => format!("{offset} − reading"),
            ValueTransform::BaselineMinus { .. } => "resting baseline − reading".into(),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Sensor {
    /// e.g. "left", "thumb", "ff".
    pub name: String,
    pub layout: Layout,
    /// Unit of the raw reading (e.g. "kPa", "raw capacitance (0–255)", "raw electrode").
    pub unit: String,
    pub transform: ValueTransform,
    /// The documented range of a raw reading, `[min, max]`: readers refuse values outside
    /// it (a reading out of range is a wrong layout, unit or file, not a touch).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
}

impl Sensor {
    /// Whether a raw reading lies in the sensor's documented range (any finite value when
    /// it has none).
    #[inline]
    pub fn in_range(&self, raw: f64) -> bool {
        self.range.is_none_or(|[lo, hi]| (lo..=hi).contains(&raw))
    }

    /// The range as text for messages, e.g. `0–255`.
    pub fn range_text(&self) -> String {
        match self.range {
            Some([lo, hi]) => format!("{lo}–{hi}"),
            None => "any finite value".into(),
        }
    }
}

/// A named set of mutually exclusive labels, e.g. "outcome": [success, failure].
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LabelSet {
    pub name: String,
    pub classes: Vec<String>,
}

/// One time step of a grasp.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Frame {
    /// Seconds from the start of the grasp.
    pub t: f64,
    /// Raw taxel readings, one vector per sensor (in the session's sensor order).
    pub taxels: Vec<Vec<f64>>,
    /// Joint encoder readings (empty when the session has no encoders).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub encoders: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Grasp {
    pub object: String,
    /// Trial number within the object, where the source numbers them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trial: Option<u32>,
    /// One class index per label set (in the session's label-set order).
    pub labels: Vec<usize>,
    pub frames: Vec<Frame>,
    /// The frame used for static analysis: the moment of full contact.
    pub key_frame: usize,
}

/// The current native format version; reading rejects any other.
pub const FORMAT_VERSION: u32 = 1;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Session {
    pub meta: SessionMeta,
    pub sensors: Vec<Sensor>,
    /// Joint encoder names (empty when there are none).
    #[serde(default)]
    pub encoders: Vec<String>,
    pub label_sets: Vec<LabelSet>,
    pub grasps: Vec<Grasp>,
}

impl Session {
    /// Index of the label set with this name.
    pub fn label_set(&self, name: &str) -> Option<usize> {
        self.label_sets.iter().position(|l| l.name == name)
    }

    /// Total taxels over all sensors.
    pub fn taxel_count(&self) -> usize {
        self.sensors.iter().map(|s| s.layout.taxel_count()).sum()
    }

    /// Every grasp's frames, counted together (the steps a sequence method reads).
    pub fn total_frames(&self) -> usize {
        self.grasps.iter().map(|g| g.frames.len()).sum()
    }

    /// Distinct object names in first-seen order.
    pub fn objects(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for g in &self.grasps {
            if !out.contains(&g.object) {
                out.push(g.object.clone());
            }
        }
        out
    }

    /// Class index of every grasp under label set `set`.
    pub fn labels_of(&self, set: usize) -> Vec<usize> {
        self.grasps.iter().map(|g| g.labels[set]).collect()
    }

    /// Pressure-like value of `raw` at taxel `taxel` of sensor `sensor`.
    #[inline]
    pub fn pressure(&self, sensor: usize, taxel: usize, raw: f64) -> f64 {
        self.sensors[sensor].transform.apply(taxel, raw)
    }

    /// Pressures of one frame for one sensor.
    pub fn frame_pressures(&self, frame: &Frame, sensor: usize) -> Vec<f64> {
        frame.taxels[sensor]
            .iter()
            .enumerate()
            .map(|(i, &v)| self.pressure(sensor, i, v))
            .collect()
    }

    /// The key frame's pressures of every sensor of grasp `g`: the grasp's patches.
    pub fn key_patches(&self, g: usize) -> Vec<Vec<f64>> {
        let grasp = &self.grasps[g];
        let frame = &grasp.frames[grasp.key_frame];
        (0..self.sensors.len())
            .map(|s| self.frame_pressures(frame, s))
            .collect()
    }
}

/// The key frame by the importers' rule: the frame of greatest total pressure over all
/// sensors (the moment of fullest contact); the first such frame on a tie.
pub fn key_frame_by_pressure(sensors: &[Sensor], frames: &[Frame]) -> usize {
    let total = |f: &Frame| -> f64 {
        sensors
            .iter()
            .zip(&f.taxels)
            .map(|(s, values)| {
                values
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| s.transform.apply(i, v))
                    .sum::<f64>()
            })
            .sum()
    };
    let mut best = 0;
    let mut best_total = f64::NEG_INFINITY;
    for (i, f) in frames.iter().enumerate() {
        let t = total(f);
        if t > best_total {
            best = i;
            best_total = t;
        }
    }
    best
}

impl Grasp {
    pub fn duration(&self) -> f64 {
        self.frames.last().map(|f| f.t).unwrap_or(0.0)
    }
}
