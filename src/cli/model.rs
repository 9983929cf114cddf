//! Models that leave their session: `fit` a method on a session into a model file,
//! `evaluate` it on another session, and `predict` a session's grasps.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, FromArgMatches};

use super::progress::with_progress;
use super::stability::{StabilityArgs, data_options, in_pool, options_from};
use crate::catalogue::{Classifier, Input, MethodId, Task};
use crate::experiments::feature_choice::{AUTO_FOLDS, FeatureChoice};
use crate::experiments::result::figure_set;
use crate::experiments::stability::StabilityData;
use crate::figures::{Format, RenderOptions, export_all};
use crate::models::{self, Calibration, HeldOutScores, ModelFile};
use crate::session::{self, Session};

/// `fit METHOD SESSION -o MODEL.json …`: a subcommand per method of the catalogue, named
/// as `frontier --method` names it, with the options of its kind of fit.
#[derive(Debug)]
pub struct FitArgs {
    pub method: MethodId,
    pub options: FitOptions,
}

/// A method's options, by its kind of fit.
#[derive(Debug)]
pub enum FitOptions {
    Stability(FitStabilityArgs),
    Sequences(FitSequenceArgs),
    Clusters(FitClusterArgs),
    TableOne(FitTableOneArgs),
    /// A registered method: its own command's options (built from its declared knobs).
    Registered(clap::ArgMatches),
}

/// How a method is fitted, from what the catalogue says it learns and reads.
#[derive(Clone, Copy)]
enum FitKind {
    Stability,
    Sequences,
    Clusters,
    TableOne,
    Registered(&'static dyn Classifier),
}

impl FitKind {
    fn of(method: MethodId) -> FitKind {
        if let Some(c) = method.classifier() {
            return FitKind::Registered(c);
        }
        match (method.task(), method.input()) {
            (Task::Stability, _) => FitKind::Stability,
            (_, Input::TableOne) => FitKind::TableOne,
            (Task::Clustering, _) => FitKind::Clusters,
            (Task::Recognition, _) => FitKind::Sequences,
        }
    }

    /// What `fit --help` says of a method of this kind, after its title.
    fn about(self) -> &'static str {
        match self {
            FitKind::Stability => {
                "on the key-frame patches, with the options of `stability`: one \
                 configuration, or a grid's parsimonious choice"
            }
            FitKind::Sequences => {
                "experts taught every grasp in the protocol's order; `--from` teaches a \
                 saved model further"
            }
            FitKind::Clusters => {
                "experts clustering at a novelty threshold; `--from` learns a saved model \
                 further (novel objects open clusters)"
            }
            FitKind::TableOne => {
                "on the per-grasp Table I features (k-means and the SOM: `--k` centres or \
                 units; the RBF SVM: C and gamma chosen by the `baselines` grid)"
            }
            FitKind::Registered(_) => "with its size knobs as options",
        }
    }
}

/// The `fit` subcommand of `method`.
fn fit_command(method: MethodId) -> clap::Command {
    let info = method.info();
    let kind = FitKind::of(method);
    let cmd = clap::Command::new(info.key);
    let cmd = match kind {
        FitKind::Stability => FitStabilityArgs::augment_args(cmd),
        FitKind::Sequences => FitSequenceArgs::augment_args(cmd),
        FitKind::Clusters => FitClusterArgs::augment_args(cmd),
        FitKind::TableOne => FitTableOneArgs::augment_args(cmd),
        FitKind::Registered(c) => registered_command(cmd, c),
    };
    cmd.visible_aliases(info.aliases.iter().copied())
        .about(format!("{} {}", info.title, kind.about()))
}

impl Args for FitArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        cmd.subcommand_required(true)
            .subcommands(MethodId::all().map(fit_command))
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for FitArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        use clap::error::ErrorKind;
        let (name, sub) = m
            .subcommand()
            .ok_or_else(|| clap::Error::new(ErrorKind::MissingSubcommand))?;
        // clap names the subcommand by its key whatever alias was typed.
        let method: MethodId = name
            .parse()
            .map_err(|_| clap::Error::new(ErrorKind::InvalidSubcommand))?;
        let options = match FitKind::of(method) {
            FitKind::Stability => FitOptions::Stability(FitStabilityArgs::from_arg_matches(sub)?),
            FitKind::Sequences => FitOptions::Sequences(FitSequenceArgs::from_arg_matches(sub)?),
            FitKind::Clusters => FitOptions::Clusters(FitClusterArgs::from_arg_matches(sub)?),
            FitKind::TableOne => FitOptions::TableOne(FitTableOneArgs::from_arg_matches(sub)?),
            FitKind::Registered(_) => FitOptions::Registered(sub.clone()),
        };
        Ok(FitArgs { method, options })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

#[derive(Args, Debug)]
pub struct FitTableOneArgs {
    pub session: PathBuf,
    /// Centres (k-means) or units (SOM); the paper's 10.
    #[arg(long, default_value_t = 10)]
    pub k: usize,
    /// The label set learned (RBF SVM) or scored against (k-means, SOM).
    #[arg(long, default_value = "object")]
    pub target: String,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitClusterArgs {
    pub session: PathBuf,
    /// The novelty threshold (e.g. the one `clustering --choose-threshold stability`
    /// chose without labels); required unless --from.
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Feature families per step, as for `fit ds` (default `auto`: chosen by cross
    /// validation of DU's (GU's) experts, DS (GS), on SESSION).
    #[arg(long)]
    pub features: Option<String>,
    /// The label set clusters are scored against by `evaluate` (default `object`; never
    /// read while learning).
    #[arg(long)]
    pub target: Option<String>,
    /// Seed of the learning order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Learn this saved model further on SESSION.
    #[arg(long, value_name = "MODEL.json")]
    pub from: Option<PathBuf>,
    /// With --from: teach the grasps one at a time in the session's order, as a live
    /// stream teaches them (`live --teach`), instead of the protocol's seeded shuffle.
    #[arg(long, requires = "from")]
    pub in_order: bool,
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitSequenceArgs {
    pub session: PathBuf,
    /// Feature families per step (`auto`, `all`, `moments`, `encoders`, `raw`, `change`, or
    /// combinations such as `raw+encoders`; default `auto`: the family with the fewest
    /// features within one standard error of the best 5-fold accuracy on SESSION).
    #[arg(long)]
    pub features: Option<String>,
    /// The label set to learn (default `object`).
    #[arg(long)]
    pub target: Option<String>,
    /// Seed of the training order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Basis vectors per expert (default: the paper's 50).
    #[arg(long)]
    pub capacity: Option<usize>,
    /// Steps of input history (default: the paper's 15).
    #[arg(long)]
    pub tau: Option<usize>,
    /// Switch off hyperparameter adaptation.
    #[arg(long)]
    pub no_adapt: bool,
    /// Teach this saved model further on SESSION (its features, target, size and range
    /// stay; a class it has not seen gets a new expert).
    #[arg(long, value_name = "MODEL.json")]
    pub from: Option<PathBuf>,
    /// With --from: teach the grasps one at a time in the session's order, as a live
    /// stream teaches them (`live --teach`), instead of the protocol's seeded shuffle.
    #[arg(long, requires = "from")]
    pub in_order: bool,
    /// The model file to write.
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitStabilityArgs {
    #[command(flatten)]
    pub stability: StabilityArgs,
    /// The model file to write.
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct EvaluateArgs {
    /// A model file (`fit`, or `--save-model` of an analysis).
    pub model: PathBuf,
    /// A session the model did not train on (native file, BTS3 CSV or iCub folder).
    pub session: PathBuf,
    /// How the session's taxels are put on the model's scale: `none` (the training
    /// session's statistics), `session` (the new session's own) or `first:K` (its first K
    /// grasps'). docs/held-out.md says why `session` is the default.
    #[arg(long, default_value = "session")]
    pub calibration: String,
    /// Write the scores and every grasp's prediction here.
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// Write the figures (SVG, PDF, PNG, CSV and an index) to this folder.
    #[arg(long, value_name = "DIR")]
    pub figures: Option<PathBuf>,
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct PredictArgs {
    pub model: PathBuf,
    pub session: PathBuf,
    /// As for `evaluate`.
    #[arg(long, default_value = "session")]
    pub calibration: String,
    /// One row per grasp: grasp, object, trial, truth (when labelled), predicted, decision.
    #[arg(short, long, value_name = "predictions.csv")]
    pub output: PathBuf,
    /// DS/GS: also every step of every grasp with the class distribution after it.
    #[arg(long, value_name = "STEPS.csv")]
    pub steps: Option<PathBuf>,
}

pub fn fit(a: FitArgs) -> anyhow::Result<()> {
    match a.options {
        FitOptions::Stability(f) => fit_stability(a.method, f),
        FitOptions::Sequences(f) => fit_sequences(a.method, f),
        FitOptions::Clusters(f) => fit_clusters(a.method, f),
        FitOptions::TableOne(f) => fit_table_one(a.method, f),
        FitOptions::Registered(m) => fit_registered(a.method, &m),
    }
}

fn fit_stability(method: MethodId, f: FitStabilityArgs) -> anyhow::Result<()> {
    let s = &f.stability;
    if s.json.is_some() || s.save_model.is_some() || s.nested {
        bail!(
            "fit writes one model file (-o); --json, --save-model and --nested belong to `stability`"
        );
    }
    super::refuse_input_as_output(Some(&f.output), &[&s.session])?;
    let session = super::stability::open(&s.session)?;
    let data = StabilityData::from_session(&session, &data_options(s))?;
    let opts = options_from(s, &data)?;
    let fitted = in_pool(s.threads, || {
        with_progress(s.quiet, |p| {
            models::fit_stability(method, &session, &data, &opts, p)
        })
    })??;
    let file = fitted.into_file(&session, &data);
    models::save(&file, &f.output)?;
    let p = &file.provenance;
    println!("{} in {:.1} s", p.summary(), p.train_seconds);
    for s in &p.selection {
        println!("  {} {:.2} % ({})", s.name, 100.0 * s.value, s.protocol);
    }
    println!("wrote {}", f.output.display());
    Ok(())
}

/// The model file at `path`, which must hold a model of `method` (`--from`). Loading
/// checks that the model's kind is the one its provenance names.
fn saved_model_of(path: &Path, method: MethodId) -> anyhow::Result<ModelFile> {
    let old = models::load(path)?;
    if old.provenance.method != method {
        bail!(
            "{} holds a {} model; --from takes a {} model",
            path.display(),
            old.provenance.method.key(),
            method.key()
        );
    }
    Ok(old)
}

fn fit_sequences(method: MethodId, a: FitSequenceArgs) -> anyhow::Result<()> {
    let mut inputs = vec![a.session.as_path()];
    inputs.extend(a.from.as_deref());
    super::refuse_input_as_output(Some(&a.output), &inputs)?;
    use super::bounds::{MAX_CAPACITY, MAX_TAU, at_most};
    at_most("--capacity", a.capacity.unwrap_or(0), MAX_CAPACITY)?;
    at_most("--tau", a.tau.unwrap_or(0), MAX_TAU)?;
    let session =
        session::open(&a.session).with_context(|| format!("opening {}", a.session.display()))?;
    let file = match &a.from {
        Some(path) => {
            if a.features.is_some()
                || a.target.is_some()
                || a.capacity.is_some()
                || a.tau.is_some()
                || a.no_adapt
            {
                bail!(
                    "--from keeps the saved model's features, target, size and adaptation: leave those options out"
                );
            }
            let old = saved_model_of(path, method)?;
            if a.in_order {
                crate::live::model::teach_in_order(&old, &session)?
            } else {
                let models::Model::Sequences(m) = &old.model else {
                    unreachable!("a {} model file holds DS or GS experts", method.key());
                };
                let (next, secs) = models::continue_sequences(m, &session)?;
                models::sequence_file(
                    next,
                    &session,
                    secs,
                    old.provenance.size_reason,
                    Some(&old.provenance),
                )
            }
        }
        None => {
            let defaults = crate::experiments::recognition::RecognitionParams::default();
            let (mut ds, mut gs) = (defaults.ds, defaults.gs);
            let reason = if a.capacity.is_some() || a.tau.is_some() {
                crate::experiments::result::SizeReason::User
            } else {
                crate::experiments::result::SizeReason::PaperDefault
            };
            for gp in [&mut ds.gp, &mut gs.gp] {
                gp.capacity = a.capacity.unwrap_or(gp.capacity);
                gp.tau = a.tau.unwrap_or(gp.tau);
                if a.no_adapt {
                    gp.adaptation = None;
                }
            }
            let opts = models::SequenceFitOptions {
                method,
                features: a.features.as_deref().unwrap_or("auto").parse()?,
                label_set: a.target.clone().unwrap_or_else(|| "object".into()),
                seed: a.seed,
                ds,
                gs,
            };
            let (opts, choice) = with_progress(false, |p| {
                models::choose_sequence_features(&session, &opts, p)
            })?;
            print_choice(choice.as_ref());
            let (model, secs) = models::fit_sequences(&session, &opts)?;
            let mut file = models::sequence_file(model, &session, secs, reason, None);
            file.provenance.feature_choice = choice;
            file
        }
    };
    models::save(&file, &a.output)?;
    let p = &file.provenance;
    println!(
        "{} in {:.1} s; classes {}",
        p.summary(),
        p.train_seconds,
        p.classes.join(", ")
    );
    println!("wrote {}", a.output.display());
    Ok(())
}

fn fit_clusters(method: MethodId, a: FitClusterArgs) -> anyhow::Result<()> {
    let mut inputs = vec![a.session.as_path()];
    inputs.extend(a.from.as_deref());
    super::refuse_input_as_output(Some(&a.output), &inputs)?;
    let session =
        session::open(&a.session).with_context(|| format!("opening {}", a.session.display()))?;
    let file = match &a.from {
        Some(path) => {
            if a.features.is_some() || a.target.is_some() || a.threshold.is_some() {
                bail!(
                    "--from keeps the saved model's features, target and threshold: leave those options out"
                );
            }
            let old = saved_model_of(path, method)?;
            if a.in_order {
                crate::live::model::teach_in_order(&old, &session)?
            } else {
                let models::Model::Clusters(m) = &old.model else {
                    unreachable!("a {} model file holds DU or GU experts", method.key());
                };
                let (next, secs) = models::continue_clusters(m, &session)?;
                models::cluster_file(next, &session, secs, Some(&old.provenance))
            }
        }
        None => {
            let Some(threshold) = a.threshold else {
                bail!(
                    "--threshold: the novelty threshold the model opens clusters at (`clustering --choose-threshold stability` chooses one without labels)"
                );
            };
            let learner = crate::experiments::clustering::UnsupervisedLearner::of(method)
                .with_context(|| format!("{} is not du or gu", method.key()))?;
            let opts = models::ClusterFitOptions {
                method,
                features: a.features.as_deref().unwrap_or("auto").parse()?,
                label_set: a.target.clone().unwrap_or_else(|| "object".into()),
                threshold,
                seed: a.seed,
                params: crate::experiments::clustering::ClusteringParams::for_learner(learner),
            };
            let (opts, choice) = with_progress(false, |p| {
                models::choose_cluster_features(&session, &opts, p)
            })?;
            print_choice(choice.as_ref());
            let (model, secs) = models::fit_clusters(&session, &opts)?;
            let mut file = models::cluster_file(model, &session, secs, None);
            file.provenance.feature_choice = choice;
            file
        }
    };
    models::save(&file, &a.output)?;
    let p = &file.provenance;
    println!(
        "{} in {:.1} s; {} clusters",
        p.summary(),
        p.train_seconds,
        p.classes.len()
    );
    println!("wrote {}", a.output.display());
    Ok(())
}

fn fit_table_one(method: MethodId, a: FitTableOneArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(Some(&a.output), &[&a.session])?;
    super::bounds::at_most("--k", a.k, super::bounds::MAX_K)?;
    let session =
        session::open(&a.session).with_context(|| format!("opening {}", a.session.display()))?;
    if method != MethodId::RbfSvm {
        super::bounds::at_most_grasps("--k", &[a.k], session.grasps.len())?;
    }
    let opts = models::TableOneFitOptions::new(method, &a.target, a.k, a.seed);
    let (model, fit) = models::fit_table_one(&session, &opts, None)?;
    let file = models::table_one_file(model, &session, fit);
    models::save(&file, &a.output)?;
    let p = &file.provenance;
    println!("{} in {:.1} s", p.summary(), p.train_seconds);
    for s in &p.selection {
        println!("  {} {:.2} % ({})", s.name, 100.0 * s.value, s.protocol);
    }
    println!("wrote {}", a.output.display());
    Ok(())
}

/// The command line of a registered method, built from its declared knobs.
fn registered_command(cmd: clap::Command, c: &dyn Classifier) -> clap::Command {
    use clap::{Arg, value_parser};
    let info = c.info();
    let mut cmd = cmd
        .arg(
            Arg::new("session")
                .value_name("SESSION")
                .required(true)
                .value_parser(value_parser!(PathBuf)),
        )
        .arg(
            Arg::new("output")
                .short('o')
                .long("output")
                .value_name("MODEL.json")
                .required(true)
                .value_parser(value_parser!(PathBuf)),
        )
        .arg(
            Arg::new("features")
                .long("features")
                .default_value("auto")
                .help(format!(
                    "Feature families per step: auto (the family with the fewest features \
                     within one standard error of the best {AUTO_FOLDS}-fold accuracy on \
                     SESSION), or a set as for `fit ds` (the method's own: {})",
                    c.features()
                )),
        )
        .arg(
            Arg::new("target")
                .long("target")
                .default_value("object")
                .help("The label set to learn"),
        )
        .arg(
            Arg::new("seed")
                .long("seed")
                .default_value("0")
                .value_parser(value_parser!(u64)),
        );
    for (k, v) in info.size_knobs.iter().zip(c.default_size()) {
        cmd = cmd.arg(
            Arg::new(k.name)
                .long(k.name)
                .value_parser(value_parser!(f64))
                .help(format!("{} (default {v})", k.meaning)),
        );
    }
    cmd
}

fn fit_registered(method: MethodId, m: &clap::ArgMatches) -> anyhow::Result<()> {
    let c =
        (method.classifier()).with_context(|| format!("{method} is not a registered method"))?;
    let session_path = m.get_one::<PathBuf>("session").expect("required");
    let output = m.get_one::<PathBuf>("output").expect("required");
    super::refuse_input_as_output(Some(output), &[session_path])?;
    let mut size = c.default_size();
    let mut given = false;
    for (k, v) in c.info().size_knobs.iter().zip(size.iter_mut()) {
        if let Some(x) = m.get_one::<f64>(k.name) {
            *v = *x;
            given = true;
        }
    }
    c.check(&size)?;
    let session = session::open(session_path)
        .with_context(|| format!("opening {}", session_path.display()))?;
    let opts = models::ClassifierFitOptions {
        method,
        features: m
            .get_one::<String>("features")
            .map(|f| f.parse())
            .transpose()?,
        size: Some(size),
        label_set: m.get_one::<String>("target").expect("defaulted").clone(),
        seed: *m.get_one::<u64>("seed").expect("defaulted"),
    };
    let (opts, choice) = with_progress(false, |p| {
        models::choose_classifier_features(&session, &opts, p)
    })?;
    print_choice(choice.as_ref());
    let (model, secs) = with_progress(false, |p| models::fit_classifier(&session, &opts, p))?;
    let reason = if given {
        crate::experiments::result::SizeReason::User
    } else {
        crate::experiments::result::SizeReason::MethodDefault
    };
    let mut file = models::classifier_file(model, &session, secs, reason);
    file.provenance.feature_choice = choice;
    models::save(&file, output)?;
    let p = &file.provenance;
    println!(
        "{} in {:.1} s; classes {}",
        p.summary(),
        p.train_seconds,
        p.classes.join(", ")
    );
    println!("wrote {}", output.display());
    Ok(())
}

/// What `auto` chose and why, when it chose.
pub(crate) fn print_choice(choice: Option<&FeatureChoice>) {
    if let Some(c) = choice {
        println!("{}", c.text());
    }
}

fn load_pair(model: &Path, session: &Path) -> anyhow::Result<(ModelFile, Session)> {
    let file = models::load(model)?;
    let session =
        session::open(session).with_context(|| format!("opening {}", session.display()))?;
    Ok((file, session))
}

pub fn evaluate(a: EvaluateArgs) -> anyhow::Result<()> {
    let inputs = [a.model.as_path(), a.session.as_path()];
    super::refuse_input_as_output(a.json.as_deref(), &inputs)?;
    super::refuse_input_as_output(a.figures.as_deref(), &inputs)?;
    let calibration: Calibration = a.calibration.parse()?;
    let (file, session) = load_pair(&a.model, &a.session)?;
    let r = models::evaluate(&file, &session, calibration).with_context(|| {
        format!(
            "evaluating {} on {}",
            a.model.display(),
            a.session.display()
        )
    })?;
    if !a.quiet {
        println!("{}", r.model);
        println!(
            "tested on {} ({} grasps), calibration {}",
            r.tested_on.name, r.tested_on.grasps, r.calibration_text
        );
        match &r.scores {
            HeldOutScores::Stability {
                weighted_success_rate,
                failure_recall,
                success_recall,
                ..
            } => println!(
                "weighted success rate {:.2} %, failure recall {:.2} %, success recall {:.2} %",
                100.0 * weighted_success_rate,
                100.0 * failure_recall,
                100.0 * success_recall
            ),
            HeldOutScores::Recognition {
                accuracy, early, ..
            } => {
                println!("accuracy {:.2} %", 100.0 * accuracy);
                let early: Vec<String> = early
                    .iter()
                    .map(|(f, a)| format!("{:.0} %: {:.1} %", 100.0 * f, 100.0 * a))
                    .collect();
                // The RBF SVM decides once per grasp: it has no early decisions.
                if !early.is_empty() {
                    println!(
                        "early classification (share observed: accuracy) {}",
                        early.join(", ")
                    );
                }
            }
            HeldOutScores::Clustering {
                purity,
                ari,
                nmi,
                clusters,
                effective,
                ..
            } => println!(
                "purity {purity:.3}, ARI {ari:.3}, NMI {nmi:.3}; the grasps fall in {effective} of the model's {clusters} clusters"
            ),
        }
    }
    if let Some(path) = &a.json {
        let text = serde_json::to_string_pretty(&r)?;
        crate::fsutil::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    if let Some(dir) = &a.figures {
        let set = figure_set(&[models::held_out_report(&r)]);
        let index = crate::fsutil::write_dir_atomic(dir, &["index.md"], |d| {
            anyhow::Ok(export_all(
                &set,
                d,
                &[Format::Svg, Format::Pdf, Format::Png, Format::Csv],
                &RenderOptions::default(),
            )?)
        })?;
        println!("wrote {} figures to {}", index.entries.len(), dir.display());
        if !index.not_drawn.is_empty() {
            anyhow::bail!("not drawn at this size: {}", index.not_drawn_text());
        }
    }
    Ok(())
}

pub fn predict(a: PredictArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(Some(&a.output), &[&a.model, &a.session])?;
    super::refuse_input_as_output(a.steps.as_deref(), &[&a.model, &a.session])?;
    let calibration: Calibration = a.calibration.parse()?;
    let (file, session) = load_pair(&a.model, &a.session)?;
    let rows = models::predict(&file, &session, calibration)?;
    if let Some(path) = &a.steps {
        let models::Model::Sequences(m) = &file.model else {
            bail!("--steps: only DS and GS models decide step by step");
        };
        let text = models::held_out::steps_csv(m, &session, calibration)?;
        crate::fsutil::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    crate::fsutil::write_atomic(
        &a.output,
        models::held_out::predictions_csv(&rows).as_bytes(),
    )
    .with_context(|| format!("writing {}", a.output.display()))?;
    println!(
        "{} grasps of {} predicted by {} (calibration {calibration}); wrote {}",
        rows.len(),
        session.meta.name,
        file.provenance.summary(),
        a.output.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::super::{Cli, Command};
    use super::*;

    fn parsed(args: &[&str]) -> Result<FitArgs, clap::Error> {
        let all = [&["tactile-workbench", "fit"], args].concat();
        match Cli::try_parse_from(all)?.command {
            Some(Command::Fit(a)) => Ok(a),
            other => panic!("not parsed as `fit`: {other:?}"),
        }
    }

    /// Every method of the catalogue is a `fit` subcommand by its key and its aliases, with
    /// the options of what it learns and reads.
    #[test]
    fn every_method_is_fitted_with_the_options_of_its_kind() {
        for m in MethodId::all() {
            let info = m.info();
            for name in std::iter::once(info.key).chain(info.aliases.iter().copied()) {
                let a = parsed(&[name, "s.json", "-o", "m.json"]).unwrap();
                assert_eq!(a.method, m, "`fit {name}`");
                let kind = match a.options {
                    FitOptions::Stability(_) => (Task::Stability, None),
                    FitOptions::Sequences(_) => (Task::Recognition, Some(Input::Sequences)),
                    FitOptions::Clusters(_) => (Task::Clustering, Some(Input::Sequences)),
                    FitOptions::TableOne(_) => (m.task(), Some(Input::TableOne)),
                    FitOptions::Registered(_) => {
                        assert!(m.classifier().is_some(), "{m}");
                        continue;
                    }
                };
                assert!(m.classifier().is_none(), "{m}");
                assert_eq!(kind.0, m.task(), "{m}");
                if let Some(input) = kind.1 {
                    assert_eq!(input, m.input(), "{m}");
                }
            }
        }
    }

    #[test]
    fn a_kinds_options_are_its_own() {
        // DS reads --capacity; DU does not, and k-means has no --threshold.
        let a = parsed(&["ds", "s.json", "-o", "m.json", "--capacity", "7"]).unwrap();
        assert!(matches!(a.options, FitOptions::Sequences(f) if f.capacity == Some(7)));
        assert!(parsed(&["du", "s.json", "-o", "m.json", "--capacity", "7"]).is_err());
        assert!(parsed(&["kmeans", "s.json", "-o", "m.json", "--threshold", "0.3"]).is_err());
        let a = parsed(&["gu", "s.json", "-o", "m.json", "--threshold", "0.3"]).unwrap();
        assert!(matches!(a.options, FitOptions::Clusters(f) if f.threshold == Some(0.3)));
        // A registered method's knob, and a name that is no method.
        let registered = MethodId::all().find_map(|m| m.classifier()).unwrap();
        let knob = registered.info().size_knobs[0].name;
        let a = parsed(&[
            registered.info().key,
            "s.json",
            "-o",
            "m.json",
            &format!("--{knob}"),
            "3",
        ])
        .unwrap();
        let FitOptions::Registered(m) = a.options else {
            panic!(
                "{} not fitted as a registered method",
                registered.info().key
            );
        };
        assert_eq!(m.get_one::<f64>(knob), Some(&3.0));
        assert!(parsed(&["no-such-method", "s.json", "-o", "m.json"]).is_err());
    }
}
