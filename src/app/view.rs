//! The views of the workbench: their titles and the analysis each shows.

use super::View;
use crate::experiments::result::AnalysisKind;

impl View {
    /// Every view, in the order of their declaration: derived with the command line's
    /// `--view` values, so a new view cannot be missing from the menus.
    pub fn all() -> &'static [View] {
        <View as clap::ValueEnum>::value_variants()
    }

    pub fn title(self) -> &'static str {
        match self {
            View::Replay => "Replay",
            View::Stability => "Grasp stability",
            View::Recognition => "Recognition",
            View::Clustering => "Clustering",
            View::Baselines => "Baselines",
            View::SpeedAccuracy => "Speed vs accuracy",
            View::Robustness => "Where methods fail",
        }
    }

    /// The analysis this view shows, if it shows one.
    pub fn kind(self) -> Option<AnalysisKind> {
        match self {
            View::Stability => Some(AnalysisKind::Stability),
            View::Recognition => Some(AnalysisKind::Recognition),
            View::Clustering => Some(AnalysisKind::Clustering),
            View::Baselines => Some(AnalysisKind::Baselines),
            View::Robustness => Some(AnalysisKind::Robustness),
            View::Replay | View::SpeedAccuracy => None,
        }
    }

    pub(super) fn of(kind: AnalysisKind) -> View {
        match kind {
            AnalysisKind::Baselines => View::Baselines,
            AnalysisKind::Recognition => View::Recognition,
            AnalysisKind::Clustering => View::Clustering,
            AnalysisKind::Stability => View::Stability,
            AnalysisKind::Robustness => View::Robustness,
        }
    }
}
