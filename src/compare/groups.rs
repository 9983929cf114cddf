//! What grasps are compared by: a label set's classes, objects, clusters, the cells of a
//! confusion map, or whether a result got each grasp right. A grouping names its groups and
//! gives each grasp at most one.

use serde::{Deserialize, Serialize};

use crate::cluster::order_agreement::CHOSEN_THRESHOLD;
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::AnalysisResult;
use crate::figures::FigureKind;
use crate::session::Session;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Groups {
    /// What the groups are, e.g. "object" or "correct vs wrong".
    pub title: String,
    pub names: Vec<String>,
    /// Each grasp's group; None for a grasp in no group (e.g. one a result did not predict).
    pub of: Vec<Option<usize>>,
}

impl Groups {
    /// Every grasp in one group.
    pub fn all(session: &Session) -> Groups {
        Groups {
            title: "all grasps".into(),
            names: vec!["all grasps".into()],
            of: vec![Some(0); session.grasps.len()],
        }
    }

    /// A clustering result's clusters at the threshold it chose without labels (at its
    /// last threshold when it chose none), read from the grasps behind its class × cluster
    /// contingency; None for a result without one. Grasps it did not cluster are in none.
    pub fn by_result_clusters(result: &AnalysisResult, grasps: usize) -> Option<Groups> {
        let figure = FigureId::ScoresVsThreshold;
        let details = result.details.iter().find(|d| d.figure == figure)?;
        let i = match result.score(CHOSEN_THRESHOLD) {
            Some(t) => details.at(t)?,
            None => details.items.len().checked_sub(1)?,
        };
        let (threshold, contingency) = &details.items[i];
        let FigureKind::Heatmap(m) = &contingency.kind else {
            return None;
        };
        let links = (result.links.iter()).find(|l| l.figure == figure && l.detail == Some(i))?;
        let mut of = vec![None; grasps];
        for item in &links.items {
            for &g in &item.grasps {
                if let Some(slot) = of.get_mut(g) {
                    *slot = Some(item.at[1]);
                }
            }
        }
        Some(Groups {
            title: format!("clusters at threshold {threshold}"),
            names: (m.columns.iter()).map(|c| format!("cluster {c}")).collect(),
            of,
        })
    }

    /// The classes of label set `set` (none for an index the session lacks).
    pub fn by_label_set(session: &Session, set: usize) -> Groups {
        let Some(ls) = session.label_sets.get(set) else {
            return Groups {
                title: "label".into(),
                names: Vec::new(),
                of: vec![None; session.grasps.len()],
            };
        };
        Groups {
            title: ls.name.clone(),
            names: ls.classes.clone(),
            of: (session.grasps.iter())
                .map(|g| g.labels.get(set).copied().filter(|&c| c < ls.classes.len()))
                .collect(),
        }
    }

    /// The objects, in first-seen order.
    pub fn by_object(session: &Session) -> Groups {
        let names = session.objects();
        let index: std::collections::HashMap<&str, usize> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect();
        let of = (session.grasps.iter())
            .map(|g| index.get(g.object.as_str()).copied())
            .collect();
        Groups {
            title: "object".into(),
            names,
            of,
        }
    }

    /// Groups given as each grasp's index into `names` (clusters); an index past the
    /// names puts the grasp in no group.
    pub fn assigned(title: &str, names: Vec<String>, of: &[Option<usize>]) -> Groups {
        let n = names.len();
        Groups {
            title: title.into(),
            names,
            of: of.iter().map(|c| c.filter(|&c| c < n)).collect(),
        }
    }

    /// "correct" and "wrong" by each grasp's true and predicted class (a grasp missing
    /// either is in neither).
    pub fn correct_vs_wrong(truth: &[Option<usize>], predicted: &[Option<usize>]) -> Groups {
        Groups {
            title: "correct vs wrong".into(),
            names: vec!["correct".into(), "wrong".into()],
            of: (truth.iter().zip(predicted))
                .map(|(t, p)| Some(if (*t)? == (*p)? { 0 } else { 1 }))
                .collect(),
        }
    }

    /// The non-empty cells of a confusion map of `classes`: "true a → b".
    pub fn confusion_cells(
        classes: &[String],
        truth: &[Option<usize>],
        predicted: &[Option<usize>],
    ) -> Groups {
        let k = classes.len();
        let cell = |t: &Option<usize>, p: &Option<usize>| {
            let (t, p) = ((*t)?, (*p)?);
            (t < k && p < k).then_some(t * k + p)
        };
        let cells: Vec<Option<usize>> = truth
            .iter()
            .zip(predicted)
            .map(|(t, p)| cell(t, p))
            .collect();
        let mut used: Vec<usize> = cells.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        let names = (used.iter())
            .map(|&c| format!("true {} → {}", classes[c / k], classes[c % k]))
            .collect();
        let of = (cells.iter())
            .map(|c| c.and_then(|c| used.binary_search(&c).ok()))
            .collect();
        Groups {
            title: "confusion cell".into(),
            names,
            of,
        }
    }

    /// How many grasps each group holds.
    pub fn sizes(&self) -> Vec<usize> {
        let mut n = vec![0; self.names.len()];
        for g in self.of.iter().flatten() {
            n[*g] += 1;
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::two_sensor_session;

    /// A clustering result's groups are its first order's assignment at the threshold it
    /// chose without labels: every grasp in the group of its own cluster, named by it.
    #[test]
    fn a_clustering_results_clusters_are_its_chosen_thresholds_assignment() {
        use crate::experiments::clustering::report::clustering_report;
        use crate::experiments::clustering::{
            ClusteringParams, UnsupervisedLearner, run_clustering,
        };
        let s = crate::session::simulate::object_recognition(0);
        let params = ClusteringParams {
            reps: 2,
            seed: 1,
            thresholds: vec![0.02, 0.05, 0.1, 0.2],
            choose_threshold: Some(
                crate::cluster::order_agreement::ThresholdCriterion::OrderAgreement,
            ),
            ..ClusteringParams::for_learner(UnsupervisedLearner::Du)
        };
        let r = run_clustering(&s, &params, &crate::jobs::Progress::new()).unwrap();
        let chosen = r.threshold_choice.as_ref().expect("a label-free choice");
        let run = (r.runs.iter())
            .find(|x| x.rep == 0 && x.threshold == chosen.threshold)
            .unwrap();
        let assignment = run.assignment.as_ref().unwrap();
        let g = Groups::by_result_clusters(&clustering_report("s", &r), s.grasps.len()).unwrap();
        assert!(
            g.title.contains(&chosen.threshold.to_string()),
            "{}",
            g.title
        );
        for (k, a) in assignment.iter().enumerate() {
            let name = &g.names[g.of[k].expect("every grasp clustered")];
            assert_eq!(name, &format!("cluster {}", a + 1), "grasp {k}");
        }
        let distinct: std::collections::BTreeSet<_> = assignment.iter().collect();
        assert_eq!(g.names.len(), distinct.len());
    }

    #[test]
    fn labels_and_objects_give_each_grasp_its_group() {
        let s = two_sensor_session();
        let g = Groups::by_label_set(&s, 0);
        assert_eq!(g.names, ["success", "failure"]);
        assert_eq!(g.of, [Some(0), Some(1), Some(1)]);
        assert_eq!(g.sizes(), [1, 2]);
        let o = Groups::by_object(&s);
        assert_eq!(o.names, ["mug", "ball"]);
        assert_eq!(o.of, [Some(0), Some(1), Some(0)]);
        assert!(Groups::by_label_set(&s, 4).of.iter().all(Option::is_none));
    }

    #[test]
    fn correct_wrong_and_cells_follow_truth_and_prediction() {
        let truth = [Some(0), Some(1), Some(1), None, Some(2)];
        let pred = [Some(0), Some(0), Some(1), Some(1), Some(2)];
        let cw = Groups::correct_vs_wrong(&truth, &pred);
        assert_eq!(cw.of, [Some(0), Some(1), Some(0), None, Some(0)]);
        let classes = ["a".to_string(), "b".into(), "c".into()];
        let cells = Groups::confusion_cells(&classes, &truth, &pred);
        // Cells used: a→a (0), b→a (3), b→b (4), c→c (8), in that order.
        assert_eq!(
            cells.names,
            ["true a → a", "true b → a", "true b → b", "true c → c"]
        );
        assert_eq!(cells.of, [Some(0), Some(1), Some(2), None, Some(3)]);
        let clusters = Groups::assigned("cluster", vec!["1".into()], &[Some(0), Some(3), None]);
        assert_eq!(clusters.of, [Some(0), None, None]);
    }
}
