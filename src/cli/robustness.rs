//! `robustness`: where the methods fail — sweep perturbations, print the break points.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;

use super::progress::with_progress;
use super::recognition::open_session;
use crate::catalogue::MethodId;
use crate::experiments::robustness::{
    Family, Perturbation, RobustnessParams, RobustnessResult, Sweep, run_robustness,
};

#[derive(Args, Debug)]
pub struct RobustnessArgs {
    /// Session: a native file, a BTS3 CSV or the iCub dataset folder.
    pub session: PathBuf,
    /// `stability` (sparse coding + SVM, raw SVM) or `recognition` (DS, GS).
    #[arg(long)]
    pub family: String,
    /// Methods, comma-separated (default: every method of the family): sparse-svm,
    /// raw-svm (stability); ds, gs, du, gu, kmeans, som, rbf-svm (recognition).
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Perturbations, comma-separated (default: every one that applies): noise,
    /// dead-taxels, saturated-taxels, dead-sensor, drift, gain, truncation, missing-frames,
    /// imbalance, few-examples, new-objects.
    #[arg(long, value_delimiter = ',')]
    pub perturbations: Vec<String>,
    /// Strengths, mild to severe: `0,100,1000` when one perturbation is swept, else
    /// `noise=25,100,1000` (repeat the option per perturbation). Unnamed ones keep their
    /// defaults.
    #[arg(long)]
    pub strengths: Vec<String>,
    /// Repetitions per strength (seeded folds / orders / perturbations).
    #[arg(long, default_value_t = 5)]
    pub reps: usize,
    /// The break point is where the mean score falls below this share of the clean score.
    #[arg(long, default_value_t = 0.9)]
    pub fraction: f64,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Do not clamp perturbed readings to the sensor's range (as the paper's Fig. 8).
    #[arg(long)]
    pub no_saturate: bool,
    /// Stability: the fixed configuration (default K = 27, beta = gamma = 0.25, BTS3's
    /// recommended model) and the stratified folds.
    #[arg(long)]
    pub num_bases: Option<usize>,
    #[arg(long)]
    pub beta: Option<f64>,
    #[arg(long)]
    pub gamma: Option<f64>,
    #[arg(long, default_value_t = 10)]
    pub folds: usize,
    /// Recognition: DU's and GU's novelty thresholds (defaults 0.2 and 0.02).
    #[arg(long)]
    pub du_threshold: Option<f64>,
    #[arg(long)]
    pub gu_threshold: Option<f64>,
    /// Recognition: GU keeps a cluster once it has this many grasps (default 3; 1 keeps all).
    #[arg(long)]
    pub gu_min_grasps: Option<usize>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the machine-readable results here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Print no progress.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The parameters the arguments describe (checked by `validate` before any work).
pub fn params_of(a: &RobustnessArgs) -> anyhow::Result<RobustnessParams> {
    super::bounds::at_most("--reps", a.reps, super::bounds::MAX_REPS)?;
    let family: Family = a.family.parse()?;
    let mut p = RobustnessParams::defaults(family);
    if !a.methods.is_empty() {
        p.methods = a
            .methods
            .iter()
            .map(|m| m.trim().parse())
            .collect::<Result<_, _>>()?;
    }
    if !a.perturbations.is_empty() {
        p.sweeps = a
            .perturbations
            .iter()
            .map(|s| {
                let perturbation: Perturbation = s.trim().parse()?;
                Ok(Sweep {
                    perturbation,
                    strengths: perturbation.default_strengths(family),
                })
            })
            .collect::<anyhow::Result<_>>()?;
    }
    for spec in &a.strengths {
        let (target, list) = match spec.split_once('=') {
            Some((name, list)) => {
                let pert: Perturbation = name.trim().parse()?;
                (Some(pert), list)
            }
            None => (None, spec.as_str()),
        };
        let values: Vec<f64> = list
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .with_context(|| format!("--strengths: `{v}` is not a number"))
            })
            .collect::<anyhow::Result<_>>()?;
        let sweep = match target {
            Some(pert) => p.sweeps.iter_mut().find(|s| s.perturbation == pert),
            None if p.sweeps.len() == 1 => p.sweeps.first_mut(),
            None => bail!(
                "--strengths without a name needs exactly one perturbation; write e.g. noise=0,100,1000"
            ),
        };
        match sweep {
            Some(s) => s.strengths = values,
            None => bail!("--strengths names a perturbation not in --perturbations: {spec}"),
        }
    }
    p.reps = a.reps;
    p.fraction = a.fraction;
    p.seed = a.seed;
    p.saturate = !a.no_saturate;
    let c = &mut p.stability.config;
    c.num_bases = a.num_bases.unwrap_or(c.num_bases);
    c.beta = a.beta.unwrap_or(c.beta);
    c.gamma = a.gamma.unwrap_or(c.gamma);
    p.stability.folds = a.folds;
    let rc = &mut p.recognition;
    rc.du_threshold = a.du_threshold.unwrap_or(rc.du_threshold);
    rc.gu_threshold = a.gu_threshold.unwrap_or(rc.gu_threshold);
    rc.gu_min_grasps = a.gu_min_grasps.unwrap_or(rc.gu_min_grasps);
    p.stability.settings.svm.seed = a.seed;
    p.stability.settings.cv_seed = a.seed;
    p.validate()?;
    Ok(p)
}

pub fn run(a: RobustnessArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    let params = params_of(&a)?;
    let session = open_session(&a.session)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()?;
    let r = pool.install(|| with_progress(a.quiet, |p| run_robustness(&session, &params, p)))?;
    print!("{}", table(&r));
    super::recognition::write_json(&r, a.json.as_deref())
}

/// The break points, one row per perturbation and a column per method.
pub fn table(r: &RobustnessResult) -> String {
    let methods: Vec<MethodId> = r.clean.iter().map(|c| c.method).collect();
    let mut out = format!(
        "{} on {}: {} reps, break = mean score < {} × clean ({:.1} s wall, {} threads)\n",
        match r.params.family {
            Family::Stability => "grasp stability",
            Family::Recognition => "object recognition",
        },
        r.session,
        r.params.reps,
        r.params.fraction,
        r.wall_seconds,
        r.threads
    );
    let w = 22;
    out.push_str(&format!("{:<28}", "perturbation (unit)"));
    for m in &methods {
        out.push_str(&format!("{:>w$}", m.title()));
    }
    out.push('\n');
    out.push_str(&format!("{:<28}", "score"));
    for m in &methods {
        out.push_str(&format!("{:>w$}", m.score_name()));
    }
    out.push('\n');
    out.push_str(&format!("{:<28}", "clean score"));
    for c in &r.clean {
        out.push_str(&format!(
            "{:>w$}",
            format!("{:.3} ± {:.3}", c.score.mean, c.score.sd)
        ));
    }
    out.push('\n');
    for sw in &r.params.sweeps {
        let (_, unit) = sw.perturbation.strength_title(r.params.family);
        out.push_str(&format!(
            "{:<28}",
            format!("{} ({unit})", sw.perturbation.key())
        ));
        for &m in &methods {
            let cell = match r.curve(m, sw.perturbation) {
                Some(c) if c.not_applicable.is_some() => "n/a".to_string(),
                Some(c) => match (c.break_point, c.points.last()) {
                    (Some(b), _) => format!("{b:.3}"),
                    (None, Some(last)) => format!(
                        "holds ({:.0}% at {})",
                        100.0 * last.relative.unwrap_or(0.0),
                        last.strength
                    ),
                    (None, None) => "-".into(),
                },
                None => "-".into(),
            };
            out.push_str(&format!("{cell:>w$}"));
        }
        out.push('\n');
    }
    for c in r
        .curves
        .iter()
        .filter(|c| methods.first() == Some(&c.method))
    {
        if let Some(why) = &c.not_applicable {
            out.push_str(&format!("n/a {}: {why}\n", c.perturbation.key()));
        }
    }
    out
}
