//! What a model of per-step sequences (DS, GS, DU, GU) reads: its feature families, their
//! column names and the training session's min-max range of each, and how a session is
//! read on that range, on its own, or on its first grasps' (the calibration). With the
//! `codes` family it also keeps the training session's dictionaries: a new session is coded
//! on the training session's atoms.

use serde::{Deserialize, Serialize};

use super::{Calibration, ModelError};
use crate::features::{
    Family, FeatureSequences, FeatureSet, FrameCodes, SequenceParams, SequenceRange,
    feature_sequences_in,
};
use crate::session::Session;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceInputs {
    /// The families the columns hold (resolved on the training session).
    pub features: FeatureSet,
    pub feature_names: Vec<String>,
    /// The training session's range of each feature.
    pub min: Vec<f64>,
    pub max: Vec<f64>,
    /// The `codes` family's dictionaries, learned on the training session.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub codes: Option<FrameCodes>,
}

/// The session's sequences of `features`, normalised on `range`.
pub(super) fn sequences(
    session: &Session,
    features: FeatureSet,
    range: SequenceRange,
    codes: Option<&FrameCodes>,
) -> Result<FeatureSequences, ModelError> {
    feature_sequences_in(
        session,
        &SequenceParams {
            features,
            taxel_noise_variance: 0.0,
            seed: 0,
        },
        range,
        codes,
    )
    .map_err(ModelError::Sequences)
}

impl SequenceInputs {
    /// The inputs the training session's sequences of `features` define.
    pub(super) fn fit(
        session: &Session,
        features: FeatureSet,
    ) -> Result<SequenceInputs, ModelError> {
        let feats = sequences(session, features, SequenceRange::Session, None)?;
        Ok(SequenceInputs {
            features: feats.families,
            feature_names: feats.names,
            min: feats.min,
            max: feats.max,
            codes: feats.codes,
        })
    }

    /// The session's sequences as the model reads them under `calibration` (None: on the
    /// model's own range, as when it learns further).
    pub(crate) fn read(
        &self,
        session: &Session,
        calibration: Option<Calibration>,
    ) -> Result<FeatureSequences, ModelError> {
        let own = SequenceRange::Given {
            min: &self.min,
            max: &self.max,
        };
        let range = match calibration {
            None => own,
            Some(c) => match c.grasps(session.grasps.len())? {
                None => own,
                Some(r) => SequenceRange::Grasps(r),
            },
        };
        let feats = sequences(session, self.features, range, self.codes.as_ref())?;
        if feats.names != self.feature_names {
            return Err(ModelError::Mismatch(format!(
                "the model reads {} features ({}); the session gives {} ({})",
                self.feature_names.len(),
                self.feature_names.join(", "),
                feats.names.len(),
                feats.names.join(", ")
            )));
        }
        Ok(feats)
    }

    /// Every length agrees and every range is finite; `dim` is the experts' input size.
    pub(super) fn validate(&self, dim: usize) -> Result<(), ModelError> {
        let n = self.feature_names.len();
        if n == 0 || self.min.len() != n || self.max.len() != n {
            return Err(ModelError::field(
                "model.min",
                format!(
                    "{} minima and {} maxima for {n} features",
                    self.min.len(),
                    self.max.len()
                ),
            ));
        }
        if self.min.iter().chain(&self.max).any(|v| !v.is_finite()) {
            return Err(ModelError::field("model.min", "ranges must be finite"));
        }
        if dim != n {
            return Err(ModelError::field(
                "model.experts",
                format!("experts of {dim} inputs for {n} features"),
            ));
        }
        let coded = self.features.families().contains(&Family::Codes);
        match &self.codes {
            None if coded => Err(ModelError::field(
                "model.codes",
                "the codes family needs its dictionaries",
            )),
            Some(_) if !coded => Err(ModelError::field(
                "model.codes",
                format!("dictionaries for features {} without codes", self.features),
            )),
            Some(c) => {
                c.validate()
                    .map_err(|crate::features::FeatureError::InvalidData(reason)| {
                        ModelError::field("model.codes", reason)
                    })
            }
            None => Ok(()),
        }
    }

    /// The provenance's description of the features.
    pub(super) fn describe(&self) -> String {
        format!(
            "{} per step: {}",
            self.feature_names.len(),
            self.feature_names.join(", ")
        )
    }
}
