//! Models that leave their session: `fit` a method on a session into a model file,
//! `evaluate` it on another session, and `predict` a session's grasps.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;

use super::fit_args::{
    FitArgs, FitClusterArgs, FitOptions, FitSequenceArgs, FitStabilityArgs, FitTableOneArgs,
};
use super::progress::with_progress;
use super::stability::{data_options, in_pool, options_from};
use crate::catalogue::MethodId;
use crate::experiments::feature_choice::FeatureChoice;
use crate::experiments::result::figure_set;
use crate::experiments::stability::StabilityData;
use crate::figures::{Format, RenderOptions, export_all};
use crate::models::{self, Calibration, HeldOutScores, ModelFile};
use crate::session::{self, Session};

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
