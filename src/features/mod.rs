//! Features computed from sessions: per-finger moments, per-step feature sequences,
//! patches, normalisation.

mod moments;
pub mod sequence;

pub use moments::FingerStats;
pub use sequence::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
