//! From the numbers of a result to the grasps behind them: which of the session's grasps
//! stand behind each cell of a confusion map or contingency table and each basis image,
//! and how a grasp-stability model sees every grasp (its codes, reconstruction and SVM
//! decision). Plain data inside an [`AnalysisResult`](super::result::AnalysisResult), so
//! a saved project keeps them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::figure_id::FigureId;
use crate::figures::{Figure, FigureKind};

/// Which of the session's grasps stand behind the parts of one figure of a result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspLinks {
    /// The figure in `AnalysisResult::figures` (or, with `detail`, the figure whose
    /// `FigureDetails` item this is).
    pub figure: FigureId,
    /// For a detail figure: the index of the item in `FigureDetails::items`; None for the
    /// figure itself.
    pub detail: Option<usize>,
    /// One per part that has grasps behind it; parts without grasps have no item.
    pub items: Vec<LinkedItem>,
}

/// The grasps behind one part of a figure.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkedItem {
    /// A heatmap cell [row, col] exactly as the figure's `values[row][col]` is indexed,
    /// or [image index, 0] for an image of an image grid.
    pub at: [usize; 2],
    /// Indices into `Session::grasps`, most relevant first, no duplicates.
    pub grasps: Vec<usize>,
    /// In words, e.g. "true failure, predicted success: 12 grasps".
    pub text: String,
}

impl GraspLinks {
    /// The item of part `at`, if grasps stand behind it.
    pub fn item(&self, at: [usize; 2]) -> Option<&LinkedItem> {
        self.items.iter().find(|i| i.at == at)
    }

    /// Links grouped from (part, grasp) observations: a grasp observed several times in a
    /// part counts once, the grasps seen most often come first (ties: lower index first),
    /// parts in row-major order. `text` describes a part from its distinct grasps and
    /// its observations.
    pub fn from_observations(
        figure: FigureId,
        detail: Option<usize>,
        observations: impl IntoIterator<Item = ([usize; 2], usize)>,
        text: impl Fn([usize; 2], usize, usize) -> String,
    ) -> GraspLinks {
        let mut cells: BTreeMap<[usize; 2], BTreeMap<usize, usize>> = BTreeMap::new();
        for (at, grasp) in observations {
            *cells.entry(at).or_default().entry(grasp).or_default() += 1;
        }
        let items = cells
            .into_iter()
            .map(|(at, seen)| {
                let total = seen.values().sum();
                let mut grasps: Vec<(usize, usize)> = seen.into_iter().collect();
                grasps.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
                LinkedItem {
                    at,
                    text: text(at, grasps.len(), total),
                    grasps: grasps.into_iter().map(|(g, _)| g).collect(),
                }
            })
            .collect();
        GraspLinks {
            figure,
            detail,
            items,
        }
    }

    /// Whether every item names a part that `figure` has: a cell of a heatmap or an image
    /// of an image grid (as [image, 0]).
    pub fn check_against(&self, figure: &Figure) -> Result<(), LinkError> {
        for item in &self.items {
            let fits = match &figure.kind {
                FigureKind::Heatmap(h) => h
                    .values
                    .get(item.at[0])
                    .is_some_and(|row| item.at[1] < row.len()),
                FigureKind::ImageGrid(g) => item.at[0] < g.images.len() && item.at[1] == 0,
                _ => false,
            };
            if !fits {
                return Err(LinkError::NoPart {
                    figure: self.figure,
                    at: item.at,
                });
            }
        }
        Ok(())
    }
}

/// Links that do not fit their result: a figure it lacks, or a part its figure lacks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinkError {
    #[error(
        "links name figure `{figure}`{} which the result does not have",
        detail.map_or(String::new(), |i| format!(", detail {i}"))
    )]
    NoFigure {
        figure: FigureId,
        detail: Option<usize>,
    },
    #[error("links of `{figure}`: figure has no part {at:?}")]
    NoPart { figure: FigureId, at: [usize; 2] },
}

/// A grasp-stability model's view of one grasp (for the replay of a focused grasp).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GraspCode {
    /// Index into `Session::grasps`.
    pub grasp: usize,
    /// The true class name.
    pub truth: String,
    /// The class name predicted by the k-fold cross validation's fold that tested this
    /// grasp.
    pub predicted: String,
    /// That fold's linear SVM decision value for the grasp: positive = predicted failure
    /// (the failure class), zero or negative = predicted success.
    pub decision: f64,
    /// One per sensor, in session sensor order.
    pub patches: Vec<PatchCode>,
}

/// One sensor's key-frame patch of a grasp, its sparse code and its reconstruction.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PatchCode {
    /// Index into `Session::sensors`.
    pub sensor: usize,
    /// Per taxel of that sensor, in the scaled units that were coded.
    pub patch: Vec<f64>,
    /// (basis, coefficient) of every non-zero coefficient, largest |coefficient| first.
    pub terms: Vec<(usize, f64)>,
    /// Σ coefficient × basis, per taxel.
    pub reconstruction: Vec<f64>,
    /// ||patch − reconstruction|| / ||patch|| (0 for an all-zero patch).
    pub relative_error: f64,
}

impl GraspCode {
    /// The largest |coefficient| of basis `b` over the grasp's patches (0 if unused).
    pub fn strength(&self, b: usize) -> f64 {
        self.patches
            .iter()
            .flat_map(|p| &p.terms)
            .filter(|(j, _)| *j == b)
            .map(|(_, c)| c.abs())
            .fold(0.0, f64::max)
    }
}

/// Links of a basis-image grid: image i (showing basis `bases[i]`) → the grasps whose codes
/// use that basis, by their largest |coefficient| on it over their patches, descending
/// (ties: lower grasp index first).
pub fn basis_links(figure: FigureId, bases: &[usize], codes: &[GraspCode]) -> GraspLinks {
    let items = bases
        .iter()
        .enumerate()
        .filter_map(|(i, &b)| {
            let mut users: Vec<(usize, f64)> = codes
                .iter()
                .map(|c| (c.grasp, c.strength(b)))
                .filter(|(_, s)| *s > 0.0)
                .collect();
            if users.is_empty() {
                return None;
            }
            users.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            Some(LinkedItem {
                at: [i, 0],
                text: format!(
                    "basis {}: {} grasp{} use it",
                    b + 1,
                    users.len(),
                    if users.len() == 1 { "" } else { "s" }
                ),
                grasps: users.into_iter().map(|(g, _)| g).collect(),
            })
        })
        .collect();
    GraspLinks {
        figure,
        detail: None,
        items,
    }
}

/// "1 grasp" / "n grasps".
pub fn grasps_text(n: usize) -> String {
    format!("{n} grasp{}", if n == 1 { "" } else { "s" })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn observations_group_by_part_and_order_grasps_by_frequency() {
        let obs = [
            ([1, 0], 5),
            ([0, 1], 3),
            ([1, 0], 2),
            ([1, 0], 2),
            ([1, 0], 9),
        ];
        let l = GraspLinks::from_observations(FigureId::Confusion, None, obs, |at, n, total| {
            format!("{at:?} {n} {total}")
        });
        assert_eq!(l.items.len(), 2);
        assert_eq!(l.items[0].at, [0, 1]);
        let item = l.item([1, 0]).unwrap();
        assert_eq!(item.grasps, vec![2, 5, 9]);
        assert_eq!(item.text, "[1, 0] 3 4");
        assert!(l.item([0, 0]).is_none());
    }

    #[test]
    fn basis_links_list_users_by_their_strongest_coefficient() {
        let code = |grasp: usize, terms: Vec<Vec<(usize, f64)>>| GraspCode {
            grasp,
            patches: terms
                .into_iter()
                .enumerate()
                .map(|(sensor, terms)| PatchCode {
                    sensor,
                    terms,
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        };
        let codes = [
            code(4, vec![vec![(0, 0.5)], vec![(1, -2.0)]]),
            code(7, vec![vec![(1, 1.0), (0, -0.9)], vec![]]),
            code(8, vec![vec![], vec![(2, 0.1)]]),
        ];
        let l = basis_links(FigureId::BasesRaw, &[0, 1, 3], &codes);
        assert_eq!(l.items.len(), 2, "basis 3 has no users");
        assert_eq!(l.items[0].grasps, vec![7, 4]);
        assert_eq!(l.items[0].text, "basis 1: 2 grasps use it");
        assert_eq!(l.items[1].at, [1, 0]);
        assert_eq!(l.items[1].grasps, vec![4, 7]);
    }
}
