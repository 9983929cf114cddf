//! The views of the workbench: every view, and the view of an analysis.

use super::View;
use crate::experiments::result::AnalysisKind;

impl View {
    /// Every view, in the order of their declaration: derived with the command line's
    /// `--view` values, so a new view cannot be missing from the menus.
    pub fn all() -> &'static [View] {
        <View as clap::ValueEnum>::value_variants()
    }

    /// The view that shows results of `kind` (titles and kinds: the registry in `views`).
    pub(super) fn showing(kind: AnalysisKind) -> Option<View> {
        View::all().iter().copied().find(|v| v.kind() == Some(kind))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_analysis_has_one_view_and_every_view_a_title_of_its_own() {
        for kind in [
            AnalysisKind::Stability,
            AnalysisKind::Recognition,
            AnalysisKind::Clustering,
            AnalysisKind::Baselines,
            AnalysisKind::Robustness,
        ] {
            let views: Vec<View> = View::all()
                .iter()
                .copied()
                .filter(|v| v.kind() == Some(kind))
                .collect();
            assert_eq!(views.len(), 1, "{kind:?} is shown by {views:?}");
            assert_eq!(View::showing(kind), Some(views[0]));
        }
        let mut titles: Vec<&str> = View::all().iter().map(|v| v.title()).collect();
        titles.sort_unstable();
        titles.dedup();
        assert_eq!(titles.len(), View::all().len());
    }
}
