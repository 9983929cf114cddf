//! One selection shared by every view, and the commands that change it. Views never mutate
//! the selection (or another view) while drawing: they push a [`Command`] and the app applies
//! the queue between frames, so every view of a frame sees the same selection.

use super::View;
use crate::catalogue::MethodId;
use crate::experiments::clustering::UnsupervisedLearner;
use crate::experiments::figure_id::FigureId;
use crate::experiments::frontier::{FrontierParams, FrontierPoint};
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
    /// The result whose figure the set came from (index into the results), if any.
    pub result: Option<usize>,
    /// A focused basis of a stability result: (result index, basis).
    pub basis: Option<(usize, usize)>,
    /// A perturbation strength chosen on a robustness chart: (result index, figure, strength).
    pub strength: Option<(usize, FigureId, f64)>,
}

impl Selection {
    pub fn contains(&self, session: usize, grasp: usize) -> bool {
        self.session == Some(session) && self.grasps.contains(&grasp)
    }

    /// Clear the selected set (the focus stays).
    pub fn clear_set(&mut self) {
        self.session = None;
        self.grasps.clear();
        self.origin.clear();
        self.result = None;
    }

    /// Keep the selection to the active session and to the results the views show: a set of
    /// another session, or from a result no longer shown (a new run, another result chosen),
    /// goes, and so do a basis and a strength of a result no longer shown. `shown(i)` says
    /// whether result `i` is the one its view shows for the active session.
    pub fn scope(&mut self, active: usize, shown: impl Fn(usize) -> bool) {
        let other_session = self.session.is_some_and(|s| s != active);
        let other_result = self.result.is_some_and(|i| !shown(i));
        if other_session || other_result {
            self.clear_set();
        }
        if self.basis.is_some_and(|(i, _)| !shown(i)) {
            self.basis = None;
        }
        if self.strength.as_ref().is_some_and(|(i, _, _)| !shown(*i)) {
            self.strength = None;
        }
    }

    /// Sessions close: indices above `closed` shift down, a selection in it goes.
    pub fn session_closed(&mut self, closed: usize) {
        let shift = |s: usize| if s > closed { s - 1 } else { s };
        match self.session {
            Some(s) if s == closed => self.clear_set(),
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
    /// Select these grasps of session `session` (the first is focused), which came from a
    /// figure of result `result`.
    SelectGrasps {
        session: usize,
        grasps: Vec<usize>,
        origin: String,
        result: Option<usize>,
    },
    /// Focus (and replay) one grasp; the selected set stays.
    Focus { session: usize, grasp: usize },
    /// Focus a basis of a stability result.
    FocusBasis { result: usize, basis: usize },
    /// A perturbation strength on a robustness chart.
    Strength {
        result: usize,
        figure: FigureId,
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
    /// "Save model…": model `0` of the Models list to a file the user picks.
    SaveModel(usize),
    /// "Load model…": a model file into the Models list.
    LoadModel,
    /// "Save selection as session…": the selected grasps as a session file.
    SaveSelection,
    /// Plot this signal in the Compare view (a taxel clicked in the replay).
    CompareSignal(crate::compare::Signal),
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
    /// The catalogue's method the spec trains (the Baselines view's k trains k-means and the
    /// SOM together: k-means stands for both).
    pub fn method(&self) -> MethodId {
        match self {
            ModelSpec::Recognition { learner, .. } => learner.method(),
            ModelSpec::Stability(_) => MethodId::SparseSvm,
            ModelSpec::Clustering { learner, .. } => learner.method(),
            ModelSpec::Baselines { k: Some(_) } => MethodId::KMeans,
            ModelSpec::Baselines { k: None } => MethodId::RbfSvm,
        }
    }

    /// The model a frontier's size stands for: what clicking it opens or trains (None for
    /// a method no view trains: the raw SVM, and the registered methods, fitted from the
    /// command line).
    pub fn of_point(params: &FrontierParams, point: &FrontierPoint) -> Option<ModelSpec> {
        let method = params.method;
        Some(match method {
            MethodId::RawSvm | MethodId::Classifier(_) => return None,
            MethodId::Ds | MethodId::Gs => ModelSpec::Recognition {
                learner: SupervisedLearner::of(method)?,
                features: params.features,
                capacity: point.knob("capacity")? as usize,
                tau: point.knob("tau")? as usize,
            },
            MethodId::SparseSvm => ModelSpec::Stability(Config {
                num_bases: point.knob("num_bases")? as usize,
                beta: point.knob("beta")?,
                gamma: point.knob("gamma")?,
            }),
            MethodId::Du | MethodId::Gu => ModelSpec::Clustering {
                learner: UnsupervisedLearner::of(method)?,
                threshold: point.knob("threshold")?,
            },
            MethodId::KMeans | MethodId::Som => ModelSpec::Baselines {
                k: Some(point.knob("k")? as usize),
            },
            MethodId::RbfSvm => ModelSpec::Baselines { k: None },
        })
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    fn selected() -> Selection {
        Selection {
            session: Some(0),
            grasps: vec![3, 5],
            focus: Some((0, 3)),
            origin: "basis 5".into(),
            result: Some(2),
            basis: Some((2, 4)),
            strength: None,
        }
    }

    /// A frontier's size opens the model of its own method, at its own size: the inverse
    /// of [`ModelSpec::method`] (k-means stands for the SOM, which the Baselines view trains
    /// with it).
    #[test]
    fn a_frontier_point_stands_for_its_own_methods_model() {
        use crate::experiments::frontier;
        let knobs = [
            ("capacity", 7.0),
            ("tau", 3.0),
            ("num_bases", 11.0),
            ("beta", 0.5),
            ("gamma", 2.0),
            ("threshold", 0.25),
            ("k", 6.0),
        ];
        let point = FrontierPoint {
            label: String::new(),
            detail: String::new(),
            knobs: knobs.iter().map(|&(n, v)| (n.to_string(), v)).collect(),
            score: 0.5,
            score_se: 0.0,
            reps: 2,
            train_us: 1.0,
            predict_us: 1.0,
        };
        let mut trained = 0;
        for m in frontier::methods() {
            let params = FrontierParams::for_method(m);
            let Some(spec) = ModelSpec::of_point(&params, &point) else {
                assert!(
                    m == MethodId::RawSvm || m.classifier().is_some(),
                    "{m}: no model"
                );
                continue;
            };
            trained += 1;
            let stands_for = if m == MethodId::Som {
                MethodId::KMeans
            } else {
                m
            };
            assert_eq!(spec.method(), stands_for, "{m}");
            // Every knob the spec states ("capacity 7, tau 3") is the point's.
            let text = spec.knobs();
            for stated in text.split(", ") {
                let Some((name, value)) = stated.rsplit_once(' ') else {
                    continue;
                };
                let (Some(name), Ok(value)) = (name.split(' ').next_back(), value.parse()) else {
                    continue;
                };
                assert_eq!(point.knob(name), Some(value), "{m}: {text}");
            }
        }
        assert_eq!(trained, 8);
    }

    #[test]
    fn a_selection_goes_with_its_session_and_its_result() {
        // Same session, its result still shown: it stays.
        let mut s = selected();
        s.scope(0, |i| i == 2);
        assert_eq!(s, selected());
        // Another session active: the set goes, the focus stays for the app to move.
        let mut s = selected();
        s.scope(1, |i| i == 2);
        assert!(s.grasps.is_empty() && s.session.is_none() && s.origin.is_empty());
        assert_eq!(s.focus, Some((0, 3)));
        // A new result shown (a new run learned a new dictionary): the set and the basis go.
        let mut s = selected();
        s.scope(0, |i| i == 7);
        assert!(s.grasps.is_empty() && s.basis.is_none());
    }
}
