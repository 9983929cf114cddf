//! GU: the generative unsupervised learner (paper Sec. IV-B2): GS experts as clusters, a new
//! cluster when the extreme-value novelty nu_G = 1 − G_e(N(o|μ, Σ)) (eqs. 31–33) of the
//! winning expert exceeds theta_U.
//!
//! Where the paper is silent (notes Sec. 7): Σ = diag(predictive variance incl. noise) and
//! m = the number of training points the winning expert has seen, as the reference code's
//! `OnlineLocalMemOGP`; the winner is the GS decision (argmax of the final posterior); the
//! per-step novelties are combined over the grasp by [`GuAggregate`] (the mean, as DU
//! averages its per-step scores, or the maximum: a grasp is novel where any step is).

use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

use super::du::Assignment;
use super::evt::evt_novelty;
use super::{Gs, GsParams, LearnerError, SequenceClassifier, argmax_of_last};

/// How the per-step novelties of a grasp become one score.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GuAggregate {
    Mean,
    Max,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GuParams {
    pub gs: GsParams,
    /// theta_U in [0, 1]: the lower, the more clusters.
    pub threshold: f64,
    pub aggregate: GuAggregate,
}

impl Default for GuParams {
    fn default() -> Self {
        GuParams {
            gs: GsParams::default(),
            threshold: 0.3,
            aggregate: GuAggregate::Mean,
        }
    }
}

impl GuParams {
    pub fn validate(&self) -> Result<(), LearnerError> {
        if !(0.0..=1.0).contains(&self.threshold) {
            return Err(LearnerError::param("threshold", "must lie in [0, 1]"));
        }
        self.gs.validate()
    }
}

#[derive(Clone, Debug)]
pub struct Gu {
    gs: Gs,
    threshold: f64,
    aggregate: GuAggregate,
    residual: Vec<f64>,
    variance: Vec<f64>,
}

impl Gu {
    pub fn new(dim: usize, params: &GuParams) -> Result<Gu, LearnerError> {
        params.validate()?;
        Ok(Gu {
            gs: Gs::new(dim, &params.gs)?,
            threshold: params.threshold,
            aggregate: params.aggregate,
            residual: vec![0.0; dim],
            variance: vec![0.0; dim],
        })
    }

    pub fn n_clusters(&self) -> usize {
        self.gs.n_classes()
    }

    pub fn learner(&self) -> &Gs {
        &self.gs
    }

    /// nu_G of a grasp under expert `c`, combined over the steps.
    pub fn novelty(&mut self, c: usize, seq: ArrayView2<f64>) -> f64 {
        let m = self.gs.models()[c].seen();
        let (means, vars) = self.gs.expert_predictions(c, seq);
        if vars.is_empty() {
            return 1.0;
        }
        let (mut sum, mut max) = (0.0, 0.0f64);
        for ((o, mu), v) in seq.rows().into_iter().zip(means.rows()).zip(&vars) {
            for ((r, x), y) in self.residual.iter_mut().zip(o).zip(mu) {
                *r = x - y;
            }
            self.variance.fill(*v);
            let nu = evt_novelty(&self.residual, &self.variance, m);
            sum += nu;
            max = max.max(nu);
        }
        match self.aggregate {
            GuAggregate::Mean => sum / vars.len() as f64,
            GuAggregate::Max => max,
        }
    }

    /// Assign one grasp (opening a cluster if it is novel) and train on it.
    pub fn learn(&mut self, seq: ArrayView2<f64>) -> Result<Assignment, LearnerError> {
        if self.gs.n_classes() == 0 {
            let c = self.gs.add_class()?;
            self.gs.train_sequence(seq, c);
            return Ok(Assignment {
                cluster: c,
                novelty: 1.0,
                created: true,
            });
        }
        let p = self.gs.predict_sequence(seq);
        let s = argmax_of_last(p.view());
        let novelty = self.novelty(s, seq);
        let (cluster, created) = if novelty > self.threshold {
            (self.gs.add_class()?, true)
        } else {
            (s, false)
        };
        self.gs.train_sequence(seq, cluster);
        Ok(Assignment {
            cluster,
            novelty,
            created,
        })
    }

    /// The cluster of a grasp under the learned models (no training).
    pub fn assign(&mut self, seq: ArrayView2<f64>) -> usize {
        let p = self.gs.predict_sequence(seq);
        argmax_of_last(p.view())
    }
}
