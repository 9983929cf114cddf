//! Features computed from sessions: per-finger moments, per-step feature sequences,
//! patches, normalisation.

pub mod codes;
mod moments;
pub mod normalise;
mod patches;
pub mod sequence;
pub mod table_one;

pub use codes::FrameCodes;
pub use moments::FingerStats;
pub use normalise::{Normalisation, Normaliser, Standardizer};
pub use patches::{KeyFramePatches, PatchError, PatchScaling};
pub use sequence::{
    Family, FeatureSequences, FeatureSet, SequenceParams, SequenceRange, feature_sequences,
    feature_sequences_in,
};

/// Features that cannot be computed or scaled from the data given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FeatureError {
    #[error("invalid data: {0}")]
    InvalidData(String),
}
