//! One selection shared by every view, and the commands that change it. Views never mutate
//! the selection (or another view) while drawing: they push a [`Command`] and the app applies
//! the queue between frames, so every view of a frame sees the same selection.

use super::View;
use crate::experiments::clustering::UnsupervisedLearner;
use crate::experiments::recognition::SupervisedLearner;
use crate::experiments::stability::Config;
use crate::features::FeatureSet;

/// What the user has selected: a set of grasps of one session, one focused grasp (the one the
/// replay shows), and the part of a figure the set came from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selection {
    /// Index of the session the grasps belong to.
    pub session: Option<usize>,
    /// Selected grasps (indices into the session's grasps), most relevant first.
    pub grasps: Vec<usize>,
    /// The focused grasp: (session, grasp).
    pub focus: Option<(usize, usize)>,
    /// Where the set came from, in words ("confusion cell: true failure, predicted success").
    pub origin: String,
    /// A focused basis of a stability result: (result index, basis).
    pub basis: Option<(usize, usize)>,
    /// A perturbation strength chosen on a robustness chart: (result index, figure, strength).
    pub strength: Option<(usize, String, f64)>,
}

impl Selection {
    pub fn contains(&self, session: usize, grasp: usize) -> bool {
        self.session == Some(session) && self.grasps.contains(&grasp)
    }

    /// Sessions close: indices above `closed` shift down, a selection in it goes.
    pub fn session_closed(&mut self, closed: usize) {
        let shift = |s: usize| if s > closed { s - 1 } else { s };
        match self.session {
            Some(s) if s == closed => {
                self.session = None;
                self.grasps.clear();
                self.origin.clear();
            }
            Some(s) => self.session = Some(shift(s)),
            None => {}
        }
        self.focus = match self.focus {
            Some((s, _)) if s == closed => None,
            Some((s, g)) => Some((shift(s), g)),
            None => None,
        };
    }
}

/// A change a view asks for; applied by the app between frames.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Select these grasps of session `session` (the first is focused).
    SelectGrasps {
        session: usize,
        grasps: Vec<usize>,
        origin: String,
    },
    /// Focus (and replay) one grasp; the selected set stays.
    Focus { session: usize, grasp: usize },
    /// Focus a basis of a stability result.
    FocusBasis { result: usize, basis: usize },
    /// A perturbation strength on a robustness chart.
    Strength {
        result: usize,
        figure: String,
        strength: f64,
    },
    /// Clear the selected set (the focus stays).
    ClearSelection,
    /// Show result `result` in its view and switch to that view.
    OpenResult(usize),
    /// Switch view.
    Open(View),
    /// Open the result of this model on the active session, or train it if there is none
    /// (a point of a frontier).
    TrainModel(ModelSpec),
}

/// A model of a given size: what a frontier's point stands for.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSpec {
    Recognition {
        learner: SupervisedLearner,
        features: FeatureSet,
        capacity: usize,
        tau: usize,
    },
    Stability(Config),
    /// DU or GU at one novelty threshold (the Clustering view).
    Clustering {
        learner: UnsupervisedLearner,
        threshold: f64,
    },
    /// The Baselines view: k-means and the SOM with `k` centres (units), or (`k` None) the
    /// RBF SVM, whose C × gamma grid that view searches.
    Baselines {
        k: Option<usize>,
    },
}

impl ModelSpec {
    /// The size in the words a result's `model_size` uses.
    pub fn knobs(&self) -> String {
        match self {
            ModelSpec::Recognition { capacity, tau, .. } => {
                format!("capacity {capacity}, tau {tau}")
            }
            ModelSpec::Stability(c) => format!(
                "num_bases {}, beta {}, gamma {}",
                c.num_bases, c.beta, c.gamma
            ),
            ModelSpec::Clustering { threshold, .. } => format!("novelty threshold {threshold}"),
            ModelSpec::Baselines { k: Some(k) } => format!("k {k}"),
            ModelSpec::Baselines { k: None } => "C × gamma grid".to_string(),
        }
    }
}
