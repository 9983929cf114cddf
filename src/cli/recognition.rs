//! `recognition`, `clustering` and `bench-recognition`: the OIESGP experiments of the second
//! paper from the shell, with machine-readable results (`--json OUT`).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

mod bench;

pub use bench::{BenchArgs, bench};

use super::progress::with_progress;
use crate::experiments::clustering::{ClusteringParams, run_clustering};
use crate::experiments::frontier::Frontier;
use crate::experiments::recognition::{
    RecognitionParams, RecognitionResult, SupervisedLearner, run_recognition,
};
use crate::experiments::result::SizeReason;
use crate::features::FeatureSet;
use crate::session::{self, Session};

/// A native session file, a BTS3 CSV or the iCub dataset folder (imported on the fly).
pub fn open_session(path: &Path) -> anyhow::Result<Session> {
    session::open(path).with_context(|| format!("opening {}", path.display()))
}

/// Write `value` as pretty JSON to `out` (atomically), if given, and say so.
pub(crate) fn write_json<T: serde::Serialize>(value: &T, out: Option<&Path>) -> anyhow::Result<()> {
    if let Some(out) = out {
        let text = serde_json::to_string_pretty(value)?;
        crate::fsutil::write_atomic(out, text.as_bytes())
            .with_context(|| format!("writing {}", out.display()))?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct RecognitionArgs {
    /// A native session file or the iCub dataset folder.
    pub session: PathBuf,
    /// ds (discriminative) or gs (generative).
    #[arg(long, default_value = "gs")]
    pub learner: String,
    /// Inputs: auto (the family with the fewest features within one standard error of the
    /// best 5-fold accuracy of the experts on SESSION), all (the paper's families the
    /// session has), or families moments (alias tactile), encoders (alias encoder), raw,
    /// change, codes, combined with + (raw+encoders).
    #[arg(long, default_value = "auto")]
    pub features: String,
    /// The label set whose classes are learned and scored.
    #[arg(long, default_value = "object")]
    pub target: String,
    /// Repetitions of the protocol (the paper: 50).
    #[arg(long, default_value_t = 50)]
    pub reps: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Variance of Gaussian noise added to the raw taxels (the paper: 100, 1000).
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Switch hyperparameter adaptation off.
    #[arg(long)]
    pub no_adapt: bool,
    /// BV budget of every expert (default: the paper's 50).
    #[arg(long)]
    pub capacity: Option<usize>,
    /// Lags of the recursive kernel (default: the paper's 15).
    #[arg(long)]
    pub tau: Option<usize>,
    /// Use the recommended capacity and tau of this learner and feature set from a
    /// `frontier --json` file of the session.
    #[arg(long, conflicts_with_all = ["capacity", "tau"])]
    pub frontier: Option<PathBuf>,
    /// Write the full result here as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also teach the learner every grasp of the session (the protocol's order, `--seed`)
    /// and save it as a model file (`evaluate`, `predict`, `fit --from`).
    #[arg(long, value_name = "MODEL.json")]
    pub save_model: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

impl RecognitionArgs {
    pub(crate) fn params(&self) -> anyhow::Result<RecognitionParams> {
        use super::bounds::{MAX_CAPACITY, MAX_REPS, MAX_TAU, at_most};
        at_most("--reps", self.reps, MAX_REPS)?;
        at_most("--capacity", self.capacity.unwrap_or(0), MAX_CAPACITY)?;
        at_most("--tau", self.tau.unwrap_or(0), MAX_TAU)?;
        let mut p = RecognitionParams {
            learner: self.learner.parse()?,
            features: self.features.parse::<FeatureSet>()?,
            label_set: self.target.clone(),
            reps: self.reps,
            seed: self.seed,
            taxel_noise_variance: self.noise,
            ..RecognitionParams::default()
        };
        let (capacity, tau, reason) = match &self.frontier {
            Some(_) if p.features.is_auto() => anyhow::bail!(
                "--frontier: a frontier file holds one frontier per feature set; give --features"
            ),
            Some(path) => {
                let (c, t) = recommended_size(path, p.learner, p.features)?;
                (c, t, SizeReason::Recommended)
            }
            None if self.capacity.is_some() || self.tau.is_some() => (
                self.capacity.unwrap_or(p.gs.gp.capacity),
                self.tau.unwrap_or(p.gs.gp.tau),
                SizeReason::User,
            ),
            None => (p.gs.gp.capacity, p.gs.gp.tau, SizeReason::PaperDefault),
        };
        p.size_reason = reason;
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = capacity;
            gp.tau = tau;
            if self.no_adapt {
                gp.adaptation = None;
            }
        }
        p.validate()?;
        Ok(p)
    }
}

/// The recommended (capacity, tau) of `learner` on `features` in a frontier file.
fn recommended_size(
    path: &Path,
    learner: SupervisedLearner,
    features: FeatureSet,
) -> anyhow::Result<(usize, usize)> {
    let reader = crate::fsutil::open_json(path, crate::fsutil::max_bytes::FIGURE, "frontier file")
        .with_context(|| format!("reading {}", path.display()))?;
    let frontiers: Vec<Frontier> = serde_json::from_reader(reader)
        .with_context(|| format!("{} is not a `frontier --json` file", path.display()))?;
    let method = learner.method();
    let f = frontiers
        .iter()
        .find(|f| f.params.method == method && f.params.features == features)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "{} holds no {} frontier on {} features",
                path.display(),
                method.title(),
                features.name()
            )
        })?;
    let p = &f.points[f.recommended];
    match (p.knob("capacity"), p.knob("tau")) {
        (Some(c), Some(t)) => Ok((c as usize, t as usize)),
        _ => anyhow::bail!(
            "{}: the recommended point has no capacity and tau",
            path.display()
        ),
    }
}

/// "all features (moments+encoders)": the set asked for and, for `all`, the families it
/// stood for on the session.
fn features_used_text(asked: FeatureSet, used: Option<FeatureSet>) -> String {
    match used {
        Some(used) if asked.is_all() => format!("all features ({used})"),
        _ => format!("{asked} features"),
    }
}

pub fn print_recognition(r: &RecognitionResult) {
    let s = &r.summary;
    println!(
        "{:?} / {}, target {}, {} repetitions, {:.1} s wall, {} s CPU",
        r.params.learner,
        features_used_text(r.params.features, r.features_used),
        r.params.label_set,
        r.repetitions.len(),
        r.wall_seconds,
        r.cpu_seconds
            .map(|c| format!("{c:.1}"))
            .unwrap_or("?".into())
    );
    let gp = match r.params.learner {
        SupervisedLearner::Ds => &r.params.ds.gp,
        SupervisedLearner::Gs => &r.params.gs.gp,
    };
    println!(
        "  size       capacity {}, tau {} ({})",
        gp.capacity,
        gp.tau,
        r.params.size_reason.text()
    );
    println!("  all        {:.3} ({:.3})", s.all.mean, s.all.sd);
    println!("  final 20%  {:.3} ({:.3})", s.final_20.mean, s.final_20.sd);
    let sets: Vec<String> = s
        .trial_sets
        .iter()
        .map(|m| format!("{:.3}", m.mean))
        .collect();
    println!("  trial sets {}", sets.join(" "));
    let early: Vec<String> = r
        .params
        .early_fractions
        .iter()
        .zip(&s.early)
        .map(|(f, m)| format!("{f:.1}:{:.3}", m.mean))
        .collect();
    println!("  early      {}", early.join(" "));
    println!(
        "  per step   predict {:.1} µs, train {:.1} µs (threads share the cores)",
        s.predict_step_us, s.train_step_us
    );
}

pub fn recognition(args: RecognitionArgs) -> anyhow::Result<()> {
    let inputs: Vec<&Path> = [Some(args.session.as_path()), args.frontier.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    super::refuse_input_as_output(args.json.as_deref(), &inputs)?;
    let params = args.params()?;
    let session = open_session(&args.session)?;
    super::refuse_input_as_output(args.save_model.as_deref(), &inputs)?;
    let result = with_progress(args.quiet, |p| run_recognition(&session, &params, p))?;
    super::model::print_choice(result.feature_choice.as_ref());
    print_recognition(&result);
    write_json(&result, args.json.as_deref())?;
    if let Some(path) = &args.save_model {
        let file = crate::models::sequence_file_of_run(&session, &result)?;
        crate::models::save(&file, path)?;
        println!("wrote {} ({})", path.display(), file.provenance.summary());
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct ClusteringArgs {
    /// A native session file or the iCub dataset folder.
    pub session: PathBuf,
    /// du (discriminative) or gu (generative).
    #[arg(long, default_value = "du")]
    pub learner: String,
    /// Novelty thresholds, comma separated (default 0.1, 0.15, …, 0.95; for GU also 0.05 …
    /// 0.25 in steps of 0.01).
    #[arg(long, value_delimiter = ',')]
    pub thresholds: Vec<f64>,
    /// Random orders per threshold (the paper: 50).
    #[arg(long, default_value_t = 50)]
    pub reps: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Inputs: auto (the family with the fewest features within one standard error of the
    /// best 5-fold accuracy of the experts on SESSION), all (the paper's families the
    /// session has), or families moments (alias tactile), encoders (alias encoder), raw,
    /// change, codes, combined with + (raw+encoders).
    #[arg(long, default_value = "auto")]
    pub features: String,
    /// The label set whose classes are learned and scored.
    #[arg(long, default_value = "object")]
    pub target: String,
    /// Switch hyperparameter adaptation off.
    #[arg(long)]
    pub no_adapt: bool,
    /// GU: combine per-step novelties by their mean or their max, or score the whole grasp
    /// as one Gaussian (joint).
    #[arg(long, default_value = "mean")]
    pub gu_aggregate: String,
    /// GU: the extreme-value m counts the winning expert's grasps (+1) or its training steps.
    #[arg(long, default_value = "grasps")]
    pub gu_draws: String,
    /// GU: initial noise sigma_n of the experts (the paper: 0.1).
    #[arg(long)]
    pub gu_sigma_n: Option<f64>,
    /// GU: the noise in the novelty's Σ: the experts' shared sigma_n² (shared) or one
    /// variance per output dimension estimated from the expert's training residuals
    /// (per-dimension), also in the GS likelihood that picks the winner
    /// (per-dimension-filter).
    #[arg(long, default_value = "shared")]
    pub gu_noise: String,
    /// GU: the floor of the per-dimension noise variance.
    #[arg(long)]
    pub gu_noise_floor: Option<f64>,
    /// GU: clusters trained on fewer grasps (counting the one that created them) take no
    /// part in the final re-assignment (default 3; 1 keeps every cluster).
    #[arg(long)]
    pub gu_min_grasps: Option<usize>,
    /// DU: the same rule (default 1, the paper's DU: every cluster takes part).
    #[arg(long)]
    pub du_min_grasps: Option<usize>,
    /// Largest k of the k-means / SOM baselines (0: skip them).
    #[arg(long, default_value_t = 20)]
    pub baseline_max_k: usize,
    /// Choose a threshold without labels: stability (the clusterings' agreement across the
    /// random orders, mean pairwise ARI) or none.
    #[arg(long, default_value = "stability")]
    pub choose_threshold: String,
    /// Write the full result here as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also learn every grasp at the threshold chosen without labels and save the model
    /// (`evaluate`, `predict`, `fit du|gu --from`).
    #[arg(long, value_name = "MODEL.json")]
    pub save_model: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

impl ClusteringArgs {
    /// The parameters the arguments describe (checked).
    pub(crate) fn params(&self) -> anyhow::Result<ClusteringParams> {
        let args = self;
        super::bounds::at_most("--reps", args.reps, super::bounds::MAX_REPS)?;
        let learner = args.learner.parse()?;
        let mut params = ClusteringParams {
            features: args.features.parse::<FeatureSet>()?,
            label_set: args.target.clone(),
            reps: args.reps,
            seed: args.seed,
            baseline_max_k: args.baseline_max_k,
            ..ClusteringParams::for_learner(learner)
        };
        params.gu_aggregate = match args.gu_aggregate.as_str() {
            "max" => crate::learners::GuAggregate::Max,
            "mean" => crate::learners::GuAggregate::Mean,
            "joint" => crate::learners::GuAggregate::Joint,
            other => anyhow::bail!("--gu-aggregate: `{other}` is not mean, max or joint"),
        };
        params.gu_draws = match args.gu_draws.as_str() {
            "grasps" => crate::learners::EvtDraws::Grasps,
            "steps" => crate::learners::EvtDraws::Steps,
            other => anyhow::bail!("--gu-draws: `{other}` is not grasps or steps"),
        };
        params.gu_noise = match args.gu_noise.as_str() {
            "shared" => crate::learners::GuNoise::Shared,
            "per-dimension" => crate::learners::GuNoise::PerDimension,
            "per-dimension-filter" => crate::learners::GuNoise::PerDimensionFilter,
            other => anyhow::bail!(
                "--gu-noise: `{other}` is not shared, per-dimension or per-dimension-filter"
            ),
        };
        params.choose_threshold = match args.choose_threshold.as_str() {
            "none" => None,
            c => Some(
                c.parse()
                    .map_err(|e| anyhow::anyhow!("--choose-threshold: {e} or none"))?,
            ),
        };
        if let Some(k) = args.gu_min_grasps {
            params.gu_min_grasps = k;
        }
        if let Some(k) = args.du_min_grasps {
            params.du_min_grasps = k;
        }
        if let Some(f) = args.gu_noise_floor {
            params.gu_noise_floor = f;
        }
        if let Some(sn) = args.gu_sigma_n {
            params.gs.gp.sigma_n = sn;
        }
        if !args.thresholds.is_empty() {
            params.thresholds = args.thresholds.clone();
        }
        if args.no_adapt {
            params.ds.gp.adaptation = None;
            params.gs.gp.adaptation = None;
        }
        params.validate()?;
        Ok(params)
    }
}

fn print_point(name: &str, k: usize, p: &Option<crate::experiments::clustering::EffectivePoint>) {
    match p {
        Some(p) => println!(
            "  {name:<8} at {k} effective: purity {:.3} ({:.3})  ARI {:.3} ({:.3})  NMI {:.3} ({:.3})  [{} runs]",
            p.purity.mean, p.purity.sd, p.ari.mean, p.ari.sd, p.nmi.mean, p.nmi.sd, p.runs
        ),
        None => println!("  {name:<8} no run with {k} effective clusters"),
    }
}

fn print_summary(name: &str, s: &crate::experiments::clustering::ThresholdSummary) {
    println!(
        "  {name}: threshold {:.2}, {:.1} ({:.1}) effective, purity {:.3} ({:.3})  ARI {:.3} ({:.3})  NMI {:.3} ({:.3})",
        s.threshold,
        s.effective.mean,
        s.effective.sd,
        s.purity.mean,
        s.purity.sd,
        s.ari.mean,
        s.ari.sd,
        s.nmi.mean,
        s.nmi.sd
    );
}

/// The label-free threshold with its curve, the labelled optimum beside it, and the
/// baselines at the effective count the label-free threshold gives.
fn print_choice(r: &crate::experiments::clustering::ClusteringResult) {
    let Some(c) = &r.threshold_choice else {
        return;
    };
    println!(
        "  {} (mean pairwise ARI of the orders' clusterings):",
        c.criterion.text()
    );
    for a in &c.curve {
        println!(
            "    {:>5.2}  {:.3} ({:.3}){}",
            a.threshold,
            a.agreement,
            a.sd,
            if a.eligible() {
                ""
            } else {
                "  (one cluster in most orders)"
            }
        );
    }
    if let Some(s) = r.at_choice() {
        print_summary("chosen without labels", s);
        let k = s.effective.mean.round() as usize;
        let find = |v: &[crate::experiments::clustering::EffectivePoint]| {
            v.iter().find(|p| p.effective == k).cloned()
        };
        print_point("k-means", k, &find(&r.kmeans));
        print_point("SOM", k, &find(&r.som));
    }
    if let Some(s) = r.best_by_labels() {
        print_summary("best NMI (labels)  ", s);
    }
}

pub fn clustering(args: ClusteringArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(args.json.as_deref(), &[&args.session])?;
    super::refuse_input_as_output(args.save_model.as_deref(), &[&args.session])?;
    let params = args.params()?;
    let session = open_session(&args.session)?;
    let r = with_progress(args.quiet, |p| run_clustering(&session, &params, p))?;
    super::model::print_choice(r.feature_choice.as_ref());
    println!(
        "{:?} / {}, target {}, {} orders per threshold, {:.1} s",
        params.learner,
        features_used_text(params.features, r.features_used),
        params.label_set,
        params.reps,
        r.wall_seconds
    );
    println!("  threshold  clusters  effective  purity   ARI     NMI");
    for t in &r.sweep {
        println!(
            "  {:>9.2}  {:>8.1}  {:>9.1}  {:.3}   {:.3}   {:.3}",
            t.threshold, t.clusters.mean, t.effective.mean, t.purity.mean, t.ari.mean, t.nmi.mean
        );
    }
    print_point("learner", 10, &r.at_10);
    print_point("k-means", 10, &r.kmeans_at_10);
    print_point("SOM", 10, &r.som_at_10);
    print_choice(&r);
    let us = r.runs.iter().map(|x| x.learn_step_us).sum::<f64>() / r.runs.len().max(1) as f64;
    println!("  learning phase {us:.1} µs per observation (threads share the cores)");
    write_json(&r, args.json.as_deref())?;
    if let Some(path) = &args.save_model {
        let Some(file) = crate::models::cluster_file_of_run(&session, &r)? else {
            anyhow::bail!(
                "--save-model learns at the threshold chosen without labels: give --choose-threshold stability"
            );
        };
        crate::models::save(&file, path)?;
        println!("wrote {} ({})", path.display(), file.provenance.summary());
    }
    Ok(())
}
