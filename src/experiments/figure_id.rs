//! The figures a result can hold, named once: a report pushes a figure under its id and a
//! view's default tiles name the same id, so renaming one side is a compile error rather
//! than a tile that says "has no figure" at run time. The ids keep the words results were
//! saved with (`bases-raw`, `noise`, …), so projects and layouts saved before still load.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::perturb::Perturbation;

/// One figure of an [`AnalysisResult`](super::result::AnalysisResult).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum FigureId {
    // Grasp stability (first paper).
    BasesRaw,
    BasesFiltered,
    Reconstruction,
    ScoreVsBases,
    BetaGamma,
    ConfusionKfold,
    ConfusionObjects,
    BasisUsage,
    UsageDifferential,
    CoefficientDifferential,
    // Recognition (second paper).
    AccuracyByTrials,
    EarlyClassification,
    Lengthscales,
    /// A recognition result's or a held-out result's confusion matrix.
    Confusion,
    // Clustering by novelty threshold.
    ScoresVsThreshold,
    ClustersVsThreshold,
    NmiVsEffective,
    ScoresAt10,
    // Table I baselines.
    NmiVsClusters,
    Scores,
    SvmGrid,
    // Held-out evaluation.
    Objects,
    Early,
    Clusters,
    /// Where methods fail: one sweep of a perturbation's strength.
    Robustness(Perturbation),
}

/// Every id without data (the robustness sweeps' ids come from [`Perturbation::ALL`]).
const PLAIN: [FigureId; 24] = [
    FigureId::BasesRaw,
    FigureId::BasesFiltered,
    FigureId::Reconstruction,
    FigureId::ScoreVsBases,
    FigureId::BetaGamma,
    FigureId::ConfusionKfold,
    FigureId::ConfusionObjects,
    FigureId::BasisUsage,
    FigureId::UsageDifferential,
    FigureId::CoefficientDifferential,
    FigureId::AccuracyByTrials,
    FigureId::EarlyClassification,
    FigureId::Lengthscales,
    FigureId::Confusion,
    FigureId::ScoresVsThreshold,
    FigureId::ClustersVsThreshold,
    FigureId::NmiVsEffective,
    FigureId::ScoresAt10,
    FigureId::NmiVsClusters,
    FigureId::Scores,
    FigureId::SvmGrid,
    FigureId::Objects,
    FigureId::Early,
    FigureId::Clusters,
];

impl FigureId {
    /// The id's word: the file stem of its export and its key in saved results.
    pub fn key(self) -> &'static str {
        match self {
            FigureId::BasesRaw => "bases-raw",
            FigureId::BasesFiltered => "bases-filtered",
            FigureId::Reconstruction => "reconstruction",
            FigureId::ScoreVsBases => "score-vs-bases",
            FigureId::BetaGamma => "beta-gamma",
            FigureId::ConfusionKfold => "confusion-kfold",
            FigureId::ConfusionObjects => "confusion-objects",
            FigureId::BasisUsage => "basis-usage",
            FigureId::UsageDifferential => "usage-differential",
            FigureId::CoefficientDifferential => "coefficient-differential",
            FigureId::AccuracyByTrials => "accuracy-by-trials",
            FigureId::EarlyClassification => "early-classification",
            FigureId::Lengthscales => "lengthscales",
            FigureId::Confusion => "confusion",
            FigureId::ScoresVsThreshold => "scores-vs-threshold",
            FigureId::ClustersVsThreshold => "clusters-vs-threshold",
            FigureId::NmiVsEffective => "nmi-vs-effective",
            FigureId::ScoresAt10 => "scores-at-10",
            FigureId::NmiVsClusters => "nmi-vs-clusters",
            FigureId::Scores => "scores",
            FigureId::SvmGrid => "svm-grid",
            FigureId::Objects => "objects",
            FigureId::Early => "early",
            FigureId::Clusters => "clusters",
            FigureId::Robustness(p) => p.key(),
        }
    }

    /// The id of word `key`, if any.
    pub fn from_key(key: &str) -> Option<FigureId> {
        PLAIN
            .into_iter()
            .chain(Perturbation::ALL.into_iter().map(FigureId::Robustness))
            .find(|id| id.key() == key)
    }
}

impl fmt::Display for FigureId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

impl From<FigureId> for String {
    fn from(id: FigureId) -> String {
        id.key().to_string()
    }
}

/// A saved figure key that no figure has.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown figure `{0}`")]
pub struct UnknownFigure(pub String);

impl TryFrom<String> for FigureId {
    type Error = UnknownFigure;
    fn try_from(key: String) -> Result<FigureId, UnknownFigure> {
        FigureId::from_key(&key).ok_or(UnknownFigure(key))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_id_has_its_own_word_and_comes_back_from_it() {
        let ids: Vec<FigureId> = PLAIN
            .into_iter()
            .chain(Perturbation::ALL.into_iter().map(FigureId::Robustness))
            .collect();
        let mut keys: Vec<&str> = ids.iter().map(|id| id.key()).collect();
        for id in &ids {
            assert_eq!(FigureId::from_key(id.key()), Some(*id));
            let json = serde_json::to_string(id).unwrap();
            assert_eq!(json, format!("\"{}\"", id.key()));
            assert_eq!(serde_json::from_str::<FigureId>(&json).unwrap(), *id);
        }
        keys.sort_unstable();
        let n = keys.len();
        keys.dedup();
        assert_eq!(keys.len(), n, "two ids share a word");
        assert!(serde_json::from_str::<FigureId>("\"no-such-figure\"").is_err());
    }
}
