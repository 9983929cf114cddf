//! Patches for sparse coding: one per sensor from each grasp's key frame (the moment of
//! full contact), in pressure units ("more contact = larger value", through each sensor's
//! value transform), optionally z-scored per taxel over the session.
//!
//! A grasp's *image* is the concatenation of its sensors' key-frame pressures (for BTS3:
//! ff, mf, th × 24 electrodes = 72 values); its *patches* are the per-sensor slices of
//! that image, which all sensors must share in size because one dictionary codes them
//! all. Scaling is fitted on the session's images, per taxel (column of the image), and
//! the same [`Standardizer`] is applied to any grasp coded later.

use ndarray::{Array2, ArrayView1};
use serde::{Deserialize, Serialize};

use super::normalise::Standardizer;
use crate::session::Session;

/// How patches are scaled before sparse coding.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PatchScaling {
    /// Each taxel of each sensor z-scored over all grasps of the session (the default:
    /// `beta`/`gamma` around 0.1–5 are then meaningful for any sensor).
    #[default]
    ZScorePerTaxel,
    /// Pressures as they are (the paper's β = 950, γ = 1000 lived on its raw scale).
    None,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PatchError {
    #[error("the session has no grasps")]
    NoGrasps,
    #[error("the session has no sensors")]
    NoSensors,
    #[error(
        "sensors differ in taxel count ({0}): one dictionary codes every sensor's patch, so they must match"
    )]
    UnequalSensors(String),
    #[error("grasp {grasp}: key frame {key_frame} is out of range ({frames} frames)")]
    KeyFrame {
        grasp: usize,
        key_frame: usize,
        frames: usize,
    },
    #[error("grasp {grasp}, sensor {sensor}: {found} taxel values where the layout has {expected}")]
    TaxelCount {
        grasp: usize,
        sensor: usize,
        found: usize,
        expected: usize,
    },
    #[error("an image of {found} values where the session's grasps have {expected}")]
    ImageLength { found: usize, expected: usize },
    #[error("grasp {grasp}, sensor {sensor}, taxel {taxel}: value {value} is not finite")]
    NotFinite {
        grasp: usize,
        sensor: usize,
        taxel: usize,
        value: f64,
    },
}

/// Key-frame patches of a session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeyFramePatches {
    pub sensor_names: Vec<String>,
    /// Taxels per sensor = patch dimension.
    pub dim: usize,
    /// Pressures of each grasp's key frame, sensors side by side (grasps × sensors·dim).
    pub pressures: Array2<f64>,
    pub scaling: PatchScaling,
    /// The fitted scaling (None for `PatchScaling::None`).
    pub scaler: Option<Standardizer>,
}

impl KeyFramePatches {
    /// Read every grasp's key frame and fit the scaling on the session.
    pub fn from_session(session: &Session, scaling: PatchScaling) -> Result<Self, PatchError> {
        if session.grasps.is_empty() {
            return Err(PatchError::NoGrasps);
        }
        if session.sensors.is_empty() {
            return Err(PatchError::NoSensors);
        }
        let counts: Vec<usize> = session
            .sensors
            .iter()
            .map(|s| s.layout.taxel_count())
            .collect();
        let dim = counts[0];
        if counts.iter().any(|&c| c != dim) || dim == 0 {
            let desc = session
                .sensors
                .iter()
                .zip(&counts)
                .map(|(s, c)| format!("{}: {c}", s.name))
                .collect::<Vec<_>>()
                .join(", ");
            return Err(PatchError::UnequalSensors(desc));
        }
        let n_s = session.sensors.len();
        let mut pressures = Array2::<f64>::zeros((session.grasps.len(), n_s * dim));
        for (g, grasp) in session.grasps.iter().enumerate() {
            let frame = grasp
                .frames
                .get(grasp.key_frame)
                .ok_or(PatchError::KeyFrame {
                    grasp: g,
                    key_frame: grasp.key_frame,
                    frames: grasp.frames.len(),
                })?;
            for s in 0..n_s {
                let raw = frame.taxels.get(s).map(|v| v.as_slice()).unwrap_or(&[]);
                if raw.len() != dim {
                    return Err(PatchError::TaxelCount {
                        grasp: g,
                        sensor: s,
                        found: raw.len(),
                        expected: dim,
                    });
                }
                for (t, &v) in raw.iter().enumerate() {
                    let p = session.pressure(s, t, v);
                    if !p.is_finite() {
                        return Err(PatchError::NotFinite {
                            grasp: g,
                            sensor: s,
                            taxel: t,
                            value: v,
                        });
                    }
                    pressures[[g, s * dim + t]] = p;
                }
            }
        }
        let scaler = match scaling {
            PatchScaling::ZScorePerTaxel => Some(Standardizer::fit(pressures.view())),
            PatchScaling::None => None,
        };
        Ok(KeyFramePatches {
            sensor_names: session.sensors.iter().map(|s| s.name.clone()).collect(),
            dim,
            pressures,
            scaling,
            scaler,
        })
    }

    pub fn grasp_count(&self) -> usize {
        self.pressures.nrows()
    }

    pub fn sensor_count(&self) -> usize {
        self.sensor_names.len()
    }

    /// Scaled images (grasps × sensors·dim).
    pub fn images(&self) -> Array2<f64> {
        match &self.scaler {
            Some(s) => s.transform(self.pressures.view()),
            None => self.pressures.clone(),
        }
    }

    /// Scaled patches, one row per (grasp, sensor), grasp-major: row `g · S + s`.
    pub fn patches(&self) -> Array2<f64> {
        let g = self.grasp_count();
        let images = self.images();
        images
            .into_shape_with_order((g * self.sensor_count(), self.dim))
            .expect("contiguous images reshape into patches")
    }

    /// Scale the key-frame pressures of a new grasp (sensors side by side) exactly as the
    /// session's were; returns its patches (sensors × dim).
    pub fn scale_image(&self, pressures: ArrayView1<f64>) -> Result<Array2<f64>, PatchError> {
        let expected = self.sensor_count() * self.dim;
        if pressures.len() != expected {
            return Err(PatchError::ImageLength {
                found: pressures.len(),
                expected,
            });
        }
        let mut out = vec![0.0; expected];
        match &self.scaler {
            Some(s) => s.transform_into(pressures, &mut out),
            None => out
                .iter_mut()
                .zip(pressures.iter())
                .for_each(|(o, v)| *o = *v),
        }
        Ok(Array2::from_shape_vec((self.sensor_count(), self.dim), out)
            .expect("image length is sensors × dim"))
    }
}
