//! Grasp stability from tactile images (the first paper): key-frame patches → sparse
//! codes on a learned dictionary → linear SVM on the concatenated codes, evaluated by
//! cross validation; a parallel grid search over (num_bases, beta, gamma) with the
//! parsimony rule; and the paper's analyses of the chosen model (Figs. 2, 5–11).
//!
//! Protocol (as in the paper): the scaling and the dictionary are fitted on all patches of
//! the session without labels (unsupervised); the SVM and its feature standardisation are
//! fitted on the training folds only. Scores are fractions (0.853 = 85.3 %). The objective
//! convention is scikit-learn's, documented in [`crate::sparse`]:
//! F = (1/N) Σ [0.5 ||x − aD||² + λ ||a||₁], with λ = `beta` when learning the
//! dictionary and λ = `gamma` when coding.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use ndarray::{Array2, ArrayView1, ArrayView2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::links::{GraspCode, PatchCode};
use super::report::SizeReason;
use crate::features::{KeyFramePatches, PatchError, PatchScaling, Standardizer};
use crate::jobs::Progress;
use crate::session::{Layout, Session};
use crate::sparse::{Dictionary, DictionaryParams, SparseError};
use crate::svm::{
    Confusion, CvResult, Folds, LinearSvm, LinearSvmParams, SvmError, cross_validate, group_k_fold,
    stratified_k_fold,
};

pub const CONVENTION: &str = "F = (1/N) Σ_i [0.5 ||x_i − a_i D||² + λ ||a_i||₁], ||d_j||² ≤ 1; \
λ = beta while learning the dictionary, λ = gamma when coding (scikit-learn's convention; \
a penalty written without the 0.5, as in the paper's eqs. 2–3, is twice these values)";

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StabilityError {
    #[error(transparent)]
    Patch(#[from] PatchError),
    #[error("sparse coding: {0}")]
    Sparse(SparseError),
    #[error("SVM: {0}")]
    Svm(SvmError),
    #[error("invalid parameter: {0}")]
    Param(String),
    #[error("invalid data: {0}")]
    Data(String),
    #[error("cancelled")]
    Cancelled,
}

impl From<SparseError> for StabilityError {
    fn from(e: SparseError) -> Self {
        match e {
            SparseError::Cancelled => StabilityError::Cancelled,
            e => StabilityError::Sparse(e),
        }
    }
}

impl From<SvmError> for StabilityError {
    fn from(e: SvmError) -> Self {
        match e {
            SvmError::Cancelled => StabilityError::Cancelled,
            e => StabilityError::Svm(e),
        }
    }
}

impl From<crate::jobs::Cancelled> for StabilityError {
    fn from(_: crate::jobs::Cancelled) -> Self {
        StabilityError::Cancelled
    }
}

// ---------------------------------------------------------------------------------------
// Data
// ---------------------------------------------------------------------------------------

/// Which labels mean failure, and how patches are scaled.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DataOptions {
    /// Label set holding the grasp outcome (default: the first whose name mentions
    /// outcome, stability, slip, success or failure; else the first).
    pub label_set: Option<String>,
    /// Class meaning a failed grasp (default: the first class whose name mentions fail,
    /// slip, drop, unstable or lost; else the second class).
    pub failure_class: Option<String>,
    pub scaling: PatchScaling,
}

/// A session prepared for the pipeline.
#[derive(Clone, Debug)]
pub struct StabilityData {
    pub session_name: String,
    pub patches: KeyFramePatches,
    /// Scaled patches, one row per (grasp, sensor), grasp-major.
    pub x: Array2<f64>,
    /// true = failure, per grasp.
    pub labels: Vec<bool>,
    /// Object index of every grasp into `object_names`.
    pub objects: Vec<usize>,
    pub object_names: Vec<String>,
    pub label_set: String,
    pub success_name: String,
    pub failure_name: String,
    /// Layout of the first sensor (used to draw basis images).
    pub layout: Option<Layout>,
    /// Index into `Session::grasps` of every grasp.
    pub grasp_ids: Vec<usize>,
}

impl StabilityData {
    pub fn from_session(session: &Session, opts: &DataOptions) -> Result<Self, StabilityError> {
        if session.label_sets.is_empty() {
            return Err(StabilityError::Data("the session has no label sets".into()));
        }
        let set = match &opts.label_set {
            Some(name) => session.label_set(name).ok_or_else(|| {
                StabilityError::Param(format!(
                    "no label set {name:?}; the session has {:?}",
                    session
                        .label_sets
                        .iter()
                        .map(|l| &l.name)
                        .collect::<Vec<_>>()
                ))
            })?,
            None => session
                .label_sets
                .iter()
                .position(|l| {
                    let n = l.name.to_lowercase();
                    ["outcome", "stab", "slip", "success", "fail"]
                        .iter()
                        .any(|k| n.contains(k))
                })
                .unwrap_or(0),
        };
        let ls = &session.label_sets[set];
        let failure = match &opts.failure_class {
            Some(name) => ls.classes.iter().position(|c| c == name).ok_or_else(|| {
                StabilityError::Param(format!(
                    "label set {:?} has no class {name:?} (classes {:?})",
                    ls.name, ls.classes
                ))
            })?,
            None => ls
                .classes
                .iter()
                .position(|c| {
                    let c = c.to_lowercase();
                    ["fail", "slip", "drop", "unstable", "lost"]
                        .iter()
                        .any(|k| c.contains(k))
                })
                .or((ls.classes.len() == 2).then_some(1))
                .ok_or_else(|| {
                    StabilityError::Param(format!(
                        "cannot tell which class of {:?} {:?} is the failure: name it",
                        ls.name, ls.classes
                    ))
                })?,
        };
        let mut labels = Vec::with_capacity(session.grasps.len());
        for (g, grasp) in session.grasps.iter().enumerate() {
            let l = *grasp.labels.get(set).ok_or_else(|| {
                StabilityError::Data(format!("grasp {g} has no label in set {:?}", ls.name))
            })?;
            labels.push(l == failure);
        }
        let object_names = session.objects();
        let objects = session
            .grasps
            .iter()
            .map(|g| {
                object_names
                    .iter()
                    .position(|o| *o == g.object)
                    .unwrap_or(0)
            })
            .collect();
        let patches = KeyFramePatches::from_session(session, opts.scaling)?;
        let success_name = if ls.classes.len() == 2 {
            ls.classes[1 - failure].clone()
        } else {
            format!("not {}", ls.classes[failure])
        };
        let data = StabilityData {
            session_name: session.meta.name.clone(),
            x: patches.patches(),
            patches,
            labels,
            objects,
            object_names,
            label_set: ls.name.clone(),
            success_name,
            failure_name: ls.classes[failure].clone(),
            layout: session.sensors.first().map(|s| s.layout.clone()),
            grasp_ids: (0..session.grasps.len()).collect(),
        };
        data.check()?;
        Ok(data)
    }

    fn check(&self) -> Result<(), StabilityError> {
        let failures = self.labels.iter().filter(|l| **l).count();
        if failures == 0 || failures == self.labels.len() {
            return Err(StabilityError::Data(format!(
                "all {} grasps have the same outcome; the classifier needs both",
                self.labels.len()
            )));
        }
        Ok(())
    }

    /// The same data restricted to some grasps (in the given order); the scaling is
    /// refitted on them. For scaling studies and held-out tests.
    pub fn subset(&self, grasps: &[usize]) -> Result<Self, StabilityError> {
        let pressures = crate::svm::gather(self.patches.pressures.view(), grasps);
        let scaler = match self.patches.scaling {
            PatchScaling::ZScorePerTaxel => Some(Standardizer::fit(pressures.view())),
            PatchScaling::None => None,
        };
        let patches = KeyFramePatches {
            pressures,
            scaler,
            ..self.patches.clone()
        };
        let data = StabilityData {
            x: patches.patches(),
            patches,
            labels: grasps.iter().map(|&g| self.labels[g]).collect(),
            objects: grasps.iter().map(|&g| self.objects[g]).collect(),
            grasp_ids: grasps.iter().map(|&g| self.grasp_ids[g]).collect(),
            ..self.clone()
        };
        data.check()?;
        Ok(data)
    }

    pub fn grasp_count(&self) -> usize {
        self.labels.len()
    }

    pub fn sensor_count(&self) -> usize {
        self.patches.sensor_count()
    }

    pub fn dim(&self) -> usize {
        self.patches.dim
    }

    /// The scaled key-frame images (grasps × sensors·taxels): the raw-electrode baseline's
    /// features.
    pub fn images(&self) -> Array2<f64> {
        self.patches.images()
    }
}

/// A grasp's feature vector: its patches' codes side by side (G·S × K → G × S·K).
pub fn grasp_features(codes: Array2<f64>, sensors: usize) -> Array2<f64> {
    let (rows, k) = codes.dim();
    let codes = codes.as_standard_layout().into_owned();
    codes
        .into_shape_with_order((rows / sensors, sensors * k))
        .expect("codes hold whole grasps")
}

// ---------------------------------------------------------------------------------------
// Settings, cross validation and one configuration
// ---------------------------------------------------------------------------------------

/// How folds are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CvScheme {
    /// Stratified k-fold over grasps (the paper's 10-fold).
    KFold { k: usize },
    /// Folds by object, no object in both train and test (the paper's "new objects");
    /// `folds: None` leaves one object out at a time.
    LeaveObjectsOut { folds: Option<usize> },
}

impl CvScheme {
    pub fn folds(&self, data: &StabilityData, seed: u64) -> Result<Folds, StabilityError> {
        Ok(match *self {
            CvScheme::KFold { k } => stratified_k_fold(&data.labels, k, seed)?,
            CvScheme::LeaveObjectsOut { folds } => group_k_fold(&data.objects, folds, seed)?,
        })
    }

    pub fn describe(&self) -> String {
        match self {
            CvScheme::KFold { k } => format!("stratified {k}-fold"),
            CvScheme::LeaveObjectsOut { folds: None } => "leave one object out".into(),
            CvScheme::LeaveObjectsOut { folds: Some(k) } => {
                format!("leave objects out ({k} folds by object)")
            }
        }
    }
}

/// Everything but the grid coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PipelineSettings {
    /// Dictionary learning (its `num_bases` and `beta` are set per configuration).
    pub dictionary: DictionaryParams,
    pub svm: LinearSvmParams,
    /// Seed of the fold assignment.
    pub cv_seed: u64,
}

impl Default for PipelineSettings {
    fn default() -> Self {
        PipelineSettings {
            dictionary: DictionaryParams::default(),
            svm: LinearSvmParams {
                loss: crate::svm::Loss::SquaredHinge,
                ..Default::default()
            },
            cv_seed: 0,
        }
    }
}

/// One configuration of the grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
}

impl std::fmt::Display for Config {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "num_bases {}, beta {}, gamma {}",
            self.num_bases, self.beta, self.gamma
        )
    }
}

/// Share of zero coefficients and mean non-zero coefficients per patch.
fn sparsity_of(codes: ArrayView2<f64>) -> (f64, f64) {
    let total = codes.len().max(1) as f64;
    let nz = codes.iter().filter(|v| **v != 0.0).count() as f64;
    (1.0 - nz / total, nz / codes.nrows().max(1) as f64)
}

/// Scores and timings of one grid cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellResult {
    pub config: Config,
    /// Pooled weighted success rate of the cross validation (the grid's score).
    pub weighted_success_rate: f64,
    pub failure_recall: f64,
    /// Per-fold mean and standard error of the weighted success rate.
    pub fold_wsr_mean: f64,
    pub fold_wsr_se: f64,
    /// Share of zero coefficients in the codes (the paper's "sparsity").
    pub sparsity: f64,
    pub active_bases_per_patch: f64,
    /// F of the dictionary (penalty beta) and its learning iterations.
    pub dictionary_objective: f64,
    pub dictionary_iterations: usize,
    /// Seconds: learning this cell's dictionary (shared by the cells with the same
    /// num_bases and beta), coding all patches with gamma, and the cross validation.
    pub dictionary_secs: f64,
    pub coding_secs: f64,
    pub cv_secs: f64,
}

/// Code every patch with `gamma` and cross-validate the SVM on the grasp features.
fn score_codes(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    folds: &Folds,
    svm: &LinearSvmParams,
) -> Result<(Array2<f64>, CvResult, f64, f64), StabilityError> {
    let t0 = Instant::now();
    let codes = dict.encode(data.x.view(), gamma)?;
    let coding_secs = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let features = grasp_features(codes.clone(), data.sensor_count());
    let cv = cross_validate(features.view(), &data.labels, folds, svm)?;
    Ok((codes, cv, coding_secs, t1.elapsed().as_secs_f64()))
}

// ---------------------------------------------------------------------------------------
// Grid search
// ---------------------------------------------------------------------------------------

/// The grid: every combination of the three lists.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridSpec {
    pub num_bases: Vec<usize>,
    pub beta: Vec<f64>,
    pub gamma: Vec<f64>,
}

impl GridSpec {
    /// The default: num_bases 2..=60 and log grids of beta and gamma suited to
    /// z-scored patches (0.25 to 4, factor 2); on raw pressures the penalties scale with
    /// the squared patch norm, so the grids are multiplied by the mean patch energy per
    /// taxel (which is 1 for z-scored data).
    pub fn default_for(data: &StabilityData) -> Self {
        let energy = data.x.iter().map(|v| v * v).sum::<f64>() / data.x.len().max(1) as f64;
        let scale = if data.patches.scaling == PatchScaling::None {
            energy.max(1e-12)
        } else {
            1.0
        };
        let log = [0.25, 0.5, 1.0, 2.0, 4.0]
            .iter()
            .map(|v| v * scale)
            .collect::<Vec<_>>();
        GridSpec {
            num_bases: (2..=60).collect(),
            beta: log.clone(),
            gamma: log,
        }
    }

    /// The benchmark grid: num_bases 5..=60 step 5 × beta, gamma ∈ {0.5, 1, 2} (108 cells).
    pub fn bench() -> Self {
        GridSpec {
            num_bases: (1..=12).map(|i| 5 * i).collect(),
            beta: vec![0.5, 1.0, 2.0],
            gamma: vec![0.5, 1.0, 2.0],
        }
    }

    pub fn cells(&self) -> usize {
        self.num_bases.len() * self.beta.len() * self.gamma.len()
    }

    pub fn validate(&self) -> Result<(), StabilityError> {
        if self.cells() == 0 {
            return Err(StabilityError::Param("the grid is empty".into()));
        }
        if self.num_bases.contains(&0) {
            return Err(StabilityError::Param("num_bases must be ≥ 1".into()));
        }
        for (name, v) in [("beta", &self.beta), ("gamma", &self.gamma)] {
            if let Some(b) = v.iter().find(|b| !(**b > 0.0 && b.is_finite())) {
                return Err(StabilityError::Param(format!(
                    "{name} must be finite and > 0, got {b}"
                )));
            }
        }
        Ok(())
    }
}

/// Grid search results.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridResult {
    pub spec: GridSpec,
    pub cv: CvScheme,
    /// Every cell, ordered by num_bases, then beta, then gamma.
    pub cells: Vec<CellResult>,
    /// For each num_bases (ascending), its best cell: the paper's Fig. 5.
    pub best_per_num_bases: Vec<CellResult>,
    /// The cell with the highest weighted success rate (ties: fewer bases first).
    pub best: CellResult,
    /// The smallest num_bases whose best score is within one standard error (of the
    /// best cell's per-fold scores) of the best: the recommended model.
    pub parsimonious: CellResult,
    pub best_dictionary: Dictionary,
    pub parsimonious_dictionary: Dictionary,
    pub secs: f64,
    pub threads: usize,
}

/// One task of the grid: a (num_bases, beta) dictionary, its gamma values coded and
/// cross-validated in turn. The unit of parallel work here and of a sharded sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridTask {
    pub num_bases: usize,
    pub beta: f64,
}

/// What a grid task leaves: its cells (in gamma order) and its dictionary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridTaskOutput {
    pub cells: Vec<CellResult>,
    pub dictionary: Dictionary,
}

impl GridSpec {
    /// The grid's tasks in grid order (num_bases, then beta).
    pub fn tasks(&self) -> Vec<GridTask> {
        self.num_bases
            .iter()
            .flat_map(|&num_bases| {
                self.beta
                    .iter()
                    .map(move |&beta| GridTask { num_bases, beta })
            })
            .collect()
    }
}

/// Check the grid and the settings, and make the folds of the selection protocol.
pub fn grid_folds(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    cv: CvScheme,
) -> Result<Folds, StabilityError> {
    spec.validate()?;
    settings.dictionary.validate()?;
    settings.svm.validate()?;
    cv.folds(data, settings.cv_seed)
}

/// Learn the task's dictionary and score it with every gamma on `folds`; `on_cell` is told
/// of each finished cell. Depends on nothing but its arguments (every seed is in
/// `settings`), so any machine computes the same task alike.
pub fn grid_task(
    data: &StabilityData,
    gamma: &[f64],
    folds: &Folds,
    settings: &PipelineSettings,
    task: GridTask,
    progress: &Progress,
    on_cell: &(dyn Fn(&CellResult) + Sync),
) -> Result<GridTaskOutput, StabilityError> {
    progress.checkpoint()?;
    let GridTask { num_bases, beta } = task;
    let params = DictionaryParams {
        num_bases,
        beta,
        ..settings.dictionary.clone()
    };
    let fit = params.fit_within(data.x.view(), progress)?;
    let mut cells = Vec::with_capacity(gamma.len());
    for &gamma in gamma {
        progress.checkpoint()?;
        let (codes, cvr, coding_secs, cv_secs) =
            score_codes(data, &fit.dictionary, gamma, folds, &settings.svm)?;
        let (sparsity, active) = sparsity_of(codes.view());
        let cell = CellResult {
            config: Config {
                num_bases,
                beta,
                gamma,
            },
            weighted_success_rate: cvr.weighted_success_rate,
            failure_recall: cvr.failure_recall,
            fold_wsr_mean: cvr.fold_wsr_mean,
            fold_wsr_se: cvr.fold_wsr_se,
            sparsity,
            active_bases_per_patch: active,
            dictionary_objective: fit.objective,
            dictionary_iterations: fit.iterations,
            dictionary_secs: fit.secs,
            coding_secs,
            cv_secs,
        };
        on_cell(&cell);
        cells.push(cell);
    }
    Ok(GridTaskOutput {
        cells,
        dictionary: fit.dictionary,
    })
}

/// The grid's result from the outputs of its tasks (in the order of `tasks`).
pub fn assemble_grid(
    spec: &GridSpec,
    cv: CvScheme,
    tasks: &[GridTask],
    outputs: Vec<GridTaskOutput>,
    secs: f64,
    threads: usize,
) -> GridResult {
    let mut cells = Vec::with_capacity(spec.cells());
    let mut dicts = Vec::with_capacity(tasks.len());
    for out in outputs {
        cells.extend(out.cells);
        dicts.push(out.dictionary);
    }
    let dict_of = |cell: &CellResult| -> Dictionary {
        let i = tasks
            .iter()
            .position(|t| t.num_bases == cell.config.num_bases && t.beta == cell.config.beta)
            .expect("every cell comes from a task");
        dicts[i].clone()
    };
    let (best_per_num_bases, best, parsimonious) = choose(&cells, &spec.num_bases);
    GridResult {
        spec: spec.clone(),
        cv,
        best_dictionary: dict_of(&best),
        parsimonious_dictionary: dict_of(&parsimonious),
        cells,
        best_per_num_bases,
        best,
        parsimonious,
        secs,
        threads,
    }
}

/// Run the grid in parallel (rayon: one [`GridTask`] per (num_bases, beta) dictionary; the
/// folds of each cross validation run in parallel too). Cancellable between dictionaries
/// and learning iterations; `progress` gets the fraction of cells done. The same seeds
/// give the same numbers whatever the thread count.
pub fn grid_search(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    cv: CvScheme,
    progress: &Progress,
) -> Result<GridResult, StabilityError> {
    let folds = grid_folds(data, spec, settings, cv)?;
    let start = Instant::now();
    let tasks = spec.tasks();
    let total = spec.cells();
    let done = AtomicUsize::new(0);
    progress.set(0.0, format!("grid search: {total} configurations"));
    let on_cell = |c: &CellResult| {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress.set(
            n as f64 / total as f64,
            format!("grid search: {n}/{total} ({})", c.config),
        );
    };
    let outputs = tasks
        .par_iter()
        .map(|&t| grid_task(data, &spec.gamma, &folds, settings, t, progress, &on_cell))
        .collect::<Result<Vec<_>, _>>()?;
    // Workers report out of order; the last word is the whole grid.
    progress.set(
        1.0,
        format!("grid search: {total}/{total} configurations done"),
    );
    Ok(assemble_grid(
        spec,
        cv,
        &tasks,
        outputs,
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads(),
    ))
}

/// Best cell per num_bases, the best overall (ties: fewer bases, then grid order) and the
/// parsimonious choice: the smallest num_bases whose best score ≥ best − SE(best).
pub fn choose(
    cells: &[CellResult],
    num_bases: &[usize],
) -> (Vec<CellResult>, CellResult, CellResult) {
    let mut ks: Vec<usize> = num_bases.to_vec();
    ks.sort_unstable();
    ks.dedup();
    let better = |a: &CellResult, b: &CellResult| a.weighted_success_rate > b.weighted_success_rate;
    let per_k: Vec<CellResult> = ks
        .iter()
        .filter_map(|&k| {
            cells.iter().filter(|c| c.config.num_bases == k).fold(
                None,
                |acc: Option<&CellResult>, c| match acc {
                    Some(a) if !better(c, a) => Some(a),
                    _ => Some(c),
                },
            )
        })
        .cloned()
        .collect();
    let best = per_k
        .iter()
        .fold(None, |acc: Option<&CellResult>, c| match acc {
            Some(a) if !better(c, a) => Some(a),
            _ => Some(c),
        })
        .cloned()
        .expect("a non-empty grid");
    let bar = best.weighted_success_rate - best.fold_wsr_se.max(0.0);
    let parsimonious = per_k
        .iter()
        .find(|c| c.weighted_success_rate >= bar)
        .cloned()
        .unwrap_or_else(|| best.clone());
    (per_k, best, parsimonious)
}

// ---------------------------------------------------------------------------------------
// Nested cross validation of the grid's selection
// ---------------------------------------------------------------------------------------

/// One outer fold of a nested cross validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NestedFold {
    pub fold: usize,
    pub train: usize,
    pub test: usize,
    /// The configuration the one-standard-error rule chose from the inner cross validation
    /// on the outer training grasps, and its inner weighted success rate.
    pub chosen: Config,
    pub chosen_inner_wsr: f64,
    /// The inner grid's highest-scoring configuration and its inner score.
    pub best: Config,
    pub best_inner_wsr: f64,
    /// The chosen model, trained on the outer training grasps, on the outer test grasps.
    pub confusion: Confusion,
    pub weighted_success_rate: Option<f64>,
    /// The raw linear SVM on the same split.
    pub raw_confusion: Confusion,
    pub raw_weighted_success_rate: Option<f64>,
}

/// Nested cross validation: the outer folds score, the grid search with its
/// one-standard-error rule runs inside every outer training fold (inner folds of the same
/// protocol), so no selection sees the labels of the grasps it is scored on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NestedResult {
    /// The protocol of the outer and the inner folds.
    pub protocol: CvScheme,
    pub description: String,
    pub folds: Vec<NestedFold>,
    /// Pooled over the outer test folds (every grasp tested once), and the per-fold mean
    /// and standard error over the folds holding both classes.
    pub weighted_success_rate: f64,
    pub failure_recall: f64,
    pub fold_wsr_mean: f64,
    pub fold_wsr_se: f64,
    /// The raw linear SVM under the same outer folds.
    pub raw_weighted_success_rate: f64,
    pub raw_failure_recall: f64,
    pub secs: f64,
}

/// Nested cross validation of the grid search under `protocol` (outer folds from the
/// settings' seed).
pub fn nested_cv(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    protocol: CvScheme,
    progress: &Progress,
) -> Result<NestedResult, StabilityError> {
    let outer = protocol.folds(data, settings.cv_seed)?;
    nested_cv_on(data, spec, settings, protocol, &outer, progress)
}

/// Inner folds of `protocol` over the grasps `train` (indices into `data`).
fn inner_folds(
    data: &StabilityData,
    train: &[usize],
    protocol: CvScheme,
    seed: u64,
) -> Result<Folds, StabilityError> {
    Ok(match protocol {
        CvScheme::KFold { k } => {
            let y: Vec<bool> = train.iter().map(|&g| data.labels[g]).collect();
            stratified_k_fold(&y, k, seed)?
        }
        CvScheme::LeaveObjectsOut { folds } => {
            let objects: Vec<usize> = train.iter().map(|&g| data.objects[g]).collect();
            group_k_fold(&objects, folds, seed)?
        }
    })
}

/// Every cell's inner scores and outer-test predictions for one outer fold.
struct NestedCell {
    config: Config,
    inner: CvResult,
    test_predictions: Vec<bool>,
}

/// [`nested_cv`] with given outer folds. Dictionaries are learned once per (num_bases,
/// beta) on all patches without labels, as in the grid search; every label the selection
/// uses comes from the outer training grasps.
pub fn nested_cv_on(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    protocol: CvScheme,
    outer: &Folds,
    progress: &Progress,
) -> Result<NestedResult, StabilityError> {
    spec.validate()?;
    settings.dictionary.validate()?;
    settings.svm.validate()?;
    if outer.fold_of.len() != data.grasp_count() {
        return Err(StabilityError::Data(format!(
            "{} outer fold assignments for {} grasps",
            outer.fold_of.len(),
            data.grasp_count()
        )));
    }
    let start = Instant::now();
    let splits: Vec<(Vec<usize>, Vec<usize>, Folds)> = (0..outer.count)
        .map(|f| {
            let train = outer.train_indices(f);
            let inner = inner_folds(data, &train, protocol, settings.cv_seed)?;
            Ok((train, outer.test_indices(f), inner))
        })
        .collect::<Result<_, StabilityError>>()?;
    let tasks: Vec<(usize, f64)> = spec
        .num_bases
        .iter()
        .flat_map(|&k| spec.beta.iter().map(move |&b| (k, b)))
        .collect();
    let done = AtomicUsize::new(0);
    let total = spec.cells();
    progress.set(
        0.0,
        format!("nested {}: {total} configurations", protocol.describe()),
    );
    // cells[task][gamma][outer fold]
    let cells: Vec<Vec<Vec<NestedCell>>> = tasks
        .par_iter()
        .map(|&(k, beta)| {
            progress.checkpoint()?;
            let fit = DictionaryParams {
                num_bases: k,
                beta,
                ..settings.dictionary.clone()
            }
            .fit_within(data.x.view(), progress)?;
            let mut per_gamma = Vec::with_capacity(spec.gamma.len());
            for &gamma in &spec.gamma {
                progress.checkpoint()?;
                let codes = fit.dictionary.encode(data.x.view(), gamma)?;
                let features = grasp_features(codes, data.sensor_count());
                let config = Config {
                    num_bases: k,
                    beta,
                    gamma,
                };
                let mut per_fold = Vec::with_capacity(splits.len());
                for (train, test, inner) in &splits {
                    let xt = crate::svm::gather(features.view(), train);
                    let yt: Vec<bool> = train.iter().map(|&g| data.labels[g]).collect();
                    let cv = cross_validate(xt.view(), &yt, inner, &settings.svm)?;
                    let model = settings.svm.fit(xt.view(), &yt)?;
                    per_fold.push(NestedCell {
                        config,
                        inner: cv,
                        test_predictions: test
                            .iter()
                            .map(|&g| model.predict(features.row(g)))
                            .collect(),
                    });
                }
                per_gamma.push(per_fold);
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress.set(
                    n as f64 / total as f64,
                    format!("nested {}: {n}/{total}", protocol.describe()),
                );
            }
            Ok(per_gamma)
        })
        .collect::<Result<_, StabilityError>>()?;
    let cells: Vec<Vec<NestedCell>> = cells.into_iter().flatten().collect();
    let raw = cross_validate(data.images().view(), &data.labels, outer, &settings.svm)?;
    let mut pooled = Confusion::default();
    let mut folds = Vec::with_capacity(splits.len());
    for (f, (train, test, _)) in splits.iter().enumerate() {
        let inner: Vec<CellResult> = cells
            .iter()
            .map(|c| {
                let cv = &c[f].inner;
                CellResult {
                    config: c[f].config,
                    weighted_success_rate: cv.weighted_success_rate,
                    failure_recall: cv.failure_recall,
                    fold_wsr_mean: cv.fold_wsr_mean,
                    fold_wsr_se: cv.fold_wsr_se,
                    sparsity: 0.0,
                    active_bases_per_patch: 0.0,
                    dictionary_objective: 0.0,
                    dictionary_iterations: 0,
                    dictionary_secs: 0.0,
                    coding_secs: 0.0,
                    cv_secs: 0.0,
                }
            })
            .collect();
        let (_, best, chosen) = choose(&inner, &spec.num_bases);
        let cell = cells
            .iter()
            .map(|c| &c[f])
            .find(|c| c.config == chosen.config)
            .expect("the choice is a cell");
        let truth: Vec<bool> = test.iter().map(|&g| data.labels[g]).collect();
        let confusion = Confusion::from_predictions(&truth, &cell.test_predictions);
        pooled.add(&confusion);
        let raw_fold = raw
            .folds
            .iter()
            .find(|r| r.fold == f)
            .expect("one score per outer fold");
        folds.push(NestedFold {
            fold: f,
            train: train.len(),
            test: test.len(),
            chosen: chosen.config,
            chosen_inner_wsr: chosen.weighted_success_rate,
            best: best.config,
            best_inner_wsr: best.weighted_success_rate,
            weighted_success_rate: confusion.weighted_success_rate(),
            confusion,
            raw_confusion: raw_fold.confusion,
            raw_weighted_success_rate: raw_fold.weighted_success_rate,
        });
    }
    let per_fold: Vec<f64> = folds
        .iter()
        .filter_map(|f| f.weighted_success_rate)
        .collect();
    let (fold_wsr_mean, fold_wsr_se) = crate::svm::mean_se(&per_fold);
    Ok(NestedResult {
        protocol,
        description: format!(
            "nested: outer {}, grid and one-SE rule on inner {} of each outer training fold",
            protocol.describe(),
            protocol.describe()
        ),
        folds,
        weighted_success_rate: pooled.weighted_success_rate().unwrap_or(f64::NAN),
        failure_recall: pooled.failure_recall().unwrap_or(f64::NAN),
        fold_wsr_mean,
        fold_wsr_se,
        raw_weighted_success_rate: raw.weighted_success_rate,
        raw_failure_recall: raw.failure_recall,
        secs: start.elapsed().as_secs_f64(),
    })
}

// ---------------------------------------------------------------------------------------
// Evaluation of a chosen model, the baseline, and the model for prediction
// ---------------------------------------------------------------------------------------

/// A configuration evaluated under both protocols.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Evaluation {
    pub config: Config,
    pub dictionary_objective: f64,
    pub dictionary_iterations: usize,
    pub dictionary_secs: f64,
    pub sparsity: f64,
    pub active_bases_per_patch: f64,
    pub kfold: CvResult,
    pub objects: CvResult,
}

/// The pipeline's model trained on every grasp, for predicting new grasps: the session's
/// scaling, the dictionary, gamma and the SVM on the concatenated codes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StabilityModel {
    pub config: Config,
    pub scaler: Option<Standardizer>,
    pub sensors: usize,
    pub dim: usize,
    pub dictionary: Dictionary,
    pub svm: LinearSvm,
}

impl StabilityModel {
    /// Train on all grasps of `data` with a given dictionary.
    pub fn train(
        data: &StabilityData,
        config: Config,
        dictionary: Dictionary,
        svm: &LinearSvmParams,
    ) -> Result<Self, StabilityError> {
        let codes = dictionary.encode(data.x.view(), config.gamma)?;
        let features = grasp_features(codes, data.sensor_count());
        let svm = svm.fit(features.view(), &data.labels)?;
        Ok(StabilityModel {
            config,
            scaler: data.patches.scaler.clone(),
            sensors: data.sensor_count(),
            dim: data.dim(),
            dictionary,
            svm,
        })
    }

    /// Predict failure (true) from a grasp's key-frame pressures, sensors side by side,
    /// scaled exactly as the training session was.
    pub fn predict_failure(&self, pressures: ArrayView1<f64>) -> Result<bool, StabilityError> {
        let expected = self.sensors * self.dim;
        if pressures.len() != expected {
            return Err(StabilityError::Data(format!(
                "{} pressures where the model expects {expected}",
                pressures.len()
            )));
        }
        let mut img = vec![0.0; expected];
        match &self.scaler {
            Some(s) => s.transform_into(pressures, &mut img),
            None => img
                .iter_mut()
                .zip(pressures.iter())
                .for_each(|(o, v)| *o = *v),
        }
        let patches = ArrayView2::from_shape((self.sensors, self.dim), &img)
            .map_err(|e| StabilityError::Data(e.to_string()))?;
        let codes = self.dictionary.encode(patches, self.config.gamma)?;
        let features = grasp_features(codes, self.sensors);
        Ok(self.svm.predict(features.row(0)))
    }
}

/// Learn the dictionary of `config` and evaluate it under k-fold and leave-objects-out.
pub fn evaluate_config(
    data: &StabilityData,
    config: Config,
    settings: &PipelineSettings,
    kfold: CvScheme,
    objects: CvScheme,
    dictionary: Option<Dictionary>,
    progress: &Progress,
) -> Result<(Evaluation, Dictionary), StabilityError> {
    let t0 = Instant::now();
    let (dict, objective, iterations) = match dictionary {
        Some(d) => {
            let codes = d.encode(data.x.view(), config.beta)?;
            let f = crate::sparse::objective(
                data.x.view(),
                d.atoms.view(),
                codes.view(),
                crate::sparse::CodePenalty::L1,
                config.beta,
            );
            (d, f, 0)
        }
        None => {
            let params = DictionaryParams {
                num_bases: config.num_bases,
                beta: config.beta,
                ..settings.dictionary.clone()
            };
            let fit = params.fit_within(data.x.view(), progress)?;
            (fit.dictionary, fit.objective, fit.iterations)
        }
    };
    let dictionary_secs = t0.elapsed().as_secs_f64();
    progress.checkpoint()?;
    let kf = kfold.folds(data, settings.cv_seed)?;
    let (codes, kcv, _, _) = score_codes(data, &dict, config.gamma, &kf, &settings.svm)?;
    let of = objects.folds(data, settings.cv_seed)?;
    let features = grasp_features(codes.clone(), data.sensor_count());
    let ocv = cross_validate(features.view(), &data.labels, &of, &settings.svm)?;
    let (sparsity, active) = sparsity_of(codes.view());
    Ok((
        Evaluation {
            config,
            dictionary_objective: objective,
            dictionary_iterations: iterations,
            dictionary_secs,
            sparsity,
            active_bases_per_patch: active,
            kfold: kcv,
            objects: ocv,
        },
        dict,
    ))
}

/// The baseline: the linear SVM on the scaled raw key-frame values (every taxel of
/// every sensor), under both protocols.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Baseline {
    pub features: usize,
    pub kfold: CvResult,
    pub objects: CvResult,
}

pub fn baseline(
    data: &StabilityData,
    settings: &PipelineSettings,
    kfold: CvScheme,
    objects: CvScheme,
) -> Result<Baseline, StabilityError> {
    let x = data.images();
    let kf = kfold.folds(data, settings.cv_seed)?;
    let of = objects.folds(data, settings.cv_seed)?;
    Ok(Baseline {
        features: x.ncols(),
        kfold: cross_validate(x.view(), &data.labels, &kf, &settings.svm)?,
        objects: cross_validate(x.view(), &data.labels, &of, &settings.svm)?,
    })
}

// ---------------------------------------------------------------------------------------
// Analyses of a model (the paper's Figs. 2, 6, 8–11)
// ---------------------------------------------------------------------------------------

/// The filter of the "filtered" basis images (the paper's Fig. 6b does not state its).
pub const FILTER: &str = "Gaussian kernel interpolation (Nadaraya–Watson) of the taxel values \
onto a grid of 4 pixels per taxel cell, σ = 0.6 cell; pixels farther than 0.75 cell from \
every taxel are left empty (background). Grid layouts use (column, row) as taxel \
coordinates; point layouts use positions divided by the taxel diameter.";
const UPSAMPLE: usize = 4;
const FILTER_SIGMA: f64 = 0.6;
const FILTER_REACH: f64 = 0.75;

/// An image on a grid, row-major, `None` where there is no taxel (background).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridImage {
    pub rows: usize,
    pub cols: usize,
    pub pixels: Vec<Option<f64>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BasisImage {
    pub basis: usize,
    /// The basis vector, one value per taxel (in the scaled units of the patches).
    pub values: Vec<f64>,
    /// The values on the sensor's grid (grid layouts only): Fig. 6a.
    pub raw: Option<GridImage>,
    /// Smoothed by [`FILTER`]: Fig. 6b.
    pub filtered: Option<GridImage>,
}

/// Taxel centres in cell units for drawing.
fn taxel_coords(layout: &Layout) -> Vec<(f64, f64)> {
    match layout {
        Layout::Grid { .. } | Layout::SparseGrid { .. } => (0..layout.taxel_count())
            .map(|i| {
                let (r, c) = layout.grid_cell(i).unwrap_or((0, 0));
                (c as f64, r as f64)
            })
            .collect(),
        Layout::Points {
            positions, radius, ..
        } => {
            let d = (2.0 * radius).max(1e-9);
            positions.iter().map(|p| (p.x / d, p.y / d)).collect()
        }
    }
}

fn raw_image(layout: &Layout, values: &[f64]) -> Option<GridImage> {
    let (rows, cols) = layout.grid_shape()?;
    let mut pixels = vec![None; rows * cols];
    for (i, &v) in values.iter().enumerate() {
        if let Some((r, c)) = layout.grid_cell(i)
            && r < rows
            && c < cols
        {
            pixels[r * cols + c] = Some(v);
        }
    }
    Some(GridImage { rows, cols, pixels })
}

fn filtered_image(coords: &[(f64, f64)], values: &[f64]) -> Option<GridImage> {
    if coords.is_empty() {
        return None;
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in coords {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let cols = ((x1 - x0 + 1.0) * UPSAMPLE as f64).round().max(1.0) as usize;
    let rows = ((y1 - y0 + 1.0) * UPSAMPLE as f64).round().max(1.0) as usize;
    let mut pixels = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let px = x0 - 0.5 + (c as f64 + 0.5) / UPSAMPLE as f64;
            let py = y0 - 0.5 + (r as f64 + 0.5) / UPSAMPLE as f64;
            let (mut num, mut den, mut nearest) = (0.0, 0.0, f64::MAX);
            for (&(x, y), &v) in coords.iter().zip(values) {
                let d2 = (px - x).powi(2) + (py - y).powi(2);
                nearest = nearest.min(d2);
                let w = (-d2 / (2.0 * FILTER_SIGMA * FILTER_SIGMA)).exp();
                num += w * v;
                den += w;
            }
            pixels.push((nearest.sqrt() <= FILTER_REACH && den > 0.0).then(|| num / den));
        }
    }
    Some(GridImage { rows, cols, pixels })
}

/// A patch, the bases its code uses and their coefficients, and the reconstruction
/// (Fig. 2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reconstruction {
    pub grasp: usize,
    pub sensor: usize,
    pub failure: bool,
    pub patch: Vec<f64>,
    /// (basis, coefficient), largest |coefficient| first.
    pub terms: Vec<(usize, f64)>,
    pub reconstruction: Vec<f64>,
    /// ||patch − reconstruction|| / ||patch||.
    pub relative_error: f64,
}

/// Per-basis statistics by label (success / failure), Figs. 8–11.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BasisUsage {
    /// Share of the label's grasps whose code (any of its patches) uses the basis
    /// (Figs. 8 and 9).
    pub grasp_usage_success: Vec<f64>,
    pub grasp_usage_failure: Vec<f64>,
    /// success − failure (Fig. 10: negative = used more by failed grasps).
    pub usage_differential: Vec<f64>,
    /// Share of the label's patches whose code uses the basis.
    pub patch_usage_success: Vec<f64>,
    pub patch_usage_failure: Vec<f64>,
    /// Mean |coefficient| over the label's patches that use the basis (0 if none).
    pub mean_abs_coef_success: Vec<f64>,
    pub mean_abs_coef_failure: Vec<f64>,
    /// success − failure of the above (Fig. 11: negative = stronger in failed grasps).
    pub coefficient_differential: Vec<f64>,
    /// Mean |coefficient| over all the label's patches (zeros included), and its
    /// differential, for comparison.
    pub mean_abs_coef_all_success: Vec<f64>,
    pub mean_abs_coef_all_failure: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Analyses {
    pub config: Config,
    pub basis_images: Vec<BasisImage>,
    pub filter: String,
    /// One representative patch per label (a patch with the label's typical number of
    /// active bases, the one with the largest norm among those).
    pub reconstructions: Vec<Reconstruction>,
    pub usage: BasisUsage,
    /// Mean non-zero coefficients per patch: all, success, failure (the paper: 4.43 vs 2.59).
    pub active_bases_per_patch: [f64; 3],
    /// Share of zero coefficients: all, success, failure (the paper: 86.31 %).
    pub sparsity: [f64; 3],
}

/// The reconstruction of one patch (grasp g, sensor s) by its code.
pub fn reconstruct(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    grasp: usize,
    sensor: usize,
) -> Result<Reconstruction, StabilityError> {
    if grasp >= data.grasp_count() || sensor >= data.sensor_count() {
        return Err(StabilityError::Param(format!(
            "no patch for grasp {grasp}, sensor {sensor}"
        )));
    }
    let row = grasp * data.sensor_count() + sensor;
    let patch = data.x.row(row);
    let code = dict.encode(data.x.slice(ndarray::s![row..row + 1, ..]), gamma)?;
    Ok(reconstruction_of(
        data,
        dict,
        grasp,
        sensor,
        patch,
        code.row(0),
    ))
}

fn reconstruction_of(
    data: &StabilityData,
    dict: &Dictionary,
    grasp: usize,
    sensor: usize,
    patch: ArrayView1<f64>,
    code: ArrayView1<f64>,
) -> Reconstruction {
    let mut terms: Vec<(usize, f64)> = code
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(j, v)| (j, *v))
        .collect();
    terms.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    let rec = dict.reconstruct(code);
    let err = (&patch - &rec).mapv(|v| v * v).sum().sqrt();
    let nrm = patch.dot(&patch).sqrt();
    Reconstruction {
        grasp,
        sensor,
        failure: data.labels[grasp],
        patch: patch.to_vec(),
        terms,
        reconstruction: rec.to_vec(),
        relative_error: if nrm > 0.0 { err / nrm } else { 0.0 },
    }
}

/// The analyses of a model with dictionary `dict` coded with `gamma`.
pub fn analyse(
    data: &StabilityData,
    config: Config,
    dict: &Dictionary,
) -> Result<Analyses, StabilityError> {
    let codes = dict.encode(data.x.view(), config.gamma)?;
    let k = dict.num_bases();
    let s = data.sensor_count();
    let coords = data.layout.as_ref().map(taxel_coords);
    let basis_images = (0..k)
        .map(|j| {
            let values = dict.atoms.row(j).to_vec();
            BasisImage {
                basis: j,
                raw: data.layout.as_ref().and_then(|l| raw_image(l, &values)),
                filtered: coords.as_ref().and_then(|c| filtered_image(c, &values)),
                values,
            }
        })
        .collect();
    // Usage and coefficients by label.
    let mut grasp_use = [vec![0.0; k], vec![0.0; k]];
    let mut patch_use = [vec![0.0; k], vec![0.0; k]];
    let mut coef_sum = [vec![0.0; k], vec![0.0; k]];
    let mut grasps_of = [0usize; 2];
    let mut active = [0usize; 2];
    for g in 0..data.grasp_count() {
        let l = data.labels[g] as usize;
        grasps_of[l] += 1;
        let mut used = vec![false; k];
        for sn in 0..s {
            let row = codes.row(g * s + sn);
            for (j, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    used[j] = true;
                    patch_use[l][j] += 1.0;
                    coef_sum[l][j] += v.abs();
                    active[l] += 1;
                }
            }
        }
        for j in 0..k {
            if used[j] {
                grasp_use[l][j] += 1.0;
            }
        }
    }
    let div = |v: &[f64], n: f64| -> Vec<f64> {
        v.iter()
            .map(|x| if n > 0.0 { x / n } else { 0.0 })
            .collect()
    };
    let patches_of = [
        grasps_of[0] as f64 * s as f64,
        grasps_of[1] as f64 * s as f64,
    ];
    let mean_abs = |l: usize| -> Vec<f64> {
        (0..k)
            .map(|j| {
                if patch_use[l][j] > 0.0 {
                    coef_sum[l][j] / patch_use[l][j]
                } else {
                    0.0
                }
            })
            .collect()
    };
    let gu = [
        div(&grasp_use[0], grasps_of[0] as f64),
        div(&grasp_use[1], grasps_of[1] as f64),
    ];
    let ma = [mean_abs(0), mean_abs(1)];
    let diff = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>();
    let usage = BasisUsage {
        usage_differential: diff(&gu[0], &gu[1]),
        coefficient_differential: diff(&ma[0], &ma[1]),
        patch_usage_success: div(&patch_use[0], patches_of[0]),
        patch_usage_failure: div(&patch_use[1], patches_of[1]),
        mean_abs_coef_all_success: div(&coef_sum[0], patches_of[0]),
        mean_abs_coef_all_failure: div(&coef_sum[1], patches_of[1]),
        grasp_usage_success: gu[0].clone(),
        grasp_usage_failure: gu[1].clone(),
        mean_abs_coef_success: ma[0].clone(),
        mean_abs_coef_failure: ma[1].clone(),
    };
    let per_patch = |n: usize, p: f64| if p > 0.0 { n as f64 / p } else { 0.0 };
    let all_patches = patches_of[0] + patches_of[1];
    let active_bases_per_patch = [
        per_patch(active[0] + active[1], all_patches),
        per_patch(active[0], patches_of[0]),
        per_patch(active[1], patches_of[1]),
    ];
    let sparsity = active_bases_per_patch.map(|a| 1.0 - a / k as f64);
    // A representative patch per label.
    let mut reconstructions = Vec::new();
    for l in [false, true] {
        let typical = active_bases_per_patch[1 + l as usize].round() as usize;
        let pick = (0..data.x.nrows())
            .filter(|&r| data.labels[r / s] == l)
            .map(|r| {
                let nz = codes.row(r).iter().filter(|v| **v != 0.0).count();
                let nrm = data.x.row(r).dot(&data.x.row(r));
                (nz.abs_diff(typical), -nrm, r)
            })
            .min_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        if let Some((_, _, r)) = pick {
            reconstructions.push(reconstruction_of(
                data,
                dict,
                r / s,
                r % s,
                data.x.row(r),
                codes.row(r),
            ));
        }
    }
    Ok(Analyses {
        config,
        basis_images,
        filter: FILTER.into(),
        reconstructions,
        usage,
        active_bases_per_patch,
        sparsity,
    })
}

/// Every grasp as a model sees it: each patch coded on `dict` with `gamma`, its
/// reconstruction, and the prediction and decision value of the cross validation `cv` (run
/// on these codes) from the fold that tested the grasp.
pub fn grasp_codes(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    cv: &CvResult,
) -> Result<Vec<GraspCode>, StabilityError> {
    let n = data.grasp_count();
    if cv.predictions.len() != n || cv.decisions.len() != n {
        return Err(StabilityError::Data(format!(
            "a cross validation of {} grasps for {n} grasps",
            cv.predictions.len()
        )));
    }
    let codes = dict.encode(data.x.view(), gamma)?;
    let s = data.sensor_count();
    let class = |failure: bool| {
        if failure {
            data.failure_name.clone()
        } else {
            data.success_name.clone()
        }
    };
    Ok((0..n)
        .map(|g| GraspCode {
            grasp: data.grasp_ids[g],
            truth: class(data.labels[g]),
            predicted: class(cv.predictions[g]),
            decision: cv.decisions[g],
            patches: (0..s)
                .map(|sensor| {
                    let r = g * s + sensor;
                    let rec = reconstruction_of(data, dict, g, sensor, data.x.row(r), codes.row(r));
                    PatchCode {
                        sensor,
                        patch: rec.patch,
                        terms: rec.terms,
                        reconstruction: rec.reconstruction,
                        relative_error: rec.relative_error,
                    }
                })
                .collect(),
        })
        .collect())
}

// ---------------------------------------------------------------------------------------
// The whole pipeline
// ---------------------------------------------------------------------------------------

/// What to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StabilityOptions {
    pub settings: PipelineSettings,
    /// Protocol of the grid's selection.
    pub selection_cv: CvScheme,
    /// The two protocols every chosen model and the baseline are reported under.
    pub kfold: CvScheme,
    pub objects: CvScheme,
    /// The grid (None: evaluate `single` only).
    pub grid: Option<GridSpec>,
    /// The configuration evaluated when there is no grid.
    pub single: Config,
    /// Protocols under which the grid's selection is also scored by nested cross
    /// validation (none by default: it costs about ten grid searches each).
    #[serde(default)]
    pub nested: Vec<CvScheme>,
    /// Why `single` has its size, when the caller knows (a frontier's recommendation);
    /// None: judged from the options (a grid's choice is recommended, the paper's
    /// configuration is the default, any other the user's).
    #[serde(default)]
    pub size_reason: Option<SizeReason>,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        StabilityOptions {
            settings: PipelineSettings::default(),
            selection_cv: CvScheme::KFold { k: 10 },
            kfold: CvScheme::KFold { k: 10 },
            objects: CvScheme::LeaveObjectsOut { folds: None },
            grid: None,
            single: Config {
                num_bases: 29,
                beta: 1.0,
                gamma: 1.0,
            },
            nested: Vec::new(),
            size_reason: None,
        }
    }
}

/// Machine-readable results of the pipeline on one session.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StabilityReport {
    pub session: String,
    pub grasps: usize,
    pub objects: usize,
    pub failures: usize,
    pub sensors: usize,
    pub patch_dim: usize,
    pub label_set: String,
    pub success_class: String,
    pub failure_class: String,
    pub scaling: String,
    pub convention: String,
    pub options: StabilityOptions,
    pub selection_cv: String,
    pub kfold_cv: String,
    pub objects_cv: String,
    pub grid: Option<GridResult>,
    /// The best configuration (the grid's best cell, or the single configuration).
    pub best: Evaluation,
    /// The parsimonious choice (equal to `best` without a grid).
    pub parsimonious: Evaluation,
    pub baseline: Baseline,
    /// Analyses of the recommended (parsimonious) model.
    pub analyses: Analyses,
    /// The recommended model trained on every grasp.
    pub model: StabilityModel,
    /// Index into `Session::grasps` of every grasp, in the order of the cross validations'
    /// predictions.
    #[serde(default)]
    pub grasp_ids: Vec<usize>,
    /// true = failure, per grasp (in the order of `grasp_ids`).
    #[serde(default)]
    pub labels: Vec<bool>,
    /// Every grasp as the recommended model sees it, with its k-fold prediction.
    #[serde(default)]
    pub grasp_codes: Vec<GraspCode>,
    /// The grid's selection scored by nested cross validation, per protocol of
    /// `options.nested` (empty without a grid).
    #[serde(default)]
    pub nested: Vec<NestedResult>,
    pub secs: f64,
}

/// Run the pipeline: the grid (if any), evaluation of the best and the parsimonious
/// configurations under both protocols, the raw baseline, the analyses and the final
/// model.
pub fn run(
    data: &StabilityData,
    opts: &StabilityOptions,
    progress: &Progress,
) -> Result<StabilityReport, StabilityError> {
    let start = Instant::now();
    let grid = match &opts.grid {
        Some(spec) => Some(grid_search(
            data,
            spec,
            &opts.settings,
            opts.selection_cv,
            progress,
        )?),
        None => None,
    };
    finish(data, opts, grid, start, progress)
}

/// The pipeline after the grid (if any): evaluation of the best and the parsimonious
/// configurations under both protocols, the raw baseline, the analyses and the final
/// model. `start` is when the run began (for the report's seconds).
pub fn finish(
    data: &StabilityData,
    opts: &StabilityOptions,
    grid: Option<GridResult>,
    start: Instant,
    progress: &Progress,
) -> Result<StabilityReport, StabilityError> {
    let s = &opts.settings;
    progress.set(1.0, "evaluating the chosen models");
    let (best_cfg, best_dict, pars_cfg, pars_dict) = match &grid {
        Some(g) => (
            g.best.config,
            Some(g.best_dictionary.clone()),
            g.parsimonious.config,
            Some(g.parsimonious_dictionary.clone()),
        ),
        None => (opts.single, None, opts.single, None),
    };
    let (mut best, bd) = evaluate_config(
        data,
        best_cfg,
        s,
        opts.kfold,
        opts.objects,
        best_dict,
        progress,
    )?;
    let (parsimonious, pd) = if pars_cfg == best_cfg {
        (best.clone(), bd.clone())
    } else {
        evaluate_config(
            data,
            pars_cfg,
            s,
            opts.kfold,
            opts.objects,
            pars_dict,
            progress,
        )?
    };
    // Keep the learning statistics of the grid's cells where they exist.
    if let Some(g) = &grid {
        best.dictionary_iterations = g.best.dictionary_iterations;
        best.dictionary_secs = g.best.dictionary_secs;
    }
    let mut parsimonious = parsimonious;
    if let Some(g) = &grid {
        parsimonious.dictionary_iterations = g.parsimonious.dictionary_iterations;
        parsimonious.dictionary_secs = g.parsimonious.dictionary_secs;
    }
    let baseline = baseline(data, s, opts.kfold, opts.objects)?;
    let nested = match &opts.grid {
        Some(spec) => opts
            .nested
            .iter()
            .map(|&protocol| nested_cv(data, spec, s, protocol, progress))
            .collect::<Result<Vec<_>, _>>()?,
        None => Vec::new(),
    };
    let analyses = analyse(data, pars_cfg, &pd)?;
    let codes = grasp_codes(data, &pd, pars_cfg.gamma, &parsimonious.kfold)?;
    let model = StabilityModel::train(data, pars_cfg, pd, &s.svm)?;
    Ok(StabilityReport {
        session: data.session_name.clone(),
        grasps: data.grasp_count(),
        objects: data.object_names.len(),
        failures: data.labels.iter().filter(|l| **l).count(),
        sensors: data.sensor_count(),
        patch_dim: data.dim(),
        label_set: data.label_set.clone(),
        success_class: data.success_name.clone(),
        failure_class: data.failure_name.clone(),
        scaling: match data.patches.scaling {
            PatchScaling::ZScorePerTaxel => {
                "pressures (through each sensor's value transform) z-scored per taxel over all grasps of the session; the same scaling is applied at prediction".into()
            }
            PatchScaling::None => "pressures as recorded through each sensor's value transform (no scaling)".into(),
        },
        convention: CONVENTION.into(),
        options: opts.clone(),
        selection_cv: opts.selection_cv.describe(),
        kfold_cv: opts.kfold.describe(),
        objects_cv: opts.objects.describe(),
        grid,
        best,
        parsimonious,
        baseline,
        analyses,
        model,
        grasp_ids: data.grasp_ids.clone(),
        labels: data.labels.clone(),
        grasp_codes: codes,
        nested,
        secs: start.elapsed().as_secs_f64(),
    })
}
