//! `frontier`: speed–accuracy frontiers by model size on one session, with the recommended
//! size of every method (`--json OUT` writes the frontiers as a list), its progress on
//! stderr.

use std::path::PathBuf;

use clap::Args;

use super::progress::with_progress;
use super::recognition::{open_session, write_json};
use crate::catalogue::MethodId;
use crate::experiments::frontier::{
    self, CostAxis, Frontier, FrontierParams, RecognitionScore, run_frontier,
};
use crate::features::FeatureSet;

#[derive(Args, Debug)]
pub struct FrontierArgs {
    /// A native session file, a BTS3 CSV or the iCub dataset folder.
    pub session: PathBuf,
    /// Methods, comma separated: ds, gs, sparse-svm, du, gu, kmeans, som, rbf-svm and the
    /// registered methods.
    #[arg(long, value_delimiter = ',', default_value = "gs")]
    pub method: Vec<String>,
    /// Feature sets of the sequence methods, comma separated: auto, all, tactile, encoder,
    /// raw … (one frontier each; default `auto`: the set with the fewest features within
    /// one standard error of the best 5-fold accuracy at the method's default size).
    #[arg(long, value_delimiter = ',')]
    pub features: Vec<String>,
    /// Seeded repetitions per size (at least 2).
    #[arg(long, default_value_t = 10)]
    pub reps: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// DS/GS BV budgets (default 2, 5, 10, 20, 50, 100).
    #[arg(long, value_delimiter = ',')]
    pub capacities: Vec<usize>,
    /// DS/GS kernel lags (default 1, 2, 5, 15, 30).
    #[arg(long, value_delimiter = ',')]
    pub taus: Vec<usize>,
    /// Sparse coding dictionary sizes (default 2, 3, 5, 10, 15, 20, 29, 40, 60).
    #[arg(long, value_delimiter = ',')]
    pub num_bases: Vec<usize>,
    /// Sparse coding: beta values tried at every num_bases (default 0.5, 1, 2).
    #[arg(long, value_delimiter = ',')]
    pub beta: Vec<f64>,
    /// Sparse coding: gamma values tried at every num_bases (default 0.5, 1, 2).
    #[arg(long, value_delimiter = ',')]
    pub gamma: Vec<f64>,
    /// DU/GU novelty thresholds (default DU 0.2, 0.3, … 0.8; GU 0.05, 0.08, 0.1, 0.12,
    /// 0.15, 0.2, 0.3).
    #[arg(long, value_delimiter = ',')]
    pub thresholds: Vec<f64>,
    /// DU/GU: the experts' capacity (default the paper's 50).
    #[arg(long)]
    pub expert_capacity: Option<usize>,
    /// DU/GU: the experts' tau (default the paper's 15).
    #[arg(long)]
    pub expert_tau: Option<usize>,
    /// k-means centres / SOM units (default 2, 4, 6, 8, 10, 12, 16, 20).
    #[arg(long, value_delimiter = ',')]
    pub ks: Vec<usize>,
    /// RBF SVM penalties C (default 1, 10, 100, 1000).
    #[arg(long, value_delimiter = ',')]
    pub svm_c: Vec<f64>,
    /// RBF SVM kernel widths gamma (default 0.001, 0.003, 0.01, 0.03, 0.1).
    #[arg(long, value_delimiter = ',')]
    pub svm_gamma: Vec<f64>,
    /// A registered method's knob values, `NAME=V1,V2` (repeatable; every combination is
    /// a size; a knob not given keeps the method's own list).
    #[arg(long = "knob", value_name = "NAME=V1,V2")]
    pub knobs: Vec<String>,
    /// DS/GS score: all (every predicted grasp) or final-20.
    #[arg(long, default_value = "all")]
    pub score: String,
    /// The time that defines the cheapest model: prediction or training.
    #[arg(long, default_value = "prediction")]
    pub cost: String,
    /// Write the frontiers here as JSON (a list).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

impl FrontierArgs {
    /// One parameter set per method × feature set (the methods on fixed features take the
    /// first feature set only).
    pub(crate) fn params(&self) -> anyhow::Result<Vec<FrontierParams>> {
        use super::bounds::*;
        at_most("--reps", self.reps, MAX_REPS)?;
        all_at_most("--capacities", &self.capacities, MAX_CAPACITY)?;
        all_at_most("--taus", &self.taus, MAX_TAU)?;
        all_at_most("--num-bases", &self.num_bases, MAX_NUM_BASES)?;
        all_at_most("--ks", &self.ks, MAX_K)?;
        at_most(
            "--expert-capacity",
            self.expert_capacity.unwrap_or(0),
            MAX_CAPACITY,
        )?;
        at_most("--expert-tau", self.expert_tau.unwrap_or(0), MAX_TAU)?;
        let score = match self.score.as_str() {
            "all" => RecognitionScore::All,
            "final-20" => RecognitionScore::Final20,
            other => anyhow::bail!("--score: `{other}` is not all or final-20"),
        };
        let cost = match self.cost.as_str() {
            "prediction" => CostAxis::Prediction,
            "training" => CostAxis::Training,
            other => anyhow::bail!("--cost: `{other}` is not prediction or training"),
        };
        let features = self
            .features
            .iter()
            .map(|f| f.parse::<FeatureSet>())
            .collect::<Result<Vec<_>, _>>()?;
        let mut out = Vec::new();
        for m in &self.method {
            let method = m
                .parse::<MethodId>()
                .ok()
                .filter(|id| frontier::methods().any(|f| f == *id))
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "--method: `{m}` is not one of {}",
                        MethodId::keys(frontier::methods())
                    )
                })?;
            let own = [if method.uses_features() {
                FeatureSet::AUTO
            } else {
                FeatureSet::ALL
            }];
            let sets = match (features.is_empty(), method.uses_features()) {
                (true, _) => &own[..],
                (false, true) => &features[..],
                (false, false) => &features[..1],
            };
            for &features in sets {
                let mut p = FrontierParams {
                    features,
                    score,
                    cost,
                    reps: self.reps,
                    seed: self.seed,
                    ..FrontierParams::for_method(method)
                };
                set_if(&mut p.capacities, &self.capacities);
                set_if(&mut p.taus, &self.taus);
                set_if(&mut p.num_bases, &self.num_bases);
                set_if(&mut p.beta, &self.beta);
                set_if(&mut p.gamma, &self.gamma);
                set_if(&mut p.thresholds, &self.thresholds);
                set_if(&mut p.ks, &self.ks);
                p.expert_capacity = self.expert_capacity;
                p.expert_tau = self.expert_tau;
                set_if(&mut p.svm_c, &self.svm_c);
                set_if(&mut p.svm_gamma, &self.svm_gamma);
                if let Some(c) = method.classifier() {
                    p.sizes = knob_sizes(c, &self.knobs)?;
                }
                p.validate()?;
                out.push(p);
            }
        }
        Ok(out)
    }
}

/// A registered method's sizes: its own values of each knob, those given by `--knob`
/// replaced.
fn knob_sizes(
    c: &dyn crate::catalogue::Classifier,
    given: &[String],
) -> anyhow::Result<Vec<Vec<f64>>> {
    let knobs = c.info().size_knobs;
    let mut lists = FrontierParams::lists_of_sizes(&c.sizes());
    for g in given {
        let (name, values) = g
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--knob: `{g}` is not NAME=V1,V2"))?;
        let k = knobs
            .iter()
            .position(|k| k.name == name.trim())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "--knob: {} has no knob `{name}` (its knobs: {})",
                    c.info().key,
                    knobs.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
                )
            })?;
        lists[k] = values
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| anyhow::anyhow!("--knob {name}: `{values}`: {e}"))?;
    }
    Ok(FrontierParams::sizes_of_lists(&lists))
}

fn set_if<T: Clone>(target: &mut Vec<T>, given: &[T]) {
    if !given.is_empty() {
        *target = given.to_vec();
    }
}

/// The frontier as a table, the Pareto and recommended sizes marked.
pub fn print_frontier(f: &Frontier) {
    println!(
        "{} on {}: {} sizes, {} repetitions each, {:.1} s",
        f.label(),
        f.session,
        f.points.len(),
        f.params.reps,
        f.wall_seconds
    );
    println!(
        "  {:<14} {:>14} {:>8}  {:>12} {:>12}  marks",
        "size",
        f.score_name.split(' ').next().unwrap_or(""),
        "SE",
        format!("train µs/{}", f.unit),
        format!("pred µs/{}", f.unit)
    );
    for (i, p) in f.points.iter().enumerate() {
        let mut marks = Vec::new();
        if i == f.best {
            marks.push("best");
        }
        if i == f.recommended {
            marks.push("RECOMMENDED");
        }
        if Some(i) == f.paper_default {
            marks.push("paper default");
        }
        if f.pareto_prediction.contains(&i) {
            marks.push("front(pred)");
        }
        if f.pareto_training.contains(&i) {
            marks.push("front(train)");
        }
        println!(
            "  {:<14} {:>14.4} {:>8.4}  {:>12.2} {:>12.2}  {}",
            p.label,
            p.score,
            p.score_se,
            p.train_us,
            p.predict_us,
            marks.join(", ")
        );
    }
    let (b, r) = (&f.points[f.best], &f.points[f.recommended]);
    println!(
        "  recommended {} ({:.4}; best {} {:.4} ± {:.4}); {:.1}× faster to predict than the best",
        r.detail,
        r.score,
        b.label,
        b.score,
        b.score_se,
        b.predict_us / r.predict_us
    );
}

pub fn run(args: FrontierArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(args.json.as_deref(), &[&args.session])?;
    let params = args.params()?;
    let session = open_session(&args.session)?;
    let mut frontiers = Vec::new();
    for p in &params {
        let f = with_progress(args.quiet, |progress| run_frontier(&session, p, progress))?;
        super::model::print_choice(f.feature_choice.as_ref());
        print_frontier(&f);
        frontiers.push(f);
    }
    write_json(&frontiers, args.json.as_deref())
}
