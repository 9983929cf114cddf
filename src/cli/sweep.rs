//! `sweep plan | run | status | merge`: an experiment sharded over a Slurm job array (or
//! any machines), merged back into the single-machine result. See docs/cluster.md.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use super::frontier::FrontierArgs;
use super::progress::with_progress;
use super::recognition::{ClusteringArgs, RecognitionArgs, open_session};
use super::robustness::{RobustnessArgs, params_of};
use super::stability::{StabilityArgs, data_options, in_pool, options_from};
use crate::experiments::stability::StabilityData;
use crate::project::Project;
use crate::session::Session;
use crate::sweep::{
    self, Experiment, FrontierSweep, PlanRequest, ShardRun, ShardState, StabilitySweep, describe,
    rerun_commands,
};

#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(subcommand)]
    pub command: SweepCommand,
}

#[derive(Subcommand, Debug)]
pub enum SweepCommand {
    /// Split an experiment into shards: write DIR/plan.json, a copy of the session and
    /// DIR/sweep.sbatch (a Slurm job array, one task per shard).
    Plan(Box<PlanArgs>),
    /// Compute one shard and write DIR/shards/I.json (skipped when already done).
    Run(RunArgs),
    /// Print which shards are done, missing or failed.
    Status(StatusArgs),
    /// Merge the shards into the single-machine result.
    Merge(MergeArgs),
}

#[derive(Args, Debug)]
pub struct PlanArgs {
    #[command(subcommand)]
    pub experiment: PlanExperiment,
}

/// The experiment to shard, with its own command's options.
#[derive(Subcommand, Debug)]
pub enum PlanExperiment {
    /// The grasp-stability grid search (items: one dictionary per num_bases × beta), then
    /// the pipeline's evaluation at the merge.
    Stability {
        #[command(flatten)]
        args: StabilityArgs,
        #[command(flatten)]
        plan: PlanOptions,
    },
    /// The robustness sweep (items: one strength of one perturbation, one repetition).
    Robustness {
        #[command(flatten)]
        args: RobustnessArgs,
        #[command(flatten)]
        plan: PlanOptions,
    },
    /// The clustering threshold sweep (items: one threshold, one order; and the baselines'
    /// runs).
    Clustering {
        #[command(flatten)]
        args: ClusteringArgs,
        #[command(flatten)]
        plan: PlanOptions,
    },
    /// Supervised recognition (items: one repetition).
    Recognition {
        #[command(flatten)]
        args: RecognitionArgs,
        #[command(flatten)]
        plan: PlanOptions,
    },
    /// Speed–accuracy frontiers (items: one repetition at one size; sparse coding: one
    /// dictionary); the merge writes the `frontier --json` list.
    Frontier {
        #[command(flatten)]
        args: FrontierArgs,
        #[command(flatten)]
        plan: PlanOptions,
    },
}

#[derive(Args, Debug)]
pub struct PlanOptions {
    /// Number of shards (array tasks).
    #[arg(long)]
    pub shards: usize,
    /// The plan directory (created; it must not hold a plan).
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Time limit of each task in minutes (default: estimated from the work).
    #[arg(long, value_name = "MINUTES")]
    pub time: Option<u64>,
    /// CPUs per task (default 2).
    #[arg(long)]
    pub cpus: Option<usize>,
    /// Memory per task in MB (default: estimated from the session).
    #[arg(long, value_name = "MB")]
    pub mem: Option<u64>,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// The program the tasks run (default: this program's path).
    #[arg(long)]
    pub program: Option<String>,
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// The plan directory.
    pub dir: PathBuf,
    /// The shard to compute (Slurm: $SLURM_ARRAY_TASK_ID).
    #[arg(long)]
    pub shard: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The plan directory.
    pub dir: PathBuf,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The plan directory.
    pub dir: PathBuf,
    /// Write the merged result here (the single-machine command's JSON).
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Also save it as a project, to open in the workbench.
    #[arg(long)]
    pub project: Option<PathBuf>,
    /// Check the merged result against this result of the single-machine command (the
    /// same options and seeds): fail unless they are equal, timings aside.
    #[arg(long, value_name = "LOCAL.json")]
    pub expect: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: SweepArgs) -> anyhow::Result<()> {
    match a.command {
        SweepCommand::Plan(p) => plan(*p),
        SweepCommand::Run(r) => run_shard(r),
        SweepCommand::Status(s) => status(s),
        SweepCommand::Merge(m) => merge(m),
    }
}

fn no_json(json: &Option<PathBuf>) -> anyhow::Result<()> {
    if json.is_some() {
        bail!("a plan writes no result: give the result's file to `sweep merge -o`");
    }
    Ok(())
}

/// The experiment the arguments describe and the session it runs on.
fn experiment_of(e: &PlanExperiment) -> anyhow::Result<(Experiment, Session, &PathBuf)> {
    Ok(match e {
        PlanExperiment::Stability { args, .. } => {
            no_json(&args.json)?;
            if args.save_model.is_some() {
                bail!(
                    "a plan saves no model: `fit sparse-svm` with the merged result's configuration does"
                );
            }
            let session = super::stability::open(&args.session)?;
            let data = data_options(args);
            let prepared = StabilityData::from_session(&session, &data)?;
            let options = options_from(args, &prepared)?;
            if options.grid.is_none() {
                bail!("one configuration is one item: give a grid (--grid or lists) to shard");
            }
            (
                Experiment::Stability(StabilitySweep { data, options }),
                session,
                &args.session,
            )
        }
        PlanExperiment::Robustness { args, .. } => {
            no_json(&args.json)?;
            if args.threads.is_some() {
                bail!("--threads: a plan runs nothing; give the tasks' CPUs with --cpus");
            }
            let params = params_of(args)?;
            (
                Experiment::Robustness(params),
                open_session(&args.session)?,
                &args.session,
            )
        }
        PlanExperiment::Clustering { args, .. } => {
            no_json(&args.json)?;
            if args.save_model.is_some() {
                bail!("a plan saves no model: `fit du|gu --threshold T` on the session does");
            }
            let session = open_session(&args.session)?;
            let params = args.params()?;
            let (params, choice) = with_progress(args.quiet, |p| {
                crate::experiments::clustering::choose_auto_features(&session, &params, p)
            })?;
            plan_choice(choice.as_ref());
            (Experiment::Clustering(params), session, &args.session)
        }
        PlanExperiment::Recognition { args, .. } => {
            no_json(&args.json)?;
            if args.save_model.is_some() {
                bail!("a plan saves no model: `fit ds|gs` on the session does");
            }
            let session = open_session(&args.session)?;
            let params = args.params()?;
            let (params, choice) = with_progress(args.quiet, |p| {
                crate::experiments::recognition::choose_auto_features(&session, &params, p)
            })?;
            plan_choice(choice.as_ref());
            (Experiment::Recognition(params), session, &args.session)
        }
        PlanExperiment::Frontier { args, .. } => {
            no_json(&args.json)?;
            let session = open_session(&args.session)?;
            let mut frontiers = Vec::new();
            for params in args.params()? {
                let (params, choice) = with_progress(args.quiet, |p| {
                    crate::experiments::frontier::choose_auto_features(&session, &params, p)
                })?;
                plan_choice(choice.as_ref());
                frontiers.push(params);
            }
            (
                Experiment::Frontier(FrontierSweep { frontiers }),
                session,
                &args.session,
            )
        }
    })
}

/// `auto` is chosen once, when planning: the shards all run the chosen family, and the
/// merged result is the single-machine command's with that family given.
fn plan_choice(choice: Option<&crate::experiments::feature_choice::FeatureChoice>) {
    if let Some(c) = choice {
        super::model::print_choice(Some(c));
        println!(
            "the plan runs {}: compare with the single-machine command given --features {}",
            c.chosen, c.chosen
        );
    }
}

fn plan(a: PlanArgs) -> anyhow::Result<()> {
    let opts = match &a.experiment {
        PlanExperiment::Stability { plan, .. }
        | PlanExperiment::Robustness { plan, .. }
        | PlanExperiment::Clustering { plan, .. }
        | PlanExperiment::Recognition { plan, .. }
        | PlanExperiment::Frontier { plan, .. } => plan,
    };
    if let PlanExperiment::Stability { args, .. } = &a.experiment
        && args.threads.is_some()
    {
        bail!("--threads: a plan runs nothing; give the tasks' CPUs with --cpus");
    }
    let (experiment, session, source) = experiment_of(&a.experiment)?;
    super::refuse_input_as_output(Some(&opts.out), &[source])?;
    let program = match &opts.program {
        Some(p) => p.clone(),
        None => std::env::current_exe()
            .context("finding this program's path (give --program)")?
            .display()
            .to_string(),
    };
    let request = PlanRequest {
        shards: opts.shards,
        source: source.display().to_string(),
        time_minutes: opts.time,
        cpus: opts.cpus,
        mem_mb: opts.mem,
        partition: opts.partition.clone(),
        program,
    };
    let p = sweep::write_plan(&opts.out, &session, experiment, &request)?;
    let r = &p.resources;
    println!(
        "{} sweep on {}: {} items in {} shards (estimated {:.0}–{:.0} CPU-s each)",
        p.experiment.name(),
        p.session.name,
        p.items.len(),
        p.shard_count(),
        p.shard_cpu_seconds
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
        p.shard_cpu_seconds.iter().copied().fold(0.0, f64::max),
    );
    println!(
        "each task: {} CPUs, {} MB, time limit {}",
        r.cpus,
        r.mem_mb,
        r.time_text()
    );
    println!(
        "wrote {}; submit with: sbatch {}",
        opts.out.display(),
        opts.out.join(sweep::SBATCH_FILE).display()
    );
    Ok(())
}

/// The plan's size parameters within their maxima, before a shard allocates for them (a
/// plan is a file anyone can edit).
fn check_plan_sizes(dir: &Path) -> anyhow::Result<()> {
    let path = dir.join(sweep::PLAN_FILE);
    let max = crate::fsutil::max_bytes::SWEEP;
    let Ok(reader) = crate::fsutil::open_json(&path, max, "sweep plan") else {
        // Reading the plan reports its own errors.
        return Ok(());
    };
    if let Ok(plan) = serde_json::from_reader::<_, serde_json::Value>(reader) {
        super::bounds::check_plan_sizes(&plan, sweep::PLAN_FILE)
            .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))?;
    }
    Ok(())
}

fn run_shard(a: RunArgs) -> anyhow::Result<()> {
    check_plan_sizes(&a.dir)?;
    let out = in_pool(a.threads, || {
        with_progress(a.quiet, |p| sweep::run_shard(&a.dir, a.shard, p))
    })??;
    let path = sweep::shard_path(&a.dir, a.shard);
    match out {
        ShardRun::Skipped => println!("shard {}: already done ({})", a.shard, path.display()),
        ShardRun::Done { items, seconds } => println!(
            "shard {}: {items} items in {seconds:.1} s; wrote {}",
            a.shard,
            path.display()
        ),
    }
    Ok(())
}

fn status(a: StatusArgs) -> anyhow::Result<()> {
    let st = sweep::status(&a.dir)?;
    for (i, s) in st.shards.iter().enumerate() {
        println!("shard {i}: {}", describe(s));
    }
    let failed = st
        .shards
        .iter()
        .filter(|s| matches!(s, ShardState::Failed { .. }))
        .count();
    let n = st.shards.len();
    println!(
        "{} done, {} missing, {failed} failed of {n}",
        st.done(),
        n - st.done() - failed
    );
    let not_done = st.not_done();
    if !not_done.is_empty() {
        println!("to run what is not done:");
        for c in rerun_commands(&a.dir, &st.plan.resources.program, &not_done) {
            println!("  {c}");
        }
    }
    Ok(())
}

/// The files of a plan directory and of its folders (the plan, the session copy, the
/// shards): a merge's inputs.
fn plan_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = entry.path();
            if p.is_dir() {
                if d == dir {
                    dirs.push(p);
                }
            } else {
                files.push(p);
            }
        }
    }
    files
}

fn merge(a: MergeArgs) -> anyhow::Result<()> {
    check_plan_sizes(&a.dir)?;
    let files = plan_files(&a.dir);
    let mut inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    inputs.push(&a.dir);
    inputs.extend(a.expect.as_deref());
    super::refuse_input_as_output(Some(&a.out), &inputs)?;
    super::refuse_input_as_output(a.project.as_deref(), &inputs)?;
    let m = with_progress(a.quiet, |p| sweep::merge(&a.dir, p))?;
    let text = serde_json::to_string_pretty(&m.result)?;
    crate::fsutil::write_atomic(&a.out, text.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!(
        "{} sweep on {}: merged ({:.1} s of shard work); wrote {}",
        m.experiment.name(),
        m.session.meta.name,
        m.time.seconds,
        a.out.display()
    );
    if let Some(path) = &a.expect {
        let reader = crate::fsutil::open_json(path, crate::fsutil::max_bytes::RESULT, "result")
            .with_context(|| format!("reading {}", path.display()))?;
        let local: serde_json::Value = serde_json::from_reader(reader)
            .with_context(|| format!("{}: not a JSON result", path.display()))?;
        match sweep::result_difference(&m.result, &local) {
            None => println!(
                "the merged result equals {} (timings aside)",
                path.display()
            ),
            Some(d) => bail!("the merged result differs from {} at {d}", path.display()),
        }
    }
    if let Some(path) = &a.project {
        let Some(analysis) = m.analysis else {
            bail!(
                "--project: a {} result is kept as its JSON ({}), not as a project",
                m.experiment.name(),
                a.out.display()
            );
        };
        let session = session_name(&a.dir);
        Project::new(vec![session], vec![analysis]).save(path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The plan's session copy as a project names it.
fn session_name(dir: &Path) -> String {
    let p = dir.join(sweep::SESSION_FILE);
    std::fs::canonicalize(&p).unwrap_or(p).display().to_string()
}
