//! A saved model at work on the grasps of a stream. Each completed grasp, as the session of
//! one grasp that the recording also holds, goes through the models' own prediction (the
//! path of `predict` and `evaluate`) under calibration `none`: a live grasp has no session
//! to calibrate on, and with `none` every grasp is read on the model's own scale, so the
//! verdicts equal `evaluate --calibration none` on the recorded session bit for bit.
//!
//! While a grasp is still open, [`Early`] gives DS/GS's class distribution one step at a
//! time from its first frame (the paper's early classification): each new frame's feature
//! row through a copy of the saved experts' `predict_step`. For DU/GU it gives the winner
//! cluster and the novelty of the grasp so far, through the learner's
//! [`NoveltySteps`](crate::learners::NoveltySteps) (equal bit for bit to assessing the
//! prefix, at O(clusters) per step).
//!
//! Teaching: a labelled grasp teaches DS/GS (or DU/GU learn it) exactly as
//! `fit --from MODEL` on that one grasp's session would, and the model file is then saved
//! atomically, so a stream teaches as a chain of `fit --from` runs does
//! ([`teach_in_order`], what `fit --from --in-order` runs).

use std::path::{Path, PathBuf};

use ndarray::ArrayView2;

use crate::catalogue::MethodId;
use crate::error::Kept;
use crate::features::feature_sequences_in;
use crate::features::sequence::{FeatureSequences, SequenceParams, SequenceRange};
use crate::figures::{Axis, Figure, FigureKind, Orientation, RefLine, Series};
use crate::learners::du::DuSteps;
use crate::learners::gu::GuSteps;
use crate::learners::{NoveltyLearner, NoveltySteps, SequenceClassifier, novelty_due};
use crate::models::clustering::{Clusterer, cluster_name};
use crate::models::inputs::SequenceInputs;
use crate::models::recognition::Experts;
use crate::models::{
    self, Calibration, Model, ModelError, ModelFile, cluster_file, continue_clusters,
    continue_sequences, sequence_file,
};
use crate::session::spec::{ImportSpec, RawGrasp};
use crate::session::{Frame, Session};

/// Steps of an open grasp the early view keeps (its decision reads them all).
pub const EARLY_CAP: usize = 20_000;

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
    /// DU/GU: the grasp's novelty against the clusters learned so far, and the threshold
    /// above which learning it would open a new cluster.
    pub novelty: Option<(f64, f64)>,
    /// DU/GU: the winner and the novelty of the grasp so far, step by step (every step; GU's
    /// joint novelty at the steps of [`novelty_due`] and the last, see
    /// [`NoveltySteps::novelty_costly`]).
    pub novelty_steps: Vec<NoveltyStep>,
}

/// DU/GU's assessment of a grasp's first `step` + 1 steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoveltyStep {
    /// From 0.
    pub step: usize,
    pub cluster: usize,
    pub novelty: f64,
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
        if let Some((n, threshold)) = self.novelty {
            out += &format!(", novelty {n:.3} (threshold {threshold:.3})");
        }
        out
    }

    /// The early decisions: the running decision after 10 %, 20 %, … 100 % of the steps.
    pub fn early_line(&self) -> Option<String> {
        if self.steps.is_empty() {
            return self.novelty_line();
        }
        let n = self.steps.len();
        let mean = self.method == MethodId::Ds;
        let words: Vec<String> = (1..=10)
            .map(|k| {
                let upto = (n * k).div_ceil(10).max(1);
                let best = running_best(&self.steps[..upto], mean);
                format!(
                    "{}%:{}",
                    k * 10,
                    self.classes.get(best).map_or("?", String::as_str)
                )
            })
            .collect();
        Some(format!("early {}", words.join(" ")))
    }
}

impl Verdict {
    /// DU/GU: the cluster and the novelty of the grasp so far after 10 %, 20 %, … 100 % of
    /// its steps (the latest assessed at or before each).
    fn novelty_line(&self) -> Option<String> {
        let last = self.novelty_steps.last()?;
        let n = last.step + 1;
        let words: Vec<String> = (1..=10)
            .filter_map(|k| {
                let upto = (n * k).div_ceil(10).max(1);
                let i = self.novelty_steps.partition_point(|s| s.step < upto);
                let s = self.novelty_steps.get(i.checked_sub(1)?)?;
                Some(format!(
                    "{}%:{}@{:.3}",
                    k * 10,
                    cluster_name(s.cluster).replace(' ', ""),
                    s.novelty
                ))
            })
            .collect();
        Some(format!("novelty by step {}", words.join(" ")))
    }

    /// DU/GU: the novelty of the grasp so far at every step assessed, against the threshold
    /// (a reference line), as a chart of the figure model. None without steps.
    pub fn novelty_figure(&self) -> Option<Figure> {
        let last = self.novelty_steps.last()?;
        let shown: Vec<&NoveltyStep> = (chart_steps(self.novelty_steps.len()).into_iter())
            .map(|i| &self.novelty_steps[i])
            .collect();
        let x = shown.iter().map(|s| (s.step + 1) as f64).collect();
        let y = shown.iter().map(|s| s.novelty).collect();
        let mut figure = Figure::chart(
            format!(
                "{} novelty of the grasp so far, step by step",
                self.method.key()
            ),
            Axis::new("step", "").including(1.0, (last.step + 1).max(2) as f64),
            Axis::new("novelty", "").including(0.0, 1.0),
            vec![Series::new("novelty", x, y)],
        );
        if let (Some((_, threshold)), FigureKind::Chart(c)) = (self.novelty, &mut figure.kind) {
            c.ref_lines.push(RefLine {
                orientation: Orientation::Horizontal,
                value: threshold,
                label: "threshold".into(),
            });
        }
        Some(figure)
    }
}

/// Steps a chart of the distribution draws at most: a long grasp is thinned evenly (its
/// last step always kept), since a tile has fewer pixels than a 1 kHz grasp has steps.
pub const CHART_STEPS: usize = 600;

/// The steps of `n` (at least one) a chart draws: every k-th, at most [`CHART_STEPS`], and
/// the last.
fn chart_steps(n: usize) -> Vec<usize> {
    let every = n.div_ceil(CHART_STEPS).max(1);
    (0..n)
        .step_by(every)
        .chain((!(n - 1).is_multiple_of(every)).then_some(n - 1))
        .collect()
}

impl Verdict {
    /// The `top` classes' probability at every step (the classes most probable at the
    /// latest step): how the decision formed, as a chart of the figure model, with the
    /// step it settled at marked. None without steps (not DS/GS, or no step yet).
    pub fn figure(&self, top: usize) -> Option<Figure> {
        let Some(last) = self.steps.last() else {
            return self.novelty_figure();
        };
        let mut order: Vec<usize> = (0..last.len()).collect();
        order.sort_by(|&a, &b| last[b].total_cmp(&last[a]));
        let n = self.steps.len();
        let shown = chart_steps(n);
        let series = order
            .into_iter()
            .take(top)
            .map(|k| {
                let name = self
                    .classes
                    .get(k)
                    .cloned()
                    .unwrap_or_else(|| k.to_string());
                let x = shown.iter().map(|&i| (i + 1) as f64).collect();
                let y = shown
                    .iter()
                    .map(|&i| self.steps[i].get(k).copied().unwrap_or(f64::NAN))
                    .collect();
                Series::new(name, x, y)
            })
            .collect();
        let mut figure = Figure::chart(
            format!("{} class distribution, step by step", self.method.key()),
            Axis::new("step", "").including(1.0, n.max(2) as f64),
            Axis::new("probability", "").including(0.0, 1.0),
            series,
        );
        if let (Some(s), FigureKind::Chart(c)) = (self.settled, &mut figure.kind) {
            c.ref_lines.push(RefLine {
                orientation: Orientation::Vertical,
                value: (s + 1) as f64,
                label: "settled".into(),
            });
        }
        Some(figure)
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
            novelty: None,
            novelty_steps: Vec::new(),
        };
        if let Model::Clusters(m) = &self.file.model
            && let Some(seq) = features(&m.inputs, one)?.sequences.first()
        {
            let mut c = m.clusterer.clone();
            let novelty = match &mut c {
                Clusterer::Du(l) => assess(l, seq.view()),
                Clusterer::Gu(l) => assess(l, seq.view()),
            };
            verdict.novelty = novelty.map(|n| (n, m.threshold));
            if let Some(mut f) = Follower::of_clusters(&m.clusterer) {
                for row in seq.rows() {
                    let row = row.to_vec();
                    if let Some(s) = f.cluster_step(&row, false)? {
                        verdict.novelty_steps.push(s);
                    }
                }
                // The last step always (GU's joint novelty may skip the steps before).
                if let Some(s) = f.cluster_step_last()
                    && verdict
                        .novelty_steps
                        .last()
                        .is_none_or(|l| l.step != s.step)
                {
                    verdict.novelty_steps.push(s);
                }
            }
        }
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
        let Some(next) = taught(&self.file, one)? else {
            return Ok(false);
        };
        models::save(&next, &self.path)?;
        self.file = next;
        self.taught += 1;
        Ok(true)
    }

    /// The early classification of a grasp that starts now (DS/GS), or its cluster and
    /// novelty step by step (DU/GU); None for a model that has none (stability, baselines)
    /// or a DU/GU that has no cluster yet.
    pub fn early(&self) -> Option<Early> {
        let (follower, inputs, classes, threshold) = match &self.file.model {
            Model::Sequences(m) => {
                let mut experts = m.experts.clone();
                learner(&mut experts).start_sequence();
                (
                    Follower::Classes(Box::new(experts)),
                    &m.inputs,
                    m.classes.clone(),
                    None,
                )
            }
            Model::Clusters(m) => (
                Follower::of_clusters(&m.clusterer)?,
                &m.inputs,
                Vec::new(),
                Some(m.threshold),
            ),
            Model::Stability(_) | Model::TableOne(_) | Model::Classifier(_) => return None,
        };
        Some(Early {
            sums: vec![0.0; classes.len()],
            follower,
            inputs: inputs.clone(),
            verdict: Verdict {
                method: self.file.provenance.method,
                predicted: String::new(),
                decision: f64::NAN,
                classes,
                steps: Vec::new(),
                settled: None,
                novelty: threshold.map(|t| (f64::NAN, t)),
                novelty_steps: Vec::new(),
            },
            template: None,
            best: None,
            seen: 0,
        })
    }
}

/// `file` taught one more session as `fit --from` teaches it; None for a model that is
/// not taught (stability, baselines).
fn taught(file: &ModelFile, session: &Session) -> Result<Option<ModelFile>, ModelError> {
    let previous = &file.provenance;
    Ok(Some(match &file.model {
        Model::Sequences(m) => {
            let (next, secs) = continue_sequences(m, session)?;
            sequence_file(next, session, secs, previous.size_reason, Some(previous))
        }
        Model::Clusters(m) => {
            let (next, secs) = continue_clusters(m, session)?;
            cluster_file(next, session, secs, Some(previous))
        }
        Model::Stability(_) | Model::TableOne(_) | Model::Classifier(_) => return Ok(None),
    }))
}

/// Teach `file` the grasps of `session` one at a time in the session's order, each as a
/// session of its own: what a stream that met them in that order taught (`live --teach`).
/// A single `fit --from` on the whole session instead teaches in the protocol's seeded
/// shuffle, as the paper's online protocol does.
pub fn teach_in_order(file: &ModelFile, session: &Session) -> Result<ModelFile, ModelError> {
    let mut current = file.clone();
    let header = Session {
        grasps: Vec::new(),
        ..session.clone()
    };
    for g in &session.grasps {
        let one = Session {
            grasps: vec![g.clone()],
            ..header.clone()
        };
        match taught(&current, &one)? {
            Some(next) => current = next,
            None => {
                return Err(ModelError::Param(format!(
                    "a {} model is not taught further",
                    current.provenance.method.key()
                )));
            }
        }
    }
    Ok(current)
}

/// The experts as the sequence methods' common trait.
fn learner(experts: &mut Experts) -> &mut dyn SequenceClassifier {
    match experts {
        Experts::Ds(l) => l,
        Experts::Gs(l) => l,
    }
}

/// A one-grasp session's feature sequences on the model's own range: what
/// `models::inputs` reads under calibration `none` (no noise), which the tests hold equal
/// bit for bit to the models' own prediction.
fn features(inputs: &SequenceInputs, one: &Session) -> Result<FeatureSequences, ModelError> {
    let params = SequenceParams {
        features: inputs.features,
        taxel_noise_variance: 0.0,
        seed: 0,
    };
    let range = SequenceRange::Given {
        min: &inputs.min,
        max: &inputs.max,
    };
    feature_sequences_in(one, &params, range, inputs.codes.as_ref()).map_err(ModelError::Sequences)
}

/// The novelty of `seq` against the clusters learned (None before the first).
fn assess<L: NoveltyLearner>(l: &mut L, seq: ArrayView2<f64>) -> Option<f64> {
    l.assess(seq).map(|a| L::novelty(&a))
}

/// What follows an open grasp: DS/GS's experts, or DU/GU's [`NoveltySteps`].
enum Follower {
    Classes(Box<Experts>),
    Du(Box<DuSteps>),
    Gu(Box<GuSteps>),
}

impl Follower {
    fn of_clusters(c: &Clusterer) -> Option<Follower> {
        Some(match c {
            Clusterer::Du(l) => Follower::Du(Box::new(l.steps()?)),
            Clusterer::Gu(l) => Follower::Gu(Box::new(l.steps()?)),
        })
    }

    fn steps(&mut self) -> Option<&mut dyn NoveltySteps> {
        match self {
            Follower::Classes(_) => None,
            Follower::Du(s) => Some(s.as_mut()),
            Follower::Gu(s) => Some(s.as_mut()),
        }
    }

    /// DU/GU: the next step; its cluster and novelty, unless the novelty is costly now and
    /// not due ([`novelty_due`]), or `every` asks for it anyway.
    fn cluster_step(
        &mut self,
        row: &[f64],
        every: bool,
    ) -> Result<Option<NoveltyStep>, ModelError> {
        let Some(s) = self.steps() else {
            return Ok(None);
        };
        if row.len() != s.dim() {
            return Err(ModelError::Mismatch(format!(
                "a step of {} features for a model of {}",
                row.len(),
                s.dim()
            )));
        }
        let cluster = s.push(row);
        let step = s.len() - 1;
        if !every && s.novelty_costly() && !novelty_due(s.len()) {
            return Ok(None);
        }
        let novelty = s.novelty();
        Ok(Some(NoveltyStep {
            step,
            cluster,
            novelty,
        }))
    }

    /// DU/GU: the cluster and novelty after the last step taken.
    fn cluster_step_last(&mut self) -> Option<NoveltyStep> {
        let s = self.steps()?;
        let step = s.len().checked_sub(1)?;
        let novelty = s.novelty();
        Some(NoveltyStep {
            step,
            cluster: s.winner(),
            novelty,
        })
    }
}

/// DS/GS (or DU/GU) at work on a grasp still open: one step per frame.
pub struct Early {
    follower: Follower,
    inputs: SequenceInputs,
    /// The distribution so far, the running decision and when it settled.
    pub verdict: Verdict,
    /// A session of one two-frame grasp, [first, latest]: a step's features depend on its
    /// frame and the grasp's first (`change`), so its second row is the latest step's.
    template: Option<Session>,
    sums: Vec<f64>,
    /// The running decision and the step it has held since.
    best: Option<(usize, usize)>,
    /// Frames stepped.
    seen: usize,
}

impl Early {
    /// Step through the frames of the open grasp not seen yet (`frames` is the grasp so
    /// far); `spec` builds the template session as a grasp of the stream is built.
    pub fn update(&mut self, spec: &ImportSpec, frames: &[Frame]) -> Result<(), ModelError> {
        let Some(first) = frames.first() else {
            return Ok(());
        };
        while self.seen < frames.len() {
            let row = self.row(spec, first, &frames[self.seen])?;
            match &mut self.follower {
                Follower::Classes(experts) => {
                    let mut dist = vec![0.0; self.verdict.classes.len()];
                    learner(experts).predict_step(&row, &mut dist);
                    self.push(self.seen, dist);
                }
                f => {
                    let step = f.cluster_step(&row, false)?;
                    if let Some(w) = f.steps().map(|s| s.winner()) {
                        self.verdict.predicted = cluster_name(w);
                    }
                    if let Some(s) = step {
                        self.push_novelty(s);
                    }
                }
            }
            self.seen += 1;
        }
        Ok(())
    }

    /// DU/GU: the grasp so far's cluster and novelty into the verdict.
    fn push_novelty(&mut self, s: NoveltyStep) {
        let v = &mut self.verdict;
        v.predicted = cluster_name(s.cluster);
        if let Some((n, _)) = &mut v.novelty {
            *n = s.novelty;
        }
        if v.novelty_steps.len() < EARLY_CAP {
            v.novelty_steps.push(s);
        }
    }

    fn row(
        &mut self,
        spec: &ImportSpec,
        first: &Frame,
        latest: &Frame,
    ) -> Result<Vec<f64>, ModelError> {
        let mut second = latest.clone();
        // The template's frames must be in time order even for the first step.
        second.t = second.t.max(first.t + 1e-6);
        let template = match &mut self.template {
            Some(t) => t,
            None => {
                let raw = RawGrasp {
                    object: super::cut::UNLABELLED.into(),
                    classes: vec![0; spec.recorded_label_sets().len()],
                    frames: vec![first.clone(), second.clone()],
                    key_frame: Some(1),
                    trial: None,
                };
                let s = super::record::grasp_session(spec, Path::new("live"), raw)
                    .map_err(|e| ModelError::Template(Kept::new(e)))?;
                self.template.insert(s)
            }
        };
        if let Some(g) = template.grasps.first_mut() {
            g.frames = vec![first.clone(), second];
        }
        let feats = features(&self.inputs, template)?;
        feats
            .sequences
            .first()
            .filter(|s| s.nrows() == 2)
            .map(|s| s.row(1).to_vec())
            .ok_or_else(|| ModelError::Mismatch("a frame gave no feature row".into()))
    }

    fn push(&mut self, k: usize, dist: Vec<f64>) {
        let mean = self.verdict.method == MethodId::Ds;
        for (s, v) in self.sums.iter_mut().zip(&dist) {
            *s += v;
        }
        let basis = if mean { &self.sums } else { &dist };
        let best = argmax(basis);
        match self.best {
            Some((b, _)) if b == best => {}
            _ => self.best = Some((best, k)),
        }
        let v = &mut self.verdict;
        v.predicted = v.classes.get(best).cloned().unwrap_or_default();
        v.decision = dist.get(best).copied().unwrap_or(f64::NAN);
        v.settled = self.best.map(|(_, since)| since);
        if v.steps.len() < EARLY_CAP {
            v.steps.push(dist);
        }
    }
}

fn argmax(v: &[f64]) -> usize {
    v.iter()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &x)| if x > b.1 { (i, x) } else { b },
        )
        .0
}

/// The running decision after `steps` (DS: argmax of the mean; GS: of the last step).
fn running_best(steps: &[Vec<f64>], mean: bool) -> usize {
    if !mean {
        return steps.last().map_or(0, |r| argmax(r));
    }
    let mut sums = vec![0.0; steps.first().map_or(0, Vec::len)];
    for row in steps {
        for (s, v) in sums.iter_mut().zip(row) {
            *s += v;
        }
    }
    argmax(&sums)
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
        let best = argmax(if mean { &sums } else { row });
        match (best == class, from) {
            (true, None) => from = Some(k),
            (false, _) => from = None,
            _ => {}
        }
    }
    from
}
