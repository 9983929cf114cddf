//! Features computed from sessions: per-finger moments, per-step feature sequences,
//! patches, normalisation.

mod moments;
mod patches;
pub mod sequence;

pub use moments::FingerStats;
pub use patches::{KeyFramePatches, PatchError, PatchScaling, Standardizer};
pub use sequence::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
