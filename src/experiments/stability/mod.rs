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

use crate::error::MethodError;
use crate::experiments::links::{GraspCode, PatchCode};
use crate::experiments::result::SizeReason;
use crate::features::{KeyFramePatches, PatchError, PatchScaling, Standardizer};
use crate::jobs::Progress;
use crate::session::{Layout, Session};
use crate::sparse::{Dictionary, DictionaryParams, SparseError};
use crate::svm::{
    Confusion, CvResult, Folds, LinearSvm, LinearSvmParams, SvmError, cross_validate, group_k_fold,
    stratified_k_fold,
};

mod analyses;
mod data;
mod grid;
mod model;
mod nested;
pub mod report;

pub use analyses::*;
pub use data::*;
pub use grid::*;
pub use model::*;
pub use nested::*;

pub const CONVENTION: &str = "F = (1/N) Σ_i [0.5 ||x_i − a_i D||² + λ ||a_i||₁], ||d_j||² ≤ 1; \
λ = beta while learning the dictionary, λ = gamma when coding (scikit-learn's convention; \
a penalty written without the 0.5, as in the paper's eqs. 2–3, is twice these values)";

/// Why the stability pipeline failed: its patches, the sparse coder or the SVM (each error
/// kept as the source), or the pipeline's own parameters, data or a cancel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StabilityError {
    #[error("{0}")]
    Patch(#[from] PatchError),
    #[error("sparse coding: {0}")]
    Sparse(#[source] SparseError),
    #[error("SVM: {0}")]
    Svm(#[source] SvmError),
    /// The pipeline's own refusal (its parameters or data), or a cancel from any stage.
    #[error("{0}")]
    Method(#[source] MethodError),
}

impl StabilityError {
    pub(crate) fn param(reason: String) -> StabilityError {
        StabilityError::Method(MethodError::Param(reason))
    }

    pub(crate) fn data(reason: String) -> StabilityError {
        StabilityError::Method(MethodError::Data(reason))
    }

    /// A sparse coder's error; a cancel stays a cancel.
    pub(crate) fn sparse(e: SparseError) -> StabilityError {
        match e {
            MethodError::Cancelled => StabilityError::Method(e),
            e => StabilityError::Sparse(e),
        }
    }

    /// An SVM's error; a cancel stays a cancel.
    pub(crate) fn svm(e: SvmError) -> StabilityError {
        match e {
            MethodError::Cancelled => StabilityError::Method(e),
            e => StabilityError::Svm(e),
        }
    }

    pub fn is_cancelled(&self) -> bool {
        matches!(self, StabilityError::Method(MethodError::Cancelled))
    }
}

impl From<crate::jobs::Cancelled> for StabilityError {
    fn from(_: crate::jobs::Cancelled) -> Self {
        StabilityError::Method(MethodError::Cancelled)
    }
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
            CvScheme::KFold { k } => {
                stratified_k_fold(&data.labels, k, seed).map_err(StabilityError::svm)?
            }
            CvScheme::LeaveObjectsOut { folds } => {
                group_k_fold(&data.objects, folds, seed).map_err(StabilityError::svm)?
            }
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
    /// What the SVM reads (older results, without the field, read codes).
    #[serde(default)]
    pub inputs: PipelineInputs,
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
            inputs: PipelineInputs::Codes,
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
    let nz = codes.iter().map(|v| usize::from(*v != 0.0)).sum::<usize>() as f64;
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

/// What [`score_codes`] leaves: the SVM's features, the codes' sparsity and active bases
/// per patch ([`sparsity_of`]), the cross validation and the seconds of coding and of
/// cross-validating.
struct ScoredCodes {
    features: Array2<f64>,
    sparsity: (f64, f64),
    cv: CvResult,
    coding_secs: f64,
    cv_secs: f64,
}

/// Code every patch with `gamma` and cross-validate the SVM on the grasp features.
fn score_codes(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    folds: &Folds,
    settings: &PipelineSettings,
) -> Result<ScoredCodes, StabilityError> {
    let t0 = Instant::now();
    let codes = dict
        .encode(data.x.view(), gamma)
        .map_err(StabilityError::sparse)?;
    let coding_secs = t0.elapsed().as_secs_f64();
    let sparsity = sparsity_of(codes.view());
    let t1 = Instant::now();
    let features = data.features(codes, settings.inputs);
    let cv = cross_validate(features.view(), &data.labels, folds, &settings.svm)
        .map_err(StabilityError::svm)?;
    Ok(ScoredCodes {
        features,
        sparsity,
        cv,
        coding_secs,
        cv_secs: t1.elapsed().as_secs_f64(),
    })
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
    // After a grid, evaluating the chosen configurations under both protocols takes about
    // two fifths of the run (benches/estimates.rs): it gets that share of the progress.
    let parts = progress.parts(&[if opts.grid.is_some() { 1.5 } else { 0.0 }, 1.0]);
    let grid = match &opts.grid {
        Some(spec) => Some(grid_search(
            data,
            spec,
            &opts.settings,
            opts.selection_cv,
            &parts[0],
        )?),
        None => None,
    };
    finish(data, opts, grid, start, &parts[1])
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
    progress.set(0.0, "evaluating the chosen models");
    let (best_cfg, best_dict, pars_cfg, pars_dict) = match &grid {
        Some(g) => (
            g.best.config,
            Some(g.best_dictionary.clone()),
            g.parsimonious.config,
            Some(g.parsimonious_dictionary.clone()),
        ),
        None => (opts.single, None, opts.single, None),
    };
    // The best and the parsimonious configuration cost alike (one when they are the same).
    let parts = progress.parts(&[1.0, if pars_cfg == best_cfg { 0.0 } else { 1.0 }]);
    let (mut best, bd) = evaluate_config(
        data,
        best_cfg,
        s,
        opts.kfold,
        opts.objects,
        best_dict,
        &parts[0],
    )?;
    parts[0].set_fraction(1.0);
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
            &parts[1],
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
    let model = StabilityModel::train(data, pars_cfg, pd, s)?;
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
