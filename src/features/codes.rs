//! The `codes` family: the first paper's sparse codes of every frame, as per-step inputs of
//! the second paper's learners (both papers on one session).
//!
//! Each sensor has its own dictionary, learned without labels on the session's frames: a
//! frame's pressures on that sensor, z-scored per taxel over the session, are one patch.
//! The dictionary is complete (as many bases as the sensor has taxels), so the codes
//! re-express the same information sparsely rather than compress it, and there is no size
//! to choose on the data. β = γ = 1 (our convention; the useful range on z-scored data,
//! see `sparse`). A model keeps its training session's dictionaries and z-scoring, so a
//! new session is coded on the training session's atoms.

use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use super::FeatureError;
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::sparse::{Dictionary, DictionaryParams, SparseError};

/// Patches a dictionary is learned from, at most (a seeded sample of the frames): enough
/// for a complete dictionary of a few dozen taxels, and a bounded learning time.
const MAX_PATCHES: usize = 4000;

/// One sensor's dictionary and the z-scoring of its taxels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorCodes {
    pub mean: Vec<f64>,
    pub sd: Vec<f64>,
    pub dictionary: Dictionary,
}

/// Every sensor's dictionary, and the penalty γ of the codes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameCodes {
    pub sensors: Vec<SensorCodes>,
    pub gamma: f64,
}

impl SensorCodes {
    /// The dictionary of one sensor from its frames (rows: frames, columns: taxels).
    fn learn(frames: ArrayView2<f64>, seed: u64) -> Result<SensorCodes, SparseError> {
        let (n, taxels) = frames.dim();
        if n == 0 || taxels == 0 {
            return Err(SparseError::Data(
                "a sensor with no frames or taxels".into(),
            ));
        }
        let mean: Vec<f64> = frames
            .columns()
            .into_iter()
            .map(|c| c.sum() / n as f64)
            .collect();
        let sd: Vec<f64> = frames
            .columns()
            .into_iter()
            .zip(&mean)
            .map(|(c, m)| {
                let sd = (c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64).sqrt();
                // A constant taxel carries nothing: it codes as 0 rather than 0/0.
                if sd > 0.0 { sd } else { 1.0 }
            })
            .collect();
        let mut codes = SensorCodes {
            mean,
            sd,
            dictionary: Dictionary {
                atoms: Array2::zeros((0, taxels)),
                norm_bound: 1.0,
            },
        };
        let mut rows: Vec<usize> = (0..n).collect();
        if n > MAX_PATCHES {
            let mut rng = Rng::stream(seed, 0);
            rng.shuffle(&mut rows);
            rows.truncate(MAX_PATCHES);
            rows.sort_unstable();
        }
        let patches = codes.standardise(frames.select(ndarray::Axis(0), &rows).view());
        let params = DictionaryParams {
            num_bases: taxels,
            max_iter: 50,
            seed,
            ..DictionaryParams::default()
        };
        codes.dictionary = params
            .fit_within(patches.view(), &Progress::new())?
            .dictionary;
        Ok(codes)
    }

    fn standardise(&self, frames: ArrayView2<f64>) -> Array2<f64> {
        let mut z = frames.to_owned();
        for mut row in z.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (*v - self.mean[j]) / self.sd[j];
            }
        }
        z
    }
}

impl FrameCodes {
    /// One dictionary per sensor, from `frames[s]` (every frame's pressures on sensor `s`).
    pub fn learn(frames: &[Array2<f64>], seed: u64) -> Result<FrameCodes, SparseError> {
        let sensors = frames
            .iter()
            .map(|f| SensorCodes::learn(f.view(), seed))
            .collect::<Result<_, _>>()?;
        Ok(FrameCodes {
            sensors,
            gamma: 1.0,
        })
    }

    /// The codes of sensor `s`'s frames (rows: frames, columns: bases).
    pub fn encode(&self, s: usize, frames: ArrayView2<f64>) -> Result<Array2<f64>, SparseError> {
        let codes = &self.sensors[s];
        if frames.ncols() != codes.mean.len() {
            return Err(SparseError::Data(format!(
                "{} taxels on sensor {s}, its dictionary {}",
                frames.ncols(),
                codes.mean.len()
            )));
        }
        codes
            .dictionary
            .encode(codes.standardise(frames).view(), self.gamma)
    }

    /// Every sensor's z-scoring and atoms agree in size and are finite, with a positive
    /// spread and a non-negative finite γ (a loaded model's).
    pub fn validate(&self) -> Result<(), FeatureError> {
        if !(self.gamma >= 0.0 && self.gamma.is_finite()) {
            return Err(FeatureError::InvalidData(format!(
                "gamma must be finite and ≥ 0, got {}",
                self.gamma
            )));
        }
        for (s, c) in self.sensors.iter().enumerate() {
            let n = c.mean.len();
            let d = &c.dictionary;
            if n == 0 || c.sd.len() != n || d.dim() != n || d.num_bases() == 0 {
                return Err(FeatureError::InvalidData(format!(
                    "sensor {s}: {n} means, {} spreads and {} bases of {} taxels",
                    c.sd.len(),
                    d.num_bases(),
                    d.dim()
                )));
            }
            let finite = c
                .mean
                .iter()
                .chain(&c.sd)
                .chain(d.atoms.iter())
                .all(|v| v.is_finite());
            if !finite || c.sd.iter().any(|&v| v <= 0.0) {
                return Err(FeatureError::InvalidData(format!(
                    "sensor {s}: non-finite values or a spread ≤ 0"
                )));
            }
        }
        Ok(())
    }

    /// Bases of each sensor.
    pub fn widths(&self) -> Vec<usize> {
        self.sensors
            .iter()
            .map(|s| s.dictionary.num_bases())
            .collect()
    }
}
