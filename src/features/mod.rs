//! Features computed from sessions: per-finger moments, per-step feature sequences,
//! patches, normalisation.

mod moments;

pub use moments::FingerStats;
