//! `stability` (the first paper's pipeline on any session) and `bench-stability` (its
//! speed on BTS3 palm-down).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;

use super::progress::with_progress;
use crate::experiments::stability::{
    self, Config, CvScheme, DataOptions, GridSpec, PipelineSettings, StabilityData,
    StabilityOptions, StabilityReport,
};
use crate::features::PatchScaling;
use crate::jobs::Progress;
use crate::session::{self, Session};
use crate::sparse::{CodePenalty, DictInit, Dictionary, DictionaryParams, FeatureSign};
use crate::svm::{LinearSvmParams, Loss, cross_validate, stratified_k_fold};

/// Where the real BTS3 set lives beside the project checkout.
pub const BTS3_CSV: &str = "../shared/datasets/bts3/biotac-palmdown-grasps.csv";

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

/// Open a native session, or import the BTS3 CSV.
pub fn open(path: &Path) -> anyhow::Result<Session> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        session::import_bts3(path).with_context(|| format!("importing {}", path.display()))
    } else {
        session::load(path).with_context(|| format!("loading {}", path.display()))
    }
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
    super::bounds::all_at_most("--num-bases", &out, super::bounds::MAX_NUM_BASES)?;
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

fn pct(v: f64) -> String {
    format!("{:.2} %", 100.0 * v)
}

/// The human-readable summary of a report.
pub fn report(r: &StabilityReport) -> String {
    let mut out = String::new();
    let mut line = |s: String| {
        out.push_str(&s);
        out.push('\n');
    };
    line(format!(
        "{}: {} grasps ({} {}), {} objects, {} sensors × {} taxels",
        r.session, r.grasps, r.failures, r.failure_class, r.objects, r.sensors, r.patch_dim
    ));
    line(format!("scaling: {}", r.scaling));
    line(format!("objective: {}", r.convention));
    if let Some(g) = &r.grid {
        line(format!(
            "grid: {} cells ({} num_bases × {} beta × {} gamma), selection by {}, {:.1} s on {} threads",
            g.cells.len(),
            g.spec.num_bases.len(),
            g.spec.beta.len(),
            g.spec.gamma.len(),
            r.selection_cv,
            g.secs,
            g.threads
        ));
        line("best per num_bases (Fig. 5):  K    beta   gamma   WSR       ± SE     failure recall  sparsity   F".into());
        for c in &g.best_per_num_bases {
            line(format!(
                "                             {:>3}  {:>5}  {:>5}   {:>8}  {:>6.2}   {:>8}        {:>8}   {:.4}",
                c.config.num_bases,
                c.config.beta,
                c.config.gamma,
                pct(c.weighted_success_rate),
                100.0 * c.fold_wsr_se,
                pct(c.failure_recall),
                pct(c.sparsity),
                c.dictionary_objective
            ));
        }
    }
    for (name, e) in [("best", &r.best), ("parsimonious", &r.parsimonious)] {
        if name == "parsimonious" && r.grid.is_none() {
            break;
        }
        line(format!(
            "{name} ({}): F = {:.4} ({} iterations, {:.2} s), sparsity {}, {:.2} active bases per patch",
            e.config,
            e.dictionary_objective,
            e.dictionary_iterations,
            e.dictionary_secs,
            pct(e.sparsity),
            e.active_bases_per_patch
        ));
        line(format!(
            "    {}: weighted success rate {}, failure recall {}",
            r.kfold_cv,
            pct(e.kfold.weighted_success_rate),
            pct(e.kfold.failure_recall)
        ));
        line(format!(
            "    {}: weighted success rate {}, failure recall {}",
            r.objects_cv,
            pct(e.objects.weighted_success_rate),
            pct(e.objects.failure_recall)
        ));
    }
    line(format!(
        "baseline (linear SVM on the {} scaled raw values): {} {} / {}; {} {} / {}  (WSR / failure recall)",
        r.baseline.features,
        r.kfold_cv,
        pct(r.baseline.kfold.weighted_success_rate),
        pct(r.baseline.kfold.failure_recall),
        r.objects_cv,
        pct(r.baseline.objects.weighted_success_rate),
        pct(r.baseline.objects.failure_recall)
    ));
    for n in &r.nested {
        line(format!(
            "{} ({:.1} s): WSR {} (per fold {} ± {:.2}), failure recall {}; raw linear SVM, same outer folds: WSR {}, failure recall {}",
            n.description,
            n.secs,
            pct(n.weighted_success_rate),
            pct(n.fold_wsr_mean),
            100.0 * n.fold_wsr_se,
            pct(n.failure_recall),
            pct(n.raw_weighted_success_rate),
            pct(n.raw_failure_recall)
        ));
        for f in &n.folds {
            line(format!(
                "    outer fold {:>2}: chose {} (inner WSR {}; inner best {} at {}); outer test WSR {}, raw {}",
                f.fold,
                f.chosen,
                pct(f.chosen_inner_wsr),
                f.best,
                pct(f.best_inner_wsr),
                f.weighted_success_rate.map_or("n/a".into(), pct),
                f.raw_weighted_success_rate.map_or("n/a".into(), pct)
            ));
        }
    }
    let a = &r.analyses;
    line(format!(
        "analyses of the recommended model: active bases per patch {:.2} ({} {:.2}, {} {:.2}); sparsity {} ({} {}, {} {})",
        a.active_bases_per_patch[0],
        r.success_class,
        a.active_bases_per_patch[1],
        r.failure_class,
        a.active_bases_per_patch[2],
        pct(a.sparsity[0]),
        r.success_class,
        pct(a.sparsity[1]),
        r.failure_class,
        pct(a.sparsity[2])
    ));
    line(format!("total {:.1} s", r.secs));
    out
}

pub(crate) fn in_pool<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    match threads {
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()?
            .install(f)),
        None => Ok(f()),
    }
}

fn write_json(path: &Path, value: &impl Serialize) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    crate::fsutil::write_atomic(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
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

pub fn run(a: StabilityArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    super::refuse_input_as_output(a.save_model.as_deref(), &[&a.session])?;
    let session = open(&a.session)?;
    let data = StabilityData::from_session(&session, &data_options(&a))?;
    let opts = options_from(&a, &data)?;
    let report = in_pool(a.threads, || {
        with_progress(a.quiet, |p| stability::run(&data, &opts, p))
    })??;
    print!("{}", self::report(&report));
    if let Some(path) = &a.json {
        write_json(path, &report)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &a.save_model {
        let file =
            crate::models::stability::StabilityFit::from_report(&session, &data, &opts, &report)
                .into_file(&session, &data);
        crate::models::save(&file, path)?;
        println!("wrote {} ({})", path.display(), file.provenance.summary());
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// bench-stability
// ---------------------------------------------------------------------------------------

#[derive(Args, Debug)]
pub struct BenchStabilityArgs {
    /// The BTS3 palm-down CSV (or a native session).
    #[arg(default_value = BTS3_CSV)]
    pub session: PathBuf,
    /// Repetitions of the single-step timings (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Skip the 108-cell grid.
    #[arg(long)]
    pub skip_grid: bool,
    /// Skip the scaling studies (K and number of grasps).
    #[arg(long)]
    pub skip_scaling: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Wall and CPU seconds of a piece of work.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Timing {
    pub wall_secs: f64,
    /// User + system CPU seconds of the whole process over the same span (Linux
    /// /proc/self/stat; NaN elsewhere): on a shared machine this is the honest measure.
    pub cpu_secs: f64,
}

fn cpu_now() -> f64 {
    // utime and stime are fields 14 and 15, in clock ticks (100 per second on Linux).
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            let u: f64 = f.get(11)?.parse().ok()?;
            let k: f64 = f.get(12)?.parse().ok()?;
            Some((u + k) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Timing) {
    let (c0, t0) = (cpu_now(), Instant::now());
    let out = f();
    (
        out,
        Timing {
            wall_secs: t0.elapsed().as_secs_f64(),
            cpu_secs: cpu_now() - c0,
        },
    )
}

fn median(mut v: Vec<Timing>) -> Timing {
    v.sort_by(|a, b| a.wall_secs.total_cmp(&b.wall_secs));
    v[v.len() / 2]
}

#[derive(Clone, Debug, Serialize)]
pub struct ScalingPoint {
    pub num_bases: usize,
    pub grasps: usize,
    pub dictionary: Timing,
    pub dictionary_iterations: usize,
    pub objective: f64,
    pub coding: Timing,
    pub cv: Timing,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub session: String,
    pub grasps: usize,
    pub patches: usize,
    pub threads: usize,
    /// /proc/loadavg at the start and the end (the machine may be shared).
    pub load_average: [String; 2],
    /// K = 29, λ = 1: time until the objective first reached F ≤ 5.38, and the whole fit.
    pub dictionary_to_target: Timing,
    pub dictionary_to_target_iterations: usize,
    pub dictionary_full: Timing,
    pub dictionary_iterations: usize,
    pub dictionary_objective: f64,
    /// All patches coded with γ = 1 by feature-sign search.
    pub coding: Timing,
    /// One feature-sign solve per patch (the same coding, one thread).
    pub feature_sign: SolveTimes,
    /// One stratified 10-fold cross validation of the linear SVM on the K = 29 codes.
    pub cv_10fold: Timing,
    pub cv_wsr: f64,
    /// The 108-configuration grid with 10-fold CV, end to end.
    pub grid: Option<Timing>,
    pub grid_best: Option<Config>,
    pub grid_best_wsr: Option<f64>,
    pub scaling_k: Vec<ScalingPoint>,
    pub scaling_grasps: Vec<ScalingPoint>,
}

/// Quantiles over patches of the time of one feature-sign solve from the zero code.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SolveTimes {
    /// Solves timed (patches × repeats).
    pub solves: usize,
    pub median_us: f64,
    pub p10_us: f64,
    pub p90_us: f64,
    /// Mean number of non-zero coefficients of the codes.
    pub mean_active: f64,
}

/// Time every patch's feature-sign solve (K bases of `dict`, penalty `gamma`) on this
/// thread, `repeats` times over, each from the zero code as `encode` starts.
fn feature_sign_times(
    dict: &Dictionary,
    x: ndarray::ArrayView2<f64>,
    gamma: f64,
    repeats: usize,
) -> SolveTimes {
    let d = &dict.atoms;
    let k = d.nrows();
    let g: Vec<f64> = d.dot(&d.t()).iter().copied().collect();
    let c: Vec<f64> = x.dot(&d.t()).iter().copied().collect();
    let mut fs = FeatureSign::new(k);
    let mut a = vec![0.0; k];
    let mut us = Vec::with_capacity(repeats * x.nrows());
    let mut active = 0usize;
    for _ in 0..repeats {
        for ci in c.chunks_exact(k) {
            a.fill(0.0);
            let t0 = Instant::now();
            fs.solve(&g, ci, gamma, &mut a);
            us.push(t0.elapsed().as_secs_f64() * 1e6);
            active += a.iter().filter(|v| **v != 0.0).count();
        }
    }
    us.sort_by(f64::total_cmp);
    let q = |f: f64| us[((us.len() - 1) as f64 * f).round() as usize];
    SolveTimes {
        solves: us.len(),
        median_us: q(0.5),
        p10_us: q(0.1),
        p90_us: q(0.9),
        mean_active: active as f64 / us.len() as f64,
    }
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

fn scaling_point(
    data: &StabilityData,
    k: usize,
    settings: &PipelineSettings,
) -> anyhow::Result<ScalingPoint> {
    let params = DictionaryParams {
        num_bases: k,
        beta: 1.0,
        ..settings.dictionary.clone()
    };
    let (fit, dictionary) = timed(|| params.fit(data.x.view(), &Progress::new()));
    let fit = fit?;
    let (codes, coding) = timed(|| fit.dictionary.encode(data.x.view(), 1.0));
    let features = stability::concatenated_codes(codes?, data.sensor_count());
    let folds = stratified_k_fold(&data.labels, 10, 0)?;
    let (cv, cv_t) = timed(|| cross_validate(features.view(), &data.labels, &folds, &settings.svm));
    cv?;
    Ok(ScalingPoint {
        num_bases: k,
        grasps: data.grasp_count(),
        dictionary,
        dictionary_iterations: fit.iterations,
        objective: fit.objective,
        coding,
        cv: cv_t,
    })
}

pub fn bench(a: &BenchStabilityArgs) -> anyhow::Result<BenchReport> {
    let session = open(&a.session)?;
    let data = StabilityData::from_session(&session, &DataOptions::default())?;
    let settings = PipelineSettings::default();
    let load0 = load_average();
    let repeats = a.repeats.max(1);
    // Dictionary learning K = 29, λ = 1.
    let params = DictionaryParams {
        num_bases: 29,
        beta: 1.0,
        ..settings.dictionary.clone()
    };
    let mut fits = Vec::new();
    let mut to_target = Vec::new();
    let mut full = Vec::new();
    for _ in 0..repeats {
        let (fit, t) = timed(|| params.fit(data.x.view(), &Progress::new()));
        let fit = fit?;
        let hit = fit.history.iter().find(|h| h.objective_after_codes <= 5.38);
        // Wall time to the target from the learner's own clock; CPU in proportion.
        let wall = hit.map_or(f64::NAN, |h| h.secs);
        let cpu = t.cpu_secs * wall / fit.secs.max(1e-12);
        to_target.push(Timing {
            wall_secs: wall,
            cpu_secs: cpu,
        });
        full.push(t);
        fits.push(fit);
    }
    let fit = fits.pop().expect("at least one repeat");
    let target_iterations = fit
        .history
        .iter()
        .find(|h| h.objective_after_codes <= 5.38)
        .map_or(0, |h| h.iteration);
    // Coding.
    let mut coding = Vec::new();
    let mut codes = None;
    for _ in 0..repeats {
        let (c, t) = timed(|| fit.dictionary.encode(data.x.view(), 1.0));
        codes = Some(c?);
        coding.push(t);
    }
    let features = stability::concatenated_codes(codes.expect("coded"), data.sensor_count());
    let feature_sign = feature_sign_times(&fit.dictionary, data.x.view(), 1.0, repeats);
    // One 10-fold CV.
    let folds = stratified_k_fold(&data.labels, 10, 0)?;
    let mut cvs = Vec::new();
    let mut wsr = f64::NAN;
    for _ in 0..repeats {
        let (r, t) = timed(|| cross_validate(features.view(), &data.labels, &folds, &settings.svm));
        wsr = r?.weighted_success_rate;
        cvs.push(t);
    }
    // The grid.
    let (grid, grid_best, grid_best_wsr) = if a.skip_grid {
        (None, None, None)
    } else {
        let (g, t) = timed(|| {
            stability::grid_search(
                &data,
                &GridSpec::bench(),
                &settings,
                CvScheme::KFold { k: 10 },
                &Progress::new(),
            )
        });
        let g = g?;
        (
            Some(t),
            Some(g.best.config),
            Some(g.best.weighted_success_rate),
        )
    };
    // Scaling with K and with the number of grasps.
    let mut scaling_k = Vec::new();
    let mut scaling_grasps = Vec::new();
    if !a.skip_scaling {
        for k in [5, 10, 20, 29, 40, 60] {
            scaling_k.push(scaling_point(&data, k, &settings)?);
        }
        let n = data.grasp_count();
        for frac in [0.25, 0.5, 1.0] {
            // A stratified, seeded subsample.
            let mut order: Vec<usize> = (0..n).collect();
            crate::rng::Rng::new(7).shuffle(&mut order);
            let take = |fail: bool| -> Vec<usize> {
                let of: Vec<usize> = order
                    .iter()
                    .copied()
                    .filter(|&g| data.labels[g] == fail)
                    .collect();
                let m = ((of.len() as f64) * frac).round() as usize;
                of[..m].to_vec()
            };
            let mut idx = take(false);
            idx.extend(take(true));
            idx.sort_unstable();
            let sub = data.subset(&idx)?;
            scaling_grasps.push(scaling_point(&sub, 29, &settings)?);
        }
    }
    Ok(BenchReport {
        session: data.session_name.clone(),
        grasps: data.grasp_count(),
        patches: data.x.nrows(),
        threads: rayon::current_num_threads(),
        load_average: [load0, load_average()],
        dictionary_to_target: median(to_target),
        dictionary_to_target_iterations: target_iterations,
        dictionary_full: median(full),
        dictionary_iterations: fit.iterations,
        dictionary_objective: fit.objective,
        coding: median(coding),
        feature_sign,
        cv_10fold: median(cvs),
        cv_wsr: wsr,
        grid,
        grid_best,
        grid_best_wsr,
        scaling_k,
        scaling_grasps,
    })
}

fn fmt_t(t: &Timing) -> String {
    format!("{:.4} s wall, {:.2} s CPU", t.wall_secs, t.cpu_secs)
}

pub fn bench_report(b: &BenchReport) -> String {
    let mut out = format!(
        "{}: {} grasps, {} patches, {} threads, load average {} → {}\n",
        b.session, b.grasps, b.patches, b.threads, b.load_average[0], b.load_average[1]
    );
    out += &format!(
        "dictionary K = 29, λ = 1: F ≤ 5.38 after {} iterations in {}; converged F = {:.4} after {} iterations in {}\n",
        b.dictionary_to_target_iterations,
        fmt_t(&b.dictionary_to_target),
        b.dictionary_objective,
        b.dictionary_iterations,
        fmt_t(&b.dictionary_full)
    );
    out += &format!(
        "coding all {} patches (γ = 1): {}\n",
        b.patches,
        fmt_t(&b.coding)
    );
    let fs = &b.feature_sign;
    out += &format!(
        "feature-sign, one solve per patch (γ = 1, from 0, one thread): median {:.2} µs, p10 {:.2} µs, p90 {:.2} µs over {} solves; {:.2} active bases per code\n",
        fs.median_us, fs.p10_us, fs.p90_us, fs.solves, fs.mean_active
    );
    out += &format!(
        "one 10-fold CV on the codes: {} (weighted success rate {:.2} %)\n",
        fmt_t(&b.cv_10fold),
        100.0 * b.cv_wsr
    );
    if let Some(g) = &b.grid {
        out += &format!(
            "108-cell grid with 10-fold CV: {}; best {} at {:.2} %\n",
            fmt_t(g),
            b.grid_best.map(|c| c.to_string()).unwrap_or_default(),
            100.0 * b.grid_best_wsr.unwrap_or(f64::NAN)
        );
    }
    for (title, pts) in [
        ("scaling with K", &b.scaling_k),
        ("scaling with grasps (K = 29)", &b.scaling_grasps),
    ] {
        if pts.is_empty() {
            continue;
        }
        out += &format!(
            "{title}:\n    K  grasps  dictionary (iter)          coding     10-fold CV   F\n"
        );
        for p in pts {
            out += &format!(
                "  {:>3}  {:>6}  {:>7.3} s ({:>3}) {:>5.2} CPU  {:>7.4} s  {:>7.3} s    {:.4}\n",
                p.num_bases,
                p.grasps,
                p.dictionary.wall_secs,
                p.dictionary_iterations,
                p.dictionary.cpu_secs,
                p.coding.wall_secs,
                p.cv.wall_secs,
                p.objective
            );
        }
    }
    out
}

pub fn run_bench(a: BenchStabilityArgs) -> anyhow::Result<()> {
    super::bounds::at_most("--repeats", a.repeats, super::bounds::MAX_REPS)?;
    super::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    let b = in_pool(a.threads, || bench(&a))??;
    print!("{}", bench_report(&b));
    if let Some(path) = &a.json {
        write_json(path, &b)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
