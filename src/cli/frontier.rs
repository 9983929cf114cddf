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
    /// Any method's knob values, `NAME=V1,V2` (repeatable; a knob not given keeps its
    /// flag's or the method's own list; a registered method sweeps every combination).
    /// The names: capacities, taus (DS/GS), num_bases (sparse coding), thresholds (DU/GU),
    /// k (k-means, SOM), C, γ (RBF SVM), and each registered method's own.
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
                set_if(&mut p.beta, &self.beta);
                set_if(&mut p.gamma, &self.gamma);
                p.expert_capacity = self.expert_capacity;
                p.expert_tau = self.expert_tau;
                p.set_size_knobs(&self.knob_lists(method)?)?;
                p.validate()?;
                out.push(p);
            }
        }
        Ok(out)
    }
}

impl FrontierArgs {
    /// The lists `method`'s frontier sweeps, one per knob of [`frontier::size_knobs`]: its
    /// own values, replaced by a built-in method's flag of the knob's name (`--capacities`
    /// for DS's "capacities") and then by `--knob NAME=V1,V2`.
    fn knob_lists(&self, method: MethodId) -> anyhow::Result<Vec<Vec<f64>>> {
        let knobs = frontier::size_knobs(method);
        let mut lists: Vec<Vec<f64>> = knobs.iter().map(|k| k.values.clone()).collect();
        // The flags are the built-in methods' own (a registered method's `k` is not
        // k-means' `--ks`).
        let named = if method.classifier().is_none() {
            self.named_knobs().to_vec()
        } else {
            Vec::new()
        };
        for (k, list) in knobs.iter().zip(&mut lists) {
            if let Some((_, given)) = named.iter().find(|(n, _)| *n == k.name)
                && !given.is_empty()
            {
                list.clone_from(given);
            }
        }
        for g in &self.knobs {
            let (name, values) = g
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--knob: `{g}` is not NAME=V1,V2"))?;
            let k = knobs
                .iter()
                .position(|k| k.name == name.trim())
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "--knob: {} has no knob `{name}` (its knobs: {})",
                        method.key(),
                        knobs.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
                    )
                })?;
            lists[k] = values
                .split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| anyhow::anyhow!("--knob {name}: `{values}`: {e}"))?;
        }
        Ok(lists)
    }

    /// The built-in methods' knobs that have a flag of their own, by the knob's name.
    fn named_knobs(&self) -> [(&'static str, Vec<f64>); 7] {
        let reals = |v: &[usize]| v.iter().map(|&v| v as f64).collect();
        [
            ("capacities", reals(&self.capacities)),
            ("taus", reals(&self.taus)),
            ("num_bases", reals(&self.num_bases)),
            ("thresholds", self.thresholds.clone()),
            ("k", reals(&self.ks)),
            ("C", self.svm_c.clone()),
            ("γ", self.svm_gamma.clone()),
        ]
    }
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

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::super::{Cli, Command};
    use super::*;

    fn args(given: &[&str]) -> FrontierArgs {
        let all = [&["tactile-workbench", "frontier", "s.json"], given].concat();
        let Some(Command::Frontier(a)) = Cli::try_parse_from(all).unwrap().command else {
            panic!("not parsed as `frontier`");
        };
        a
    }

    /// The one frontier `given` asks for.
    fn one(given: &[&str]) -> FrontierParams {
        let mut p = args(given).params().unwrap();
        assert_eq!(p.len(), 1);
        p.remove(0)
    }

    fn error(given: &[&str]) -> String {
        args(given).params().unwrap_err().to_string()
    }

    #[test]
    fn every_flag_names_a_built_in_knob() {
        let built_in: Vec<&str> = frontier::methods()
            .filter(|m| m.classifier().is_none())
            .flat_map(|m| frontier::size_knobs(m).into_iter().map(|k| k.name))
            .collect();
        for (name, _) in args(&[]).named_knobs() {
            assert!(built_in.contains(&name), "no built-in knob `{name}`");
        }
    }

    #[test]
    fn flags_and_knobs_reach_the_lists_swept() {
        let ds = one(&["--method", "ds", "--capacities", "3,7"]);
        assert_eq!(ds.capacities, [3, 7]);
        assert_eq!(ds.taus, FrontierParams::for_method(MethodId::Ds).taus);
        let by_name = one(&["--method", "ds", "--knob", "capacities=3,7"]);
        assert_eq!(by_name, ds);
        // `--knob` comes after the flag.
        let som = one(&["--method", "som", "--ks", "2,4", "--knob", "k=6"]);
        assert_eq!(som.ks, [6]);
        let rbf = one(&["--method", "rbf-svm", "--svm-c", "5", "--knob", "γ=0.1,0.2"]);
        assert_eq!((rbf.svm_c, rbf.svm_gamma), (vec![5.0], vec![0.1, 0.2]));
        let du = one(&["--method", "du", "--thresholds", "0.4"]);
        assert_eq!(du.thresholds, [0.4]);
    }

    #[test]
    fn a_built_in_flag_leaves_a_registered_knob_of_the_same_name() {
        let every_flag = [
            "--capacities=3",
            "--taus=1",
            "--num-bases=2",
            "--thresholds=0.5",
            "--ks=2,4",
            "--svm-c=1",
            "--svm-gamma=1",
        ];
        let registered: Vec<MethodId> = frontier::methods()
            .filter(|m| m.classifier().is_some())
            .collect();
        assert!(!registered.is_empty());
        for m in registered {
            let knobs = frontier::size_knobs(m);
            let own: Vec<Vec<f64>> = knobs.iter().map(|k| k.values.clone()).collect();
            let key = m.key();
            let flagged = one(&[&["--method", key], &every_flag[..]].concat());
            assert_eq!(FrontierParams::lists_of_sizes(&flagged.sizes), own, "{key}");
            // Its first knob through `--knob`: two of its own values, the others kept.
            let first = &knobs[0];
            let two: Vec<f64> = first.values.iter().take(2).copied().collect();
            let list = two.iter().map(|v| v.to_string()).collect::<Vec<_>>();
            let knob = format!("{}={}", first.name, list.join(","));
            let p = one(&["--method", key, "--knob", &knob]);
            let lists = FrontierParams::lists_of_sizes(&p.sizes);
            assert_eq!(lists[0], two, "{key}");
            assert_eq!(lists[1..], own[1..], "{key}");
        }
    }

    #[test]
    fn a_bad_knob_is_refused_by_name() {
        let e = error(&["--method", "kmeans", "--knob", "k=2.5"]);
        assert!(e.contains("`k`") && e.contains("whole"), "{e}");
        let e = error(&["--method", "gs", "--knob", "tau=2"]);
        assert!(
            e.contains("no knob `tau`") && e.contains("capacities, taus"),
            "{e}"
        );
        let e = error(&["--method", "gs", "--knob", "taus"]);
        assert!(e.contains("NAME=V1,V2"), "{e}");
    }
}
