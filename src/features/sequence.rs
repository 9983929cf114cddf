//! Per-time-step feature sequences of the second paper (Sec. V-C): at every frame the
//! joint encoders, then for every finger the mean, sd, skewness, max and min of its taxel
//! pressures (9 + 5 × 5 = 34 on the iCub), each min-max normalised to [0, 1].
//!
//! The normalisation range is taken over every frame of every grasp of the session (the
//! paper normalises the dataset; with a fixed session this is what a deployed robot would
//! calibrate once). Optional Gaussian noise on the raw taxel readings reproduces the
//! paper's robustness experiment (Fig. 8: variances 100 and 1000 on the 0–255 readings);
//! readings are not clipped after the noise, as the paper does not say they were.

use std::str::FromStr;

use ndarray::Array2;
use serde::{Deserialize, Serialize};

use super::FingerStats;
use crate::rng::Rng;
use crate::session::Session;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureSet {
    /// Encoders and tactile moments (34 on the iCub).
    All,
    /// Tactile moments only (25).
    Tactile,
    /// Encoders only (9).
    Encoder,
}

impl FromStr for FeatureSet {
    type Err = SequenceError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "all" => Ok(FeatureSet::All),
            "tactile" => Ok(FeatureSet::Tactile),
            "encoder" => Ok(FeatureSet::Encoder),
            other => Err(SequenceError::Parameter {
                name: "features",
                reason: format!("`{other}` is not one of all, tactile, encoder"),
            }),
        }
    }
}

impl FeatureSet {
    pub fn name(self) -> &'static str {
        match self {
            FeatureSet::All => "all",
            FeatureSet::Tactile => "tactile",
            FeatureSet::Encoder => "encoder",
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SequenceError {
    #[error("invalid parameter `{name}`: {reason}")]
    Parameter { name: &'static str, reason: String },
    #[error("session cannot give {set} features: {reason}")]
    Session { set: &'static str, reason: String },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceParams {
    pub features: FeatureSet,
    /// Variance of Gaussian noise added to each raw taxel reading (0: none).
    pub taxel_noise_variance: f64,
    /// Seed of that noise (grasp g uses stream g).
    pub seed: u64,
}

impl Default for SequenceParams {
    fn default() -> Self {
        SequenceParams {
            features: FeatureSet::All,
            taxel_noise_variance: 0.0,
            seed: 0,
        }
    }
}

impl SequenceParams {
    pub fn validate(&self) -> Result<(), SequenceError> {
        if !(self.taxel_noise_variance.is_finite() && self.taxel_noise_variance >= 0.0) {
            return Err(SequenceError::Parameter {
                name: "taxel_noise_variance",
                reason: "must be finite and non-negative".into(),
            });
        }
        Ok(())
    }
}

/// One normalised T × D matrix per grasp (rows are time steps), in session order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeatureSequences {
    pub names: Vec<String>,
    pub sequences: Vec<Array2<f64>>,
    /// Raw range of each feature before normalisation.
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

impl FeatureSequences {
    pub fn dim(&self) -> usize {
        self.names.len()
    }
}

pub fn feature_sequences(
    session: &Session,
    params: &SequenceParams,
) -> Result<FeatureSequences, SequenceError> {
    params.validate()?;
    let set = params.features.name();
    let n_enc = session.encoders.len();
    let use_enc = params.features != FeatureSet::Tactile;
    let use_tac = params.features != FeatureSet::Encoder;
    if use_enc && n_enc == 0 {
        return Err(SequenceError::Session {
            set,
            reason: "it has no joint encoders".into(),
        });
    }
    if use_tac && session.sensors.is_empty() {
        return Err(SequenceError::Session {
            set,
            reason: "it has no tactile sensors".into(),
        });
    }
    let mut names = Vec::new();
    if use_enc {
        names.extend(session.encoders.iter().map(|e| format!("encoder/{e}")));
    }
    if use_tac {
        for s in &session.sensors {
            for stat in FingerStats::NAMES {
                names.push(format!("{}/{stat}", s.name));
            }
        }
    }
    let dim = names.len();
    let sd = params.taxel_noise_variance.sqrt();
    let mut sequences = Vec::with_capacity(session.grasps.len());
    for (g, grasp) in session.grasps.iter().enumerate() {
        let mut rng = Rng::stream(params.seed, g as u64);
        let mut m = Array2::zeros((grasp.frames.len(), dim));
        for (t, frame) in grasp.frames.iter().enumerate() {
            let mut row = m.row_mut(t);
            let mut c = 0;
            if use_enc {
                if frame.encoders.len() != n_enc {
                    return Err(SequenceError::Session {
                        set,
                        reason: format!(
                            "grasp {g} frame {t} has {} encoders, the session names {n_enc}",
                            frame.encoders.len()
                        ),
                    });
                }
                for &e in &frame.encoders {
                    row[c] = e;
                    c += 1;
                }
            }
            if use_tac {
                for (s, raw) in frame.taxels.iter().enumerate() {
                    let p: Vec<f64> = raw
                        .iter()
                        .enumerate()
                        .map(|(i, &v)| {
                            let noisy = if sd > 0.0 { v + sd * rng.normal() } else { v };
                            session.pressure(s, i, noisy)
                        })
                        .collect();
                    for v in FingerStats::of(&p).to_array() {
                        row[c] = v;
                        c += 1;
                    }
                }
                if c != dim {
                    return Err(SequenceError::Session {
                        set,
                        reason: format!(
                            "grasp {g} frame {t} does not have one taxel vector per sensor"
                        ),
                    });
                }
            }
        }
        sequences.push(m);
    }
    let mut min = vec![f64::INFINITY; dim];
    let mut max = vec![f64::NEG_INFINITY; dim];
    for m in &sequences {
        for row in m.rows() {
            for (j, &v) in row.iter().enumerate() {
                min[j] = min[j].min(v);
                max[j] = max[j].max(v);
            }
        }
    }
    for m in &mut sequences {
        for mut row in m.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                let range = max[j] - min[j];
                // A constant feature carries nothing: it becomes 0 rather than 0/0.
                *v = if range > 0.0 {
                    (*v - min[j]) / range
                } else {
                    0.0
                };
            }
        }
    }
    Ok(FeatureSequences {
        names,
        sequences,
        min,
        max,
    })
}
