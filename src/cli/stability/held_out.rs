//! `bench-held-out`: each grasp-stability method fitted on a training session and evaluated
//! on held-out sessions under each calibration (by default the BioTac SP set v2's palm-45
//! pair, ten objects never seen in training).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;

use super::{in_pool, parse_cv};
use crate::catalogue::MethodId;
use crate::experiments::stability::{PipelineInputs, StabilityData};
use crate::models::{self, Calibration, HeldOutScores};
use crate::session;

/// The held-out benchmark of the BioTac SP set v2: palm-45 training and test files.
pub const BTS3V2_TRAIN: &str = "../shared/datasets/bts3v2/bts3v2_palm_45.csv";
pub const BTS3V2_TEST: &str = "../shared/datasets/bts3v2/bts3v2_palm_45_test.csv";

#[derive(Args, Debug)]
pub struct BenchHeldOutArgs {
    /// The training session.
    #[arg(default_value = BTS3V2_TRAIN)]
    pub train: PathBuf,
    /// Sessions to test on (default: the palm-45 test file of ten new objects).
    #[arg(default_value = BTS3V2_TEST)]
    pub test: Vec<PathBuf>,
    /// Calibrations to evaluate under, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "none,session,first:50,first:150"
    )]
    pub calibrations: Vec<String>,
    /// Fit the sparse pipeline by the default grid's parsimonious choice (selected by
    /// --cv on the training session) instead of its single default configuration.
    #[arg(long)]
    pub grid: bool,
    /// Selection protocol of the grid, as for `stability --cv`.
    #[arg(long, default_value = "10")]
    pub cv: String,
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Fit each grasp-stability method on a training session, evaluate it on test sessions
/// under each calibration, and print scores and times as a table.
pub fn bench_held_out(a: BenchHeldOutArgs) -> anyhow::Result<()> {
    let calibrations = a
        .calibrations
        .iter()
        .map(|c| c.parse::<Calibration>())
        .collect::<Result<Vec<_>, _>>()?;
    let train =
        session::open(&a.train).with_context(|| format!("opening {}", a.train.display()))?;
    let tests = a
        .test
        .iter()
        .map(|p| session::open(p).with_context(|| format!("opening {}", p.display())))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let data = StabilityData::from_session(&train, &Default::default())?;
    let mut opts = crate::experiments::stability::StabilityOptions {
        selection_cv: parse_cv(&a.cv)?,
        ..Default::default()
    };
    if a.grid {
        opts.grid = Some(crate::experiments::stability::GridSpec::default_for(&data));
    }
    println!(
        "| method | trained on | 10-fold | leave objects out | fit s | tested on | calibration | WSR | failure recall | evaluate s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let pipelines = [
        (MethodId::RawSvm, PipelineInputs::Codes),
        (MethodId::SparseSvm, PipelineInputs::Codes),
        (MethodId::SparseSvm, PipelineInputs::CodesAndRaw),
    ];
    for (method, inputs) in pipelines {
        opts.settings.inputs = inputs;
        let fit = in_pool(a.threads, || {
            models::fit_stability(method, &train, &data, &opts, &crate::jobs::Progress::new())
        })??;
        let file = fit.into_file(&train, &data);
        let p = &file.provenance;
        let score = |i: usize| p.selection.get(i).map_or(f64::NAN, |s| s.value);
        for (test, path) in tests.iter().zip(&a.test) {
            for &c in &calibrations {
                let r = models::evaluate(&file, test, c)
                    .with_context(|| format!("evaluating on {}", path.display()))?;
                let HeldOutScores::Stability {
                    weighted_success_rate,
                    failure_recall,
                    ..
                } = r.scores
                else {
                    bail!("{} is not a grasp-stability model", method.key());
                };
                println!(
                    "| {} | {} | {:.3} | {:.3} | {:.2} | {} | {c} | {:.3} | {:.3} | {:.3} |",
                    p.summary().split(", trained on").next().unwrap_or_default(),
                    session::file_name(&a.train),
                    score(0),
                    score(1),
                    p.train_seconds,
                    session::file_name(path),
                    weighted_success_rate,
                    failure_recall,
                    r.secs
                );
            }
        }
    }
    Ok(())
}
