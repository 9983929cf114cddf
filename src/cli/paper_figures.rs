//! `paper-figures`: run an experiment headless and write every figure of it (SVG, PNG,
//! CSV and an index), so a paper's figures are regenerated in one command.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::figures::Preset;
use super::progress::with_progress;
use super::recognition::open_session;
use crate::catalogue::MethodId;
use crate::experiments::baselines::baselines_report;
use crate::experiments::baselines::{BaselinesParams, grid_for, run_baselines};
use crate::experiments::clustering::report::clustering_report;
use crate::experiments::clustering::{ClusteringParams, UnsupervisedLearner, run_clustering};
use crate::experiments::frontier::report::frontier_figures;
use crate::experiments::frontier::{Frontier, FrontierParams, run_frontier};
use crate::experiments::recognition::report::{comparison_figures, recognition_report};
use crate::experiments::recognition::{RecognitionParams, SupervisedLearner, run_recognition};
use crate::experiments::result::{AnalysisResult, figure_set, speed_accuracy_figures};
use crate::experiments::robustness::report::robustness_report;
use crate::experiments::robustness::{Family, RobustnessParams, run_robustness};
use crate::experiments::stability::report::stability_report;
use crate::experiments::stability::{
    self, DataOptions, GridSpec, PipelineSettings, StabilityData, StabilityOptions,
};
use crate::features::FeatureSet;
use crate::features::table_one::session_features;
use crate::figures::{FigureEntry, FigureSet, Format, RenderOptions, export_all};
use crate::jobs::Progress;
use crate::project::Project;
use crate::session::Session;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Experiment {
    /// DS and GS on all, tactile and encoder features; noise σ² 100 and 1000 (Figs. 6–9).
    Recognition,
    /// DU and GU threshold sweeps with k-means and SOM (Figs. 11–13, Table IV).
    Clustering,
    /// k-means, SOM and RBF SVM on the Table I features.
    Baselines,
    /// Grasp stability by sparse coding and a linear SVM over the 108-cell benchmark grid
    /// (the first paper's Figs. 2 and 5–11); --reps does not apply.
    Stability,
    /// Where sparse coding + SVM and the raw SVM fail: every perturbation at its default
    /// strengths (`--reps` per strength; 5–10 is plenty).
    RobustnessStability,
    /// Where DS and GS fail: every perturbation at its default strengths.
    RobustnessRecognition,
    /// Speed against accuracy by model size, with the recommended sizes: for a session
    /// with an `object` label set DS and GS on all and encoder features, DU, GU, k-means,
    /// the SOM and the RBF SVM; else sparse coding + SVM (`--reps` per size; 10 is plenty).
    Frontier,
}

#[derive(Args, Debug)]
pub struct PaperFiguresArgs {
    /// Session: a native file, a BTS3 CSV or the iCub dataset folder.
    pub session: PathBuf,
    #[arg(long, value_enum)]
    pub experiment: Experiment,
    /// Output folder (created if missing).
    #[arg(short, long)]
    pub out_dir: PathBuf,
    /// Repetitions (seeded orders); the papers use 50.
    #[arg(long, default_value_t = 50)]
    pub reps: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// A size for a paper (a 3.5-in column or a 7-in page at 300 DPI); replaces --width,
    /// --height and --dpi.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    #[arg(long, default_value_t = 640)]
    pub height: u32,
    #[arg(long, default_value_t = 96.0)]
    pub dpi: f64,
    /// Also save the results as a project, to inspect them in the workbench.
    #[arg(long)]
    pub project: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: PaperFiguresArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(Some(&a.out_dir), &[&a.session])?;
    super::refuse_input_as_output(a.project.as_deref(), &[&a.session])?;
    super::bounds::at_most("--reps", a.reps, super::bounds::MAX_REPS)?;
    let set = figures(&a)?;
    let opts = a.preset.map_or(
        RenderOptions {
            width: a.width,
            height: a.height,
            dpi: a.dpi,
        },
        Preset::options,
    );
    let t0 = std::time::Instant::now();
    // Into a temporary folder put in place at the end: a killed run never leaves a folder
    // of figures without its index.
    let index = crate::fsutil::write_dir_atomic(&a.out_dir, &["index.md"], |dir| {
        anyhow::Ok(export_all(
            &set,
            dir,
            &[Format::Svg, Format::Pdf, Format::Png, Format::Csv],
            &opts,
        )?)
    })?;
    println!(
        "wrote {} figures to {} in {:.2} s",
        index.entries.len(),
        a.out_dir.display(),
        t0.elapsed().as_secs_f64()
    );
    if !index.not_drawn.is_empty() {
        anyhow::bail!(
            "{} figure{} could not be drawn at this size (the others are written, see index.md): {}",
            index.not_drawn.len(),
            if index.not_drawn.len() == 1 { "" } else { "s" },
            index.not_drawn_text()
        );
    }
    Ok(())
}

/// Run the experiment and gather every figure of it (saving the project when asked).
pub fn figures(a: &PaperFiguresArgs) -> anyhow::Result<FigureSet> {
    let session = open_session(&a.session)?;
    let name = session.meta.name.clone();
    let (results, frontiers) = with_progress(a.quiet, |p| experiment_results(a, &session, p))?;
    if let Some(path) = &a.project {
        Project::new(vec![a.session.display().to_string()], results.clone())
            .with_frontiers(frontiers.clone())
            .save(path)?;
        println!("wrote {}", path.display());
    }
    let mut set = figure_set(&results);
    let extra = speed_accuracy_figures(&results)
        .into_iter()
        .chain(comparison_figures(&results))
        .chain(grouped_frontier_figures(&frontiers));
    for (figure_name, f) in extra {
        set.entries.push(FigureEntry {
            name: figure_name,
            figure: f,
            parameters: Default::default(),
            session: name.clone(),
            date: crate::experiments::result::date_text(crate::experiments::result::now_unix()),
        });
    }
    Ok(set)
}

/// The frontiers' figures, one set per score and time unit (DS/GS accuracy per step; the
/// clusterers' NMI per grasp; ...), named `frontier-…` with the score's group when there
/// are several.
fn grouped_frontier_figures(frontiers: &[Frontier]) -> Vec<(String, crate::figures::Figure)> {
    let mut groups: Vec<((String, String), Vec<Frontier>)> = Vec::new();
    for f in frontiers {
        let key = (f.score_name.clone(), f.unit.clone());
        match groups.iter_mut().find(|g| g.0 == key) {
            Some(g) => g.1.push(f.clone()),
            None => groups.push((key, vec![f.clone()])),
        }
    }
    let several = groups.len() > 1;
    groups
        .into_iter()
        .flat_map(|((score, _), fs)| {
            let tag: String = score
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() {
                        c.to_ascii_lowercase()
                    } else {
                        '-'
                    }
                })
                .collect::<String>()
                .split('-')
                .filter(|w| !w.is_empty())
                .collect::<Vec<_>>()
                .join("-");
            frontier_figures(&fs).into_iter().map(move |(name, fig)| {
                let name = match name.strip_prefix("frontier-") {
                    Some(rest) if several => format!("frontier-{tag}-{rest}"),
                    _ => name,
                };
                (name, fig)
            })
        })
        .collect()
}

/// Run the experiment's analyses (and, for `frontier`, its frontiers).
fn experiment_results(
    a: &PaperFiguresArgs,
    session: &Session,
    progress: &Progress,
) -> anyhow::Result<(Vec<AnalysisResult>, Vec<Frontier>)> {
    let mut frontiers = Vec::new();
    let name = session.meta.name.clone();
    let mut results: Vec<AnalysisResult> = Vec::new();
    match a.experiment {
        Experiment::Recognition => {
            let mut settings = Vec::new();
            for learner in [SupervisedLearner::Ds, SupervisedLearner::Gs] {
                for features in [FeatureSet::ALL, FeatureSet::MOMENTS, FeatureSet::ENCODERS] {
                    settings.push((learner, features, 0.0));
                }
                for noise in [100.0, 1000.0] {
                    settings.push((learner, FeatureSet::ALL, noise));
                }
            }
            for (learner, features, noise) in settings {
                let params = RecognitionParams {
                    learner,
                    features,
                    reps: a.reps,
                    seed: a.seed,
                    taxel_noise_variance: noise,
                    ..Default::default()
                };
                let r = run_recognition(session, &params, progress)?;
                let report = recognition_report(&name, &r);
                eprintln!("{}: final 20% {:.3}", report.label, r.summary.final_20.mean);
                results.push(report);
            }
        }
        Experiment::Clustering => {
            for learner in [UnsupervisedLearner::Du, UnsupervisedLearner::Gu] {
                let params = ClusteringParams {
                    reps: a.reps,
                    seed: a.seed,
                    ..ClusteringParams::for_learner(learner)
                };
                let r = run_clustering(session, &params, progress)?;
                let report = clustering_report(&name, &r);
                eprintln!("{}: done in {:.1} s", report.label, r.wall_seconds);
                results.push(report);
            }
        }
        Experiment::Baselines => {
            let set = session
                .label_set("object")
                .ok_or_else(|| anyhow::anyhow!("the session has no `object` label set"))?;
            let truth = session.labels_of(set);
            let features = session_features(session)?;
            let (rows, cols) = grid_for(10);
            let mut params = BaselinesParams {
                orders: a.reps,
                seed: a.seed,
                ..Default::default()
            };
            params.som.rows = rows;
            params.som.cols = cols;
            let t0 = std::time::Instant::now();
            let r = run_baselines(features.view(), &truth, &params, progress)?;
            results.push(baselines_report(&name, &r, t0.elapsed().as_secs_f64()));
        }
        Experiment::Stability => {
            let data = StabilityData::from_session(session, &DataOptions::default())?;
            let mut settings = PipelineSettings {
                cv_seed: a.seed,
                ..Default::default()
            };
            settings.dictionary.seed = a.seed;
            settings.svm.seed = a.seed;
            let opts = StabilityOptions {
                grid: Some(GridSpec::bench()),
                settings,
                ..Default::default()
            };
            let r = stability::run(&data, &opts, progress)?;
            let report = stability_report(&r);
            eprintln!("{}: done in {:.1} s", report.label, r.secs);
            results.push(report);
        }
        Experiment::RobustnessStability | Experiment::RobustnessRecognition => {
            let family = if a.experiment == Experiment::RobustnessStability {
                Family::Stability
            } else {
                Family::Recognition
            };
            let params = RobustnessParams {
                reps: a.reps,
                seed: a.seed,
                ..RobustnessParams::defaults(family)
            };
            let r = run_robustness(session, &params, progress)?;
            eprint!("{}", super::robustness::table(&r));
            results.push(robustness_report(&name, &r));
        }
        Experiment::Frontier => {
            let methods: &[(MethodId, FeatureSet)] = if session.label_set("object").is_some() {
                &[
                    (MethodId::Ds, FeatureSet::ALL),
                    (MethodId::Ds, FeatureSet::ENCODERS),
                    (MethodId::Gs, FeatureSet::ALL),
                    (MethodId::Gs, FeatureSet::ENCODERS),
                    (MethodId::Du, FeatureSet::ALL),
                    (MethodId::Gu, FeatureSet::ALL),
                    (MethodId::KMeans, FeatureSet::ALL),
                    (MethodId::Som, FeatureSet::ALL),
                    (MethodId::RbfSvm, FeatureSet::ALL),
                ]
            } else {
                &[(MethodId::SparseSvm, FeatureSet::ALL)]
            };
            for &(method, features) in methods {
                let params = FrontierParams {
                    features,
                    reps: a.reps,
                    seed: a.seed,
                    ..FrontierParams::for_method(method)
                };
                let f = run_frontier(session, &params, progress)?;
                super::frontier::print_frontier(&f);
                frontiers.push(f);
            }
        }
    }
    Ok((results, frontiers))
}
