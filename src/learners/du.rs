//! DU: the discriminative unsupervised learner (paper Sec. IV-A2): DS experts as clusters,
//! a new cluster when the novelty nu_D = 1 − (1/T) Σ_t max(0, 2 q_t(c_s|o) − 1) (eq. 28)
//! exceeds the threshold theta_D.
//!
//! Where the paper is silent: the winner s is fixed per grasp (the DS decision, argmax of
//! the mean p over the grasp), and a grasp is trained into its cluster with DS's rule (the
//! most probable other cluster gets the negatives), also when it opens a new cluster.
//! As GU's ([`super::GuParams::min_grasps`]), the final re-assignment can leave out the
//! clusters trained on fewer than [`DuParams::min_grasps`] grasps (default 1: keep all, as
//! the paper's DU).

use ndarray::{Array2, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use super::ds::p_of_q;
use super::novelty::{Assignment, NoveltyLearner, NoveltySteps};
use super::{Ds, DsParams, LearnerError, SequenceClassifier, argmax, argmax_of_mean};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DuParams {
    pub ds: DsParams,
    /// theta_D in [0, 1]: the lower, the more clusters.
    pub threshold: f64,
    /// Clusters trained on fewer grasps take no part in the final re-assignment.
    #[serde(default = "every_cluster")]
    pub min_grasps: usize,
}

fn every_cluster() -> usize {
    1
}

impl Default for DuParams {
    fn default() -> Self {
        DuParams {
            ds: DsParams::default(),
            threshold: 0.3,
            min_grasps: every_cluster(),
        }
    }
}

impl DuParams {
    pub fn validate(&self) -> Result<(), LearnerError> {
        if !(0.0..=1.0).contains(&self.threshold) {
            return Err(LearnerError::param("threshold", "must lie in [0, 1]"));
        }
        if self.min_grasps == 0 {
            return Err(LearnerError::param("min_grasps", "must be at least 1"));
        }
        self.ds.validate()
    }
}

/// Saved with serde as its DS learner, its own parameters and the grasps of each cluster;
/// loading (deserialising) checks them against each other (see [`super`]). A loaded DU
/// goes on learning: a novel grasp opens a new cluster.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "DuState")]
pub struct Du {
    ds: Ds,
    threshold: f64,
    min_grasps: usize,
    /// Grasps trained into each cluster.
    #[serde(rename = "grasps_per_cluster")]
    grasps: Vec<usize>,
}

/// A [`Du`] as it is saved: the fields of [`Du`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DuState {
    ds: Ds,
    threshold: f64,
    min_grasps: usize,
    grasps_per_cluster: Vec<usize>,
}

impl TryFrom<DuState> for Du {
    type Error = LearnerError;

    fn try_from(s: DuState) -> Result<Du, LearnerError> {
        let du = Du {
            ds: s.ds,
            threshold: s.threshold,
            min_grasps: s.min_grasps,
            grasps: s.grasps_per_cluster,
        };
        du.params().validate()?;
        super::check_per_class("grasps_per_cluster", du.grasps.len(), du.n_clusters())?;
        // Every cluster was opened by a grasp trained into it.
        if let Some(c) = du.grasps.iter().position(|g| *g == 0) {
            return Err(LearnerError::state(
                format!("grasps_per_cluster[{c}]"),
                "a cluster without grasps",
            ));
        }
        Ok(du)
    }
}

/// nu_D of eq. 28 from the q of cluster s at every step.
pub fn du_novelty(q: impl ExactSizeIterator<Item = f64>) -> f64 {
    let t = q.len();
    if t == 0 {
        return 1.0;
    }
    1.0 - q.map(|q| (2.0 * q - 1.0).max(0.0)).sum::<f64>() / t as f64
}

impl Du {
    pub fn new(dim: usize, params: &DuParams) -> Result<Du, LearnerError> {
        params.validate()?;
        Ok(Du {
            ds: Ds::new(dim, &params.ds)?,
            threshold: params.threshold,
            min_grasps: params.min_grasps,
            grasps: Vec::new(),
        })
    }

    pub fn n_clusters(&self) -> usize {
        self.ds.n_classes()
    }

    /// Read the experts' distances from a pair table of the inputs ([`Ds::use_pairs`]).
    pub fn use_pairs(&mut self, pairs: std::sync::Arc<crate::gp::PairDistances>) {
        self.ds.use_pairs(pairs);
    }

    pub fn learner(&self) -> &Ds {
        &self.ds
    }

    /// The parameters the learner was built with.
    pub fn params(&self) -> DuParams {
        DuParams {
            ds: self.ds.params().clone(),
            threshold: self.threshold,
            min_grasps: self.min_grasps,
        }
    }

    /// The grasps trained into each cluster.
    pub fn grasps_per_cluster(&self) -> &[usize] {
        &self.grasps
    }

    /// The cluster of a grasp under the learned models (no training): the DS decision
    /// among the clusters trained on at least `min_grasps` grasps (all if none is), with
    /// p renormalised over them.
    pub fn assign(&mut self, seq: ArrayView2<f64>) -> usize {
        self.assign_all(&[seq])[0]
    }

    /// [`Du::assign`] of each of `seqs`, every expert scoring all of them in turn.
    pub fn assign_all(&mut self, seqs: &[ArrayView2<f64>]) -> Vec<usize> {
        let confirmed: Vec<usize> = (0..self.grasps.len())
            .filter(|&c| self.grasps[c] >= self.min_grasps)
            .collect();
        let every = confirmed.len() == self.grasps.len() || confirmed.is_empty();
        let qs = self.ds.predict_q_many(seqs);
        qs.iter()
            .map(|q| match every {
                true => argmax_of_mean(p_of_q(q.view()).view()),
                false => confirmed_decision(q.view(), &confirmed),
            })
            .collect()
    }
}

/// A grasp assessed by DU: every cluster's q at each step (T × C), the DS winner and its
/// nu_D.
#[derive(Clone, Debug)]
pub struct DuAssessment {
    q: Array2<f64>,
    winner: usize,
    novelty: f64,
}

impl NoveltyLearner for Du {
    type Assessment = DuAssessment;
    type Steps = DuSteps;

    fn threshold(&self) -> f64 {
        self.threshold
    }

    fn n_clusters(&self) -> usize {
        Du::n_clusters(self)
    }

    fn assess(&mut self, seq: ArrayView2<f64>) -> Option<DuAssessment> {
        if self.ds.n_classes() == 0 {
            return None;
        }
        let (q, p) = self.ds.predict_q_and_p(seq);
        let winner = argmax_of_mean(p.view());
        let novelty = du_novelty(q.column(winner).iter().copied());
        Some(DuAssessment { q, winner, novelty })
    }

    fn novelty(a: &DuAssessment) -> f64 {
        a.novelty
    }

    fn commit(
        &mut self,
        seq: ArrayView2<f64>,
        a: Option<DuAssessment>,
        create: bool,
    ) -> Result<Assignment, LearnerError> {
        let Some(a) = a else {
            let c = self.ds.add_class()?;
            self.ds.train_sequence(seq, c);
            self.grasps.push(1);
            return Ok(Assignment {
                cluster: c,
                novelty: 1.0,
                created: true,
            });
        };
        let cluster = if create {
            self.grasps.push(0);
            self.ds.add_class()?
        } else {
            a.winner
        };
        self.grasps[cluster] += 1;
        self.ds.train_sequence_predicted(seq, cluster, a.q.view());
        Ok(Assignment {
            cluster,
            novelty: a.novelty,
            created: create,
        })
    }

    fn assign_all(&mut self, seqs: &[ArrayView2<f64>]) -> Vec<usize> {
        Du::assign_all(self, seqs)
    }

    fn steps(&self) -> Option<DuSteps> {
        let c = self.ds.n_classes();
        if c == 0 {
            return None;
        }
        let mut ds = self.ds.clone();
        ds.start_sequence();
        Some(DuSteps {
            ds,
            p_sums: vec![0.0; c],
            q_sums: vec![0.0; c],
            dist: vec![0.0; c],
            winner: 0,
            t: 0,
        })
    }
}

/// DU following a grasp step by step ([`NoveltyLearner::steps`]): DS's q is causal (a
/// step's q depends on the steps up to it), so each step is one `predict_step` of every
/// expert, and the prefix is two running sums per cluster, added in step order as
/// [`Du`]'s assessment adds them: Σ p (its winner is the argmax of the mean p) and
/// Σ max(0, 2q − 1) (eq. 28's sum).
#[derive(Clone, Debug)]
pub struct DuSteps {
    /// A copy of the learner's experts, observing the grasp.
    ds: Ds,
    p_sums: Vec<f64>,
    q_sums: Vec<f64>,
    /// The step's p (scratch).
    dist: Vec<f64>,
    winner: usize,
    t: usize,
}

impl NoveltySteps for DuSteps {
    fn dim(&self) -> usize {
        self.ds.dim()
    }

    fn push(&mut self, o: &[f64]) -> usize {
        assert_eq!(o.len(), self.ds.dim(), "a step of the learner's width");
        self.ds.predict_step(o, &mut self.dist);
        for ((s, p), (h, q)) in self
            .p_sums
            .iter_mut()
            .zip(&self.dist)
            .zip(self.q_sums.iter_mut().zip(self.ds.q()))
        {
            *s += p;
            *h += (2.0 * q - 1.0).max(0.0);
        }
        self.t += 1;
        self.winner = argmax(self.p_sums.iter().copied());
        self.winner
    }

    fn novelty(&mut self) -> f64 {
        if self.t == 0 {
            return 1.0;
        }
        1.0 - self.q_sums[self.winner] / self.t as f64
    }

    fn winner(&self) -> usize {
        self.winner
    }

    fn len(&self) -> usize {
        self.t
    }
}

/// The DS decision among the `confirmed` clusters from every cluster's q at each step: each
/// step's q renormalised over them (uniform where all of them are 0), then the argmax of
/// the mean.
fn confirmed_decision(q: ArrayView2<f64>, confirmed: &[usize]) -> usize {
    let mut p = q.select(Axis(1), confirmed);
    for mut row in p.rows_mut() {
        let sum = row.sum();
        if sum > 0.0 {
            row /= sum;
        } else {
            row.fill(1.0 / confirmed.len() as f64);
        }
    }
    confirmed[argmax_of_mean(p.view())]
}

#[cfg(test)]
mod tests {
    use ndarray::array;

    use super::super::testing::{grasps, load_error, probes, quick_adaptation, round_trip};
    use super::*;
    use crate::gp::SogpParams;

    fn small(adapting: bool) -> DuParams {
        DuParams {
            ds: DsParams {
                gp: SogpParams {
                    capacity: 10,
                    tau: 4,
                    adaptation: adapting.then(quick_adaptation),
                    ..DsParams::default().gp
                },
            },
            threshold: 0.3,
            min_grasps: 2,
        }
    }

    /// DU that clustered grasps of three objects, saved and loaded, goes on learning as
    /// the saved one: grasps of two more objects open new clusters in both, every
    /// assignment (cluster, novelty, creation) and re-assignment is the same, bit for bit,
    /// and both end in the same state.
    #[test]
    fn a_loaded_du_goes_on_as_the_saved_one_bit_for_bit() {
        for adapting in [true, false] {
            let mut a = Du::new(3, &small(adapting)).unwrap();
            for (_, g) in &grasps(1, 30, 3, 3) {
                a.learn(g.view()).unwrap();
            }
            let before = a.n_clusters();
            if adapting {
                let m = a.learner().models();
                assert!(m.iter().any(|m| m.hyper_updates() >= 5));
            }
            let mut b = round_trip(&a);
            assert_eq!(
                (b.params(), b.grasps_per_cluster()),
                (a.params(), a.grasps_per_cluster())
            );
            let s2 = grasps(2, 30, 5, 3);
            for (i, (_, g)) in s2.iter().enumerate() {
                let (la, lb) = (a.learn(g.view()).unwrap(), b.learn(g.view()).unwrap());
                assert_eq!(
                    (la.cluster, la.created),
                    (lb.cluster, lb.created),
                    "grasp {i}"
                );
                assert_eq!(la.novelty.to_bits(), lb.novelty.to_bits(), "grasp {i}");
            }
            assert!(
                a.n_clusters() > before,
                "{before} clusters before, {} after",
                a.n_clusters()
            );
            for (i, (_, g)) in s2.iter().enumerate() {
                assert_eq!(a.assign(g.view()), b.assign(g.view()), "grasp {i}");
            }
            let (ja, jb) = (serde_json::to_string(&a), serde_json::to_string(&b));
            assert_eq!(ja.unwrap(), jb.unwrap());
        }
    }

    /// Followed step by step, every prefix of a grasp gets the winner and the novelty that
    /// assessing that prefix gives, bit for bit (so the last step is the whole grasp's),
    /// with the experts' own distance tables (adapting) and the shared one (not), at a
    /// threshold low enough for many clusters; the learner is left as it was. Among the probes, some prefix's winner is not the
    /// grasp's: the running sums are kept for every cluster.
    #[test]
    fn du_steps_equal_the_assessment_of_every_prefix_bit_for_bit() {
        for (adapting, threshold) in [(true, 0.1), (false, 0.1)] {
            let p = DuParams {
                threshold,
                ..small(adapting)
            };
            let mut du = Du::new(3, &p).unwrap();
            for (_, g) in &grasps(1, 30, 3, 3) {
                du.learn(g.view()).unwrap();
            }
            assert!(du.n_clusters() >= 2, "{}", du.n_clusters());
            let mut winner_changed = false;
            for (i, g) in probes().iter().enumerate() {
                let before = serde_json::to_string(&du).unwrap();
                let steps = du.assess_steps(g.view());
                assert_eq!(serde_json::to_string(&du).unwrap(), before);
                assert_eq!(steps.len(), g.nrows());
                for (t, &(winner, novelty)) in steps.iter().enumerate() {
                    let a = du.assess(g.slice(ndarray::s![..t + 1, ..])).unwrap();
                    assert_eq!(
                        (winner, novelty.to_bits()),
                        (a.winner, a.novelty.to_bits()),
                        "adapting {adapting}, grasp {i}, step {t}: {novelty} vs {}",
                        a.novelty
                    );
                }
                winner_changed |= steps.iter().any(|s| s.0 != steps.last().unwrap().0);
            }
            assert!(winner_changed, "adapting {adapting}");
        }
    }

    /// A damaged state is an error naming what is wrong, and nothing panics (learning into
    /// a cluster without its count would index past the counts).
    #[test]
    fn a_damaged_du_state_is_an_error_naming_the_field() {
        let mut du = Du::new(3, &small(false)).unwrap();
        for (_, g) in &grasps(2, 30, 5, 3) {
            du.learn(g.view()).unwrap();
        }
        assert!(du.n_clusters() >= 2);
        load_error(&du, "grasps_per_cluster", |v| {
            v["grasps_per_cluster"].as_array_mut().unwrap().pop();
        });
        load_error(&du, "grasps_per_cluster[0]", |v| {
            v["grasps_per_cluster"][0] = 0.into()
        });
        load_error(&du, "threshold", |v| v["threshold"] = 1.5.into());
        load_error(&du, "min_grasps", |v| v["min_grasps"] = 0.into());
        load_error(&du, "models[1]: invalid state `q`", |v| {
            v["ds"]["models"][1]["q"] = serde_json::json!([0.5, 0.5])
        });
        // A negative count is not a count (serde says where).
        let mut v = serde_json::to_value(&du).unwrap();
        v["grasps_per_cluster"][1] = (-1).into();
        let e = serde_json::from_value::<Du>(v).unwrap_err().to_string();
        assert!(e.contains("-1"), "{e}");
    }

    /// Worked by hand: clusters 0 and 1 are confirmed, 2 is not. Renormalised over 0 and 1
    /// the steps' q are (0.1, 0.9), (0.6, 0.4) and, where both are 0, (0.5, 0.5): means
    /// 0.4 and 0.6, so cluster 1. The raw q (means 0.203 and 0.163), or q weighted by its
    /// sum over the confirmed clusters, would give cluster 0, and so would a uniform p
    /// everywhere (a tie goes to the first).
    #[test]
    fn each_step_is_renormalised_over_the_confirmed_clusters() {
        let q = array![[0.01, 0.09, 0.9], [0.6, 0.4, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(confirmed_decision(q.view(), &[0, 1]), 1);
    }
}
