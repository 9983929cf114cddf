//! `bench-recognition`: the cost of a step of the recognition learners, on synthetic
//! sequences and on a session, beside the figures of the authors' C++ library (libOTL).

use std::path::{Path, PathBuf};

use clap::Args;

use super::{open_session, write_json};
use crate::experiments::recognition::{
    RecognitionParams, SessionBenchParams, SessionStepBench, StepBench, StepBenchParams,
    SupervisedLearner, bench_session_steps, bench_steps, run_recognition,
};
use crate::jobs::Progress;
use crate::session::Session;

/// The session timed when none is given: the iCub dataset beside the checkout, if present.
const DEFAULT_BENCH_SESSION: &str = "../shared/datasets/icub-grasp";

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Time the steps on this session (native file or iCub folder; default: the iCub
    /// dataset at ../shared/datasets/icub-grasp when present).
    pub session: Option<PathBuf>,
    /// Protocol orders over which the session's steps are timed.
    #[arg(long, default_value_t = 3)]
    pub session_reps: usize,
    /// Also time the whole Table II protocol on the session.
    #[arg(long)]
    pub protocol: bool,
    /// Repetitions of the protocol timing.
    #[arg(long, default_value_t = 50)]
    pub reps: usize,
    /// BV budgets of the per-step scaling (at the default tau).
    #[arg(long, value_delimiter = ',', default_value = "10,25,50,100")]
    pub budgets: Vec<usize>,
    /// Kernel lags of the per-step scaling (at the default budget).
    #[arg(long, value_delimiter = ',', default_value = "5,15,30")]
    pub taus: Vec<usize>,
    /// Learners to time: ds, gs or both.
    #[arg(long, value_delimiter = ',', default_value = "ds,gs")]
    pub learners: Vec<String>,
    /// Timed sequences per setting (20 steps each; more gives steadier figures).
    #[arg(long, default_value_t = 60)]
    pub sequences: usize,
    /// Skip the per-step timings on synthetic sequences.
    #[arg(long)]
    pub no_steps: bool,
    /// Skip the steps timed beside libOTL's figures on the session.
    #[arg(long)]
    pub no_anchor: bool,
    /// Skip the DS and GS steps on the session with and without adaptation.
    #[arg(long)]
    pub no_session_steps: bool,
    /// Write the measurements here as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(serde::Serialize)]
struct BenchReport {
    steps: Vec<StepBench>,
    session_steps: Vec<SessionStepBench>,
    protocol: Vec<ProtocolTiming>,
    anchor: Option<crate::experiments::recognition::AnchorBench>,
    threads: usize,
}

#[derive(serde::Serialize)]
struct ProtocolTiming {
    learner: String,
    features: String,
    reps: usize,
    wall_seconds: f64,
    cpu_seconds: Option<f64>,
    all: f64,
    final_20: f64,
}

pub fn bench(args: BenchArgs) -> anyhow::Result<()> {
    let inputs: Vec<&Path> = args.session.as_deref().into_iter().collect();
    crate::cli::refuse_input_as_output(args.json.as_deref(), &inputs)?;
    {
        use crate::cli::bounds::{MAX_CAPACITY, MAX_REPS, MAX_TAU, all_at_most, at_most};
        at_most("--reps", args.reps, MAX_REPS)?;
        at_most("--session-reps", args.session_reps, MAX_REPS)?;
        all_at_most("--budgets", &args.budgets, MAX_CAPACITY)?;
        all_at_most("--taus", &args.taus, MAX_TAU)?;
    }
    println!("per observation, one thread (34 inputs, 10 classes, adaptation on unless noted):");
    let learners = args
        .learners
        .iter()
        .map(|l| l.parse::<SupervisedLearner>())
        .collect::<Result<Vec<_>, _>>()?;
    let base = StepBenchParams {
        sequences: args.sequences,
        ..StepBenchParams::default()
    };
    let steps = synthetic_steps(&args, &learners, &base)?;
    let path = args.session.clone().or_else(|| {
        let p = PathBuf::from(DEFAULT_BENCH_SESSION);
        p.exists().then_some(p)
    });
    let session = path.as_deref().map(open_session).transpose()?;
    let shown = path.as_deref().map(|p| p.display().to_string());
    let anchor = match &session {
        Some(session) if !args.no_anchor => {
            let a = crate::experiments::recognition::anchor_steps(
                session,
                base.capacity,
                base.tau,
                args.session_reps,
            )?;
            print_anchor(&a);
            Some(a)
        }
        _ => None,
    };
    let session_steps = match session.as_ref().filter(|_| !args.no_session_steps) {
        Some(session) => {
            session_steps(session, &shown.unwrap_or_default(), &args, &learners, &base)?
        }
        None => Vec::new(),
    };
    let protocol = match session.as_ref().filter(|_| args.protocol) {
        Some(session) => protocol_timings(session, &args, &learners)?,
        None => Vec::new(),
    };
    write_json(
        &BenchReport {
            steps,
            session_steps,
            protocol,
            anchor,
            threads: rayon::current_num_threads(),
        },
        args.json.as_deref(),
    )
}

/// Each learner's steps on synthetic sequences: over the budgets, the lags other than
/// `base`'s, and without adaptation (none with `--no-steps`); printed as they come.
fn synthetic_steps(
    args: &BenchArgs,
    learners: &[SupervisedLearner],
    base: &StepBenchParams,
) -> anyhow::Result<Vec<StepBench>> {
    let mut steps = Vec::new();
    let mut configs = Vec::new();
    if !args.no_steps {
        for &capacity in &args.budgets {
            configs.push(StepBenchParams {
                capacity,
                ..base.clone()
            });
        }
        for &tau in args.taus.iter().filter(|&&t| t != base.tau) {
            configs.push(StepBenchParams {
                tau,
                ..base.clone()
            });
        }
        configs.push(StepBenchParams {
            adaptation: false,
            ..base.clone()
        });
    }
    for p in configs {
        for &learner in learners {
            let b = bench_steps(learner, &p)?;
            let cpu = |v: Option<f64>| v.map_or("?".to_string(), |v| format!("{v:.0}"));
            println!(
                "  {:?} budget {:>3} tau {:>2} adapt {:<5}: predict {:>7.1} µs/step (cpu {}), train {:>7.1} µs/step (cpu {})  ({:.0} BVs, {} adapting)",
                learner,
                p.capacity,
                p.tau,
                p.adaptation,
                b.predict_step_us,
                cpu(b.predict_step_cpu_us),
                b.train_step_us,
                cpu(b.train_step_cpu_us),
                b.mean_basis,
                b.adapting
            );
            steps.push(b);
        }
    }
    Ok(steps)
}

/// Each learner's steps on the session (`shown` names it), with and without adaptation,
/// once every expert is full; printed as they come.
fn session_steps(
    session: &Session,
    shown: &str,
    args: &BenchArgs,
    learners: &[SupervisedLearner],
    base: &StepBenchParams,
) -> anyhow::Result<Vec<SessionStepBench>> {
    let mut session_steps = Vec::new();
    println!(
        "per step on {} once every expert is full (all features, capacity {}, tau {}, {} orders, one thread), µs median [p10, p90]:",
        shown, base.capacity, base.tau, args.session_reps
    );
    for adaptation in [true, false] {
        for &learner in learners {
            let b = bench_session_steps(
                session,
                &SessionBenchParams {
                    learner,
                    capacity: base.capacity,
                    tau: base.tau,
                    adaptation,
                    reps: args.session_reps,
                    seed: 0,
                },
            )?;
            println!(
                "  {:?} adapt {:<5}: predict {:>6.1} [{:.1}, {:.1}], train {:>6.1} [{:.1}, {:.1}]  ({} steps; {} of {} experts adapting at the end)",
                learner,
                adaptation,
                b.predict.median,
                b.predict.p10,
                b.predict.p90,
                b.train.median,
                b.train.p10,
                b.train.p90,
                b.train.steps,
                b.adapting,
                b.experts
            );
            session_steps.push(b);
        }
    }
    Ok(session_steps)
}

/// The whole Table II protocol on the session for each learner, timed; printed as they
/// come.
fn protocol_timings(
    session: &Session,
    args: &BenchArgs,
    learners: &[SupervisedLearner],
) -> anyhow::Result<Vec<ProtocolTiming>> {
    let mut protocol = Vec::new();
    for &learner in learners {
        let p = RecognitionParams {
            learner,
            reps: args.reps,
            ..RecognitionParams::default()
        };
        let r = run_recognition(session, &p, &Progress::new())?;
        println!(
            "  Table II protocol {:?}/all, {} reps: {:.1} s wall, {:.1} s CPU ({} threads)",
            learner,
            args.reps,
            r.wall_seconds,
            r.cpu_seconds.unwrap_or(f64::NAN),
            rayon::current_num_threads()
        );
        protocol.push(ProtocolTiming {
            learner: format!("{learner:?}"),
            features: "all".into(),
            reps: args.reps,
            wall_seconds: r.wall_seconds,
            cpu_seconds: r.cpu_seconds,
            all: r.summary.all.mean,
            final_20: r.summary.final_20.mean,
        });
    }
    Ok(protocol)
}

fn print_anchor(a: &crate::experiments::recognition::AnchorBench) {
    println!(
        "the steps libOTL was timed on (DS experts, no adaptation, capacity {}, tau {}, {} orders, one thread), µs median [p10, p90]:",
        a.capacity, a.tau, a.orders
    );
    // libOTL's figures were measured on another machine, under another load: they are
    // shown for orientation and never divided into this run's.
    println!(
        "  (libOTL: {})",
        crate::experiments::recognition::LIBOTL_MEASURED
    );
    let rows = [
        ("one update alone", &a.ours.update, a.libotl.update),
        ("10-class prediction", &a.ours.predict, a.libotl.predict),
        ("DS training step", &a.ours.ds_train, a.libotl.ds_train),
        (
            "every expert updated",
            &a.ours.all_updated,
            a.libotl.all_updated,
        ),
    ];
    for (name, t, theirs) in rows {
        println!(
            "  {name:<21} {:>7.1} [{:.1}, {:.1}]  ({} steps)   libOTL, measured elsewhere: {theirs:.0}",
            t.median, t.p10, t.p90, t.steps
        );
    }
    let list = |v: &[usize]| {
        v.iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !a.inputs_held.is_empty() {
        let factor = a.inputs_summed.iter().sum::<usize>() as f64
            / a.inputs_held.iter().sum::<usize>().max(1) as f64;
        println!(
            "  distinct inputs at the end of each order: {} summed over the experts, {} held once in their shared table ({factor:.1}× fewer new distances per step)",
            list(&a.inputs_summed),
            list(&a.inputs_held)
        );
    }
}
