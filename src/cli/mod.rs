//! The headless command line: the same binary as the window, with subcommands.
//! Each subcommand lives in its own file with its `clap::Args` struct and a `run`.

pub mod baselines;
pub mod bounds;
pub mod figures;
pub mod fit_args;
pub mod frontier;
pub mod live;
pub mod model;
pub mod paper_figures;
mod progress;
pub mod recognition;
pub mod robustness;
pub mod session;
pub mod simulate;
pub mod stability;
pub mod sweep;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "tactile-workbench",
    version,
    about = "Learn from robot touch: open the workbench, or run a headless command",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Session files to open in the workbench (with no subcommand).
    pub files: Vec<PathBuf>,
    /// Open the window, print the time to the first frame and to the sessions shown, and
    /// quit (a startup benchmark).
    #[arg(long)]
    pub measure_startup: bool,
    /// Open the window, run a 108-cell grid search on the grasp-stability sample in its view,
    /// print the UI time per frame over at most SECONDS, and quit (a frame-time benchmark).
    #[arg(long, value_name = "SECONDS")]
    pub measure_frames: Option<f64>,
    /// The view to open in the workbench (default: the one of the last run).
    #[arg(long, value_enum)]
    pub view: Option<View>,
}

/// The views of the workbench's central area; `--view` names them in kebab case. Defined
/// here, not in `app`, so that the command line parses them without the `gui` feature.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
pub enum View {
    #[default]
    Replay,
    Stability,
    Recognition,
    Clustering,
    Baselines,
    SpeedAccuracy,
    Robustness,
    Live,
    Compare,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print a summary of a session file.
    Info(session::InfoArgs),
    /// Check session files: format, version and every count and value.
    Validate(session::ValidateArgs),
    /// Convert a real dataset to the native format.
    Import(session::ImportArgs),
    /// Regenerate the sample sessions from a seed.
    Simulate(simulate::SimulateArgs),
    /// Run an experiment and write all its figures (SVG, PNG, CSV, index).
    PaperFigures(paper_figures::PaperFiguresArgs),
    /// Render a figure saved as JSON to SVG, PNG or CSV.
    RenderFigure(figures::RenderFigureArgs),
    /// Sequential k-means, SOM and RBF SVM baselines on the per-grasp Table I features.
    Baselines(baselines::BaselinesArgs),
    /// Online object recognition (DS/GS) under the paper's supervised protocol.
    Recognition(recognition::RecognitionArgs),
    /// Online clustering (DU/GU) over a novelty-threshold sweep, with k-means and SOM.
    Clustering(recognition::ClusteringArgs),
    /// Time per-observation prediction/training and the Table II protocol.
    BenchRecognition(recognition::BenchArgs),
    /// Grasp stability by sparse coding and a linear SVM (the first paper): grid search,
    /// 10-fold and leave-objects-out scores, the raw-value baseline and the analyses.
    Stability(stability::StabilityArgs),
    /// Time the grasp-stability pipeline on BTS3 palm-down (dictionary, coding, CV, grid).
    BenchStability(stability::BenchStabilityArgs),
    /// Where the methods fail: sweep one perturbation at a time (noise, dead taxels, drift,
    /// gain, truncation, ...) and print each method's break point.
    Robustness(robustness::RobustnessArgs),
    /// Speed against accuracy by model size: sweep a method's size knobs, score each size
    /// over seeded repetitions, and recommend the cheapest within one standard error of
    /// the best.
    Frontier(frontier::FrontierArgs),
    /// Fit a method on a session and save the model file (evaluate it elsewhere).
    Fit(fit_args::FitArgs),
    /// A model's scores on a session it did not train on, with every grasp's prediction.
    Evaluate(model::EvaluateArgs),
    /// A model's prediction for every grasp of a session, as CSV.
    Predict(model::PredictArgs),
    /// A session of some grasps of another (objects, trials, labels).
    Subset(session::SubsetArgs),
    /// Fit the grasp-stability methods on a training session and evaluate them on held-out
    /// sessions under each calibration: scores and times (default: BTS3 v2 palm-45).
    BenchHeldOut(stability::BenchHeldOutArgs),
    /// Read a robot's live stream (Foxglove WebSocket protocol): a line per grasp with the
    /// model's verdict, the grasps recorded as a session.
    Live(live::LiveArgs),
    /// Publish a recorded session as a live stream on the Foxglove SDK's server.
    Serve(live::ServeArgs),
    /// Sharded sweeps for a cluster: plan the shards and a Slurm job array, run a shard,
    /// show their status, merge them into the single-machine result.
    Sweep(sweep::SweepArgs),
}

/// Refuse, before any work, an output (`-o`, `--json`, `--project`, an output folder) that
/// is one of the command's inputs: writing it would destroy the input.
pub(crate) fn refuse_input_as_output(
    output: Option<&std::path::Path>,
    inputs: &[&std::path::Path],
) -> anyhow::Result<()> {
    if let Some(out) = output {
        crate::fsutil::refuse_input_as_output(out, inputs)?;
    }
    Ok(())
}

/// Run a subcommand.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Info(a) => session::info(a),
        Command::Validate(a) => session::validate(a),
        Command::Import(a) => session::import(a),
        Command::Simulate(a) => simulate::run(a),
        Command::PaperFigures(a) => paper_figures::run(a),
        Command::RenderFigure(a) => figures::run(a),
        Command::Baselines(a) => baselines::run(a),
        Command::Recognition(a) => recognition::recognition(a),
        Command::Clustering(a) => recognition::clustering(a),
        Command::BenchRecognition(a) => recognition::bench(a),
        Command::Stability(a) => stability::run(a),
        Command::BenchStability(a) => stability::run_bench(a),
        Command::Robustness(a) => robustness::run(a),
        Command::Frontier(a) => frontier::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Fit(a) => model::fit(a),
        Command::Evaluate(a) => model::evaluate(a),
        Command::Predict(a) => model::predict(a),
        Command::Subset(a) => session::subset(a),
        Command::BenchHeldOut(a) => stability::bench_held_out(a),
        Command::Live(a) => live::live(a),
        Command::Serve(a) => live::serve(a),
    }
}

/// The one line an error prints as: its message, then each cause in its chain that the
/// message does not already say. The engine's errors show their source in their own message
/// and keep it as the source too (`crate::error`), so a plain walk of the chain would repeat
/// it; a context added here (`anyhow::Context`) does not say its cause, so it follows.
pub fn error_line(e: &anyhow::Error) -> String {
    let mut line = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
    }
    line
}

#[cfg(test)]
mod error_line_tests {
    use super::error_line;
    use anyhow::Context;

    #[derive(Debug, thiserror::Error)]
    #[error("lower")]
    struct Lower;

    #[derive(Debug, thiserror::Error)]
    #[error("upper: {0}")]
    struct Upper(#[source] Lower);

    #[test]
    fn a_cause_already_in_the_message_is_not_repeated_and_a_context_keeps_its_cause() {
        let e = anyhow::Error::from(Upper(Lower));
        assert_eq!(error_line(&e), "upper: lower");
        let e: anyhow::Error = Err::<(), _>(Upper(Lower)).context("reading x").unwrap_err();
        assert_eq!(error_line(&e), "reading x: upper: lower");
    }
}
