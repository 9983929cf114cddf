//! A saved model at work on the grasps of a stream. Each completed grasp, as the session of
//! one grasp that the recording also holds, goes through the models' own prediction (the
//! path of `predict` and `evaluate`) under calibration `none`: a live grasp has no session
//! to calibrate on, and with `none` every grasp is read on the model's own scale, so the
//! verdicts equal `evaluate --calibration none` on the recorded session bit for bit.
//!
//! Teaching: a labelled grasp teaches DS/GS (or DU/GU learn it) exactly as
//! `fit --from MODEL` on that one grasp's session would, and the model file is then saved
//! atomically, so a stream teaches as a chain of `fit --from` runs does.

use std::path::{Path, PathBuf};

use crate::catalogue::MethodId;
use crate::models::{
    self, Calibration, Model, ModelError, ModelFile, cluster_file, continue_clusters,
    continue_sequences, sequence_file,
};
use crate::session::Session;

/// What the model says about one grasp.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub method: MethodId,
    /// The decided class (recognition, stability) or cluster (clustering).
    pub predicted: String,
    /// DS/GS: the decided class's probability at the last step; stability: the SVM's
    /// decision value at the key frame (positive for failure); clustering: none (NaN).
    pub decision: f64,
    /// DS/GS: the model's classes and the class distribution after each step from onset.
    pub classes: Vec<String>,
    pub steps: Vec<Vec<f64>>,
    /// DS/GS: the step from which the running decision stays the final one.
    pub settled: Option<usize>,
}

impl Verdict {
    /// One line for the CLI: the decision, and when it settled.
    pub fn line(&self) -> String {
        let mut out = format!("{} → {}", self.method.key(), self.predicted);
        if self.decision.is_finite() {
            out += &format!(" ({:.3})", self.decision);
        }
        if let Some(s) = self.settled {
            out += &format!(", settled at step {} of {}", s + 1, self.steps.len());
        }
        out
    }
}

pub struct LiveModel {
    path: PathBuf,
    pub file: ModelFile,
    teach: bool,
    /// Grasps taught since the model was loaded.
    pub taught: usize,
}

impl LiveModel {
    /// The model file at `path`; with `teach`, labelled grasps teach it and it is saved.
    pub fn load(path: &Path, teach: bool) -> Result<LiveModel, ModelError> {
        Ok(LiveModel {
            path: path.to_path_buf(),
            file: models::load(path)?,
            teach,
            taught: 0,
        })
    }

    pub fn verdict(&self, one: &Session) -> Result<Verdict, ModelError> {
        let method = self.file.provenance.method;
        let row = models::predict(&self.file, one, Calibration::None)?
            .into_iter()
            .next()
            .ok_or_else(|| ModelError::Mismatch("the grasp gave no prediction".into()))?;
        let mut verdict = Verdict {
            method,
            predicted: row.predicted,
            decision: row.decision,
            classes: Vec::new(),
            steps: Vec::new(),
            settled: None,
        };
        if let Model::Sequences(m) = &self.file.model
            && let Some(p) = m.predict(one, Calibration::None)?.into_iter().next()
        {
            verdict.classes = m.classes.clone();
            verdict.steps = p
                .distributions
                .rows()
                .into_iter()
                .map(|r| r.to_vec())
                .collect();
            verdict.settled = settled(&verdict.steps, p.class, method == MethodId::Ds);
        }
        Ok(verdict)
    }

    /// Teach the grasp (labelled) and save the model atomically; false when the model is
    /// not taught (teaching off, or a stability or baseline model).
    pub fn teach(&mut self, one: &Session) -> Result<bool, ModelError> {
        if !self.teach {
            return Ok(false);
        }
        let previous = &self.file.provenance;
        let next = match &self.file.model {
            Model::Sequences(m) => {
                let (next, secs) = continue_sequences(m, one)?;
                sequence_file(next, one, secs, previous.size_reason, Some(previous))
            }
            Model::Clusters(m) => {
                let (next, secs) = continue_clusters(m, one)?;
                cluster_file(next, one, secs, Some(previous))
            }
            _ => return Ok(false),
        };
        models::save(&next, &self.path)?;
        self.file = next;
        self.taught += 1;
        Ok(true)
    }
}

/// The first step from which the running decision (DS: the argmax of the mean so far; GS:
/// the argmax of the step's distribution) is `class` at every later step.
fn settled(steps: &[Vec<f64>], class: usize, mean: bool) -> Option<usize> {
    let mut sums = vec![0.0; steps.first()?.len()];
    let mut from = None;
    for (k, row) in steps.iter().enumerate() {
        for (s, v) in sums.iter_mut().zip(row) {
            *s += v;
        }
        let basis = if mean { &sums } else { row };
        let best = basis
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (i, &v)| if v > b.1 { (i, v) } else { b },
            )
            .0;
        match (best == class, from) {
            (true, None) => from = Some(k),
            (false, _) => from = None,
            _ => {}
        }
    }
    from
}
