//! The `stability` command line: its arguments, and the pipeline's options they give.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};

use crate::experiments::stability::{
    Config, CvScheme, DataOptions, GridSpec, PipelineInputs, PipelineSettings, StabilityData,
    StabilityOptions,
};
use crate::features::PatchScaling;
use crate::sparse::{CodePenalty, DictInit, DictionaryParams};
use crate::svm::{LinearSvmParams, Loss};

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum GridPreset {
    /// num_bases 2..=60 × beta, gamma ∈ {0.25, 0.5, 1, 2, 4} (scaled to the data when
    /// patches are not z-scored).
    Default,
    /// The benchmark grid: num_bases 5..=60 step 5 × beta, gamma ∈ {0.5, 1, 2}.
    Bench,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum LossArg {
    Hinge,
    SquaredHinge,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PenaltyArg {
    L1,
    EpsL1,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum InputsArg {
    /// The patches' sparse codes side by side (the first paper).
    Codes,
    /// The codes followed by the scaled key-frame values (docs/held-out.md).
    #[value(name = "codes+raw")]
    CodesRaw,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum InitArg {
    Svd,
    Patches,
    Random,
}

#[derive(Args, Debug)]
pub struct StabilityArgs {
    /// A native session file, or the BTS3 CSV (imported on the fly).
    pub session: PathBuf,
    /// Protocol of the grid's model selection: `10` (stratified k-fold, any k), `objects`
    /// (leave one object out) or `objects:K` (K folds by object).
    #[arg(long, default_value = "10")]
    pub cv: String,
    /// Run a grid search: a preset, refined by --num-bases/--beta/--gamma. Without it (and
    /// with single values) one configuration is evaluated.
    #[arg(long, value_enum)]
    pub grid: Option<GridPreset>,
    /// Dictionary sizes: a list `10,20,29` and/or ranges `5..60` or `5..60:5` (inclusive).
    #[arg(long)]
    pub num_bases: Option<String>,
    /// Sparsity penalties while learning (scikit-learn convention), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub beta: Option<Vec<f64>>,
    /// Sparsity penalties when coding, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub gamma: Option<Vec<f64>>,
    /// Write the machine-readable results here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also save the recommended model as a model file (`evaluate`, `predict`).
    #[arg(long, value_name = "MODEL.json")]
    pub save_model: Option<PathBuf>,
    /// With a grid: also score its selection by nested cross validation, under stratified
    /// 10-fold and 10 folds by object (outer and inner folds alike); about ten grid
    /// searches each.
    #[arg(long, requires = "grid")]
    pub nested: bool,
    /// Label set holding the grasp outcome.
    #[arg(long)]
    pub label_set: Option<String>,
    /// Class meaning a failed grasp.
    #[arg(long)]
    pub failure_class: Option<String>,
    /// Use pressures as they are instead of z-scoring each taxel over the session.
    #[arg(long)]
    pub no_scaling: bool,
    /// Seed of the dictionary start, the SVM and the folds.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// SVM penalty C.
    #[arg(long, default_value_t = 1.0)]
    pub svm_c: f64,
    #[arg(long, value_enum, default_value = "squared-hinge")]
    pub loss: LossArg,
    /// What the SVM reads of a grasp.
    #[arg(long, value_enum, default_value = "codes")]
    pub inputs: InputsArg,
    /// Penalty while learning: L1 (exact feature-sign codes) or the paper's epsilon-L1.
    #[arg(long, value_enum, default_value = "l1")]
    pub learn_penalty: PenaltyArg,
    /// ε of the epsilon-L1 penalty.
    #[arg(long, default_value_t = 0.01)]
    pub epsilon: f64,
    #[arg(long, value_enum, default_value = "svd")]
    pub init: InitArg,
    /// Dictionary learning stops when the objective's relative decrease per iteration
    /// falls below this.
    #[arg(long, default_value_t = 1e-5)]
    pub tol: f64,
    #[arg(long, default_value_t = 100)]
    pub max_iter: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Parse `10` or `objects` or `objects:K`.
pub fn parse_cv(s: &str) -> anyhow::Result<CvScheme> {
    let s = s.trim();
    if s == "objects" {
        return Ok(CvScheme::LeaveObjectsOut { folds: None });
    }
    if let Some(k) = s.strip_prefix("objects:") {
        let k: usize = k
            .parse()
            .with_context(|| format!("bad fold count in --cv {s:?}"))?;
        return Ok(CvScheme::LeaveObjectsOut { folds: Some(k) });
    }
    let k: usize = s
        .parse()
        .with_context(|| format!("--cv takes a fold count, `objects` or `objects:K`, not {s:?}"))?;
    Ok(CvScheme::KFold { k })
}

/// Parse `10,20,29` / `5..60` / `5..60:5` (inclusive ranges; items may be mixed).
pub fn parse_num_bases(s: &str) -> anyhow::Result<Vec<usize>> {
    let mut out = Vec::new();
    for item in s.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        if let Some((a, rest)) = item.split_once("..") {
            let (b, step) = rest.split_once(':').unwrap_or((rest, "1"));
            let bad = || format!("bad range {item:?} (expected A..B or A..B:STEP)");
            let (a, b, step): (usize, usize, usize) = (
                a.parse().with_context(bad)?,
                b.trim_start_matches('=').parse().with_context(bad)?,
                step.parse().with_context(bad)?,
            );
            if step == 0 || a > b {
                bail!("bad range {item:?}");
            }
            out.extend((a..=b).step_by(step));
        } else {
            out.push(
                item.parse()
                    .with_context(|| format!("bad num_bases {item:?}"))?,
            );
        }
    }
    if out.is_empty() {
        bail!("--num-bases is empty");
    }
    crate::cli::bounds::all_at_most("--num-bases", &out, crate::cli::bounds::MAX_NUM_BASES)?;
    Ok(out)
}

fn settings_from(a: &StabilityArgs) -> PipelineSettings {
    PipelineSettings {
        dictionary: DictionaryParams {
            penalty: match a.learn_penalty {
                PenaltyArg::L1 => CodePenalty::L1,
                PenaltyArg::EpsL1 => CodePenalty::EpsilonL1 { epsilon: a.epsilon },
            },
            init: match a.init {
                InitArg::Svd => DictInit::Svd,
                InitArg::Patches => DictInit::Patches,
                InitArg::Random => DictInit::Random,
            },
            tol: a.tol,
            max_iter: a.max_iter,
            seed: a.seed,
            ..Default::default()
        },
        svm: LinearSvmParams {
            c: a.svm_c,
            loss: match a.loss {
                LossArg::Hinge => Loss::Hinge,
                LossArg::SquaredHinge => Loss::SquaredHinge,
            },
            seed: a.seed,
            ..Default::default()
        },
        inputs: match a.inputs {
            InputsArg::Codes => PipelineInputs::Codes,
            InputsArg::CodesRaw => PipelineInputs::CodesAndRaw,
        },
        cv_seed: a.seed,
    }
}

/// Options of the run from the arguments (needs the data for the default grid).
pub fn options_from(a: &StabilityArgs, data: &StabilityData) -> anyhow::Result<StabilityOptions> {
    let num_bases = a.num_bases.as_deref().map(parse_num_bases).transpose()?;
    let many = |v: &Option<Vec<f64>>| v.as_ref().is_some_and(|v| v.len() > 1);
    let grid = if a.grid.is_some()
        || num_bases.as_ref().is_some_and(|v| v.len() > 1)
        || many(&a.beta)
        || many(&a.gamma)
    {
        let mut spec = match a.grid {
            Some(GridPreset::Bench) => GridSpec::bench(),
            _ => GridSpec::default_for(data),
        };
        if let Some(k) = &num_bases {
            spec.num_bases = k.clone();
        }
        if let Some(b) = &a.beta {
            spec.beta = b.clone();
        }
        if let Some(g) = &a.gamma {
            spec.gamma = g.clone();
        }
        spec.validate()?;
        Some(spec)
    } else {
        None
    };
    let single = Config {
        num_bases: num_bases.as_ref().map_or(29, |v| v[0]),
        beta: a.beta.as_ref().map_or(1.0, |v| v[0]),
        gamma: a.gamma.as_ref().map_or(1.0, |v| v[0]),
    };
    Ok(StabilityOptions {
        settings: settings_from(a),
        selection_cv: parse_cv(&a.cv)?,
        grid,
        single,
        nested: if a.nested {
            vec![
                CvScheme::KFold { k: 10 },
                CvScheme::LeaveObjectsOut { folds: Some(10) },
            ]
        } else {
            Vec::new()
        },
        ..StabilityOptions::default()
    })
}

/// Which labels and scaling the arguments ask for.
pub fn data_options(a: &StabilityArgs) -> DataOptions {
    DataOptions {
        label_set: a.label_set.clone(),
        failure_class: a.failure_class.clone(),
        scaling: if a.no_scaling {
            PatchScaling::None
        } else {
            PatchScaling::ZScorePerTaxel
        },
    }
}
