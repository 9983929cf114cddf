//! `bench-stability`: the time of each step of the pipeline on BTS3 palm-down (dictionary
//! learning, coding, feature-sign solves, cross validation, the 108-cell grid) and how it
//! scales with K and with the number of grasps.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;

use super::{in_pool, open, write_json};
use crate::experiments::stability::{
    self, Config, CvScheme, DataOptions, GridSpec, PipelineSettings, StabilityData,
};
use crate::jobs::Progress;
use crate::sparse::{Dictionary, DictionaryParams, FeatureSign};
use crate::svm::{cross_validate, stratified_k_fold};

/// Where the real BTS3 set lives beside the project checkout.
pub const BTS3_CSV: &str = "../shared/datasets/bts3/biotac-palmdown-grasps.csv";

#[derive(Args, Debug)]
pub struct BenchStabilityArgs {
    /// The BTS3 palm-down CSV (or a native session).
    #[arg(default_value = BTS3_CSV)]
    pub session: PathBuf,
    /// Repetitions of the single-step timings (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Skip the 108-cell grid.
    #[arg(long)]
    pub skip_grid: bool,
    /// Skip the scaling studies (K and number of grasps).
    #[arg(long)]
    pub skip_scaling: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Wall and CPU seconds of a piece of work.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Timing {
    pub wall_secs: f64,
    /// User + system CPU seconds of the whole process over the same span (Linux
    /// /proc/self/stat; NaN elsewhere): on a shared machine this is the honest measure.
    pub cpu_secs: f64,
}

fn cpu_now() -> f64 {
    // utime and stime are fields 14 and 15, in clock ticks (100 per second on Linux).
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            let u: f64 = f.get(11)?.parse().ok()?;
            let k: f64 = f.get(12)?.parse().ok()?;
            Some((u + k) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Timing) {
    let (c0, t0) = (cpu_now(), Instant::now());
    let out = f();
    (
        out,
        Timing {
            wall_secs: t0.elapsed().as_secs_f64(),
            cpu_secs: cpu_now() - c0,
        },
    )
}

fn median(mut v: Vec<Timing>) -> Timing {
    v.sort_by(|a, b| a.wall_secs.total_cmp(&b.wall_secs));
    v[v.len() / 2]
}

#[derive(Clone, Debug, Serialize)]
pub struct ScalingPoint {
    pub num_bases: usize,
    pub grasps: usize,
    pub dictionary: Timing,
    pub dictionary_iterations: usize,
    pub objective: f64,
    pub coding: Timing,
    pub cv: Timing,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub session: String,
    pub grasps: usize,
    pub patches: usize,
    pub threads: usize,
    /// /proc/loadavg at the start and the end (the machine may be shared).
    pub load_average: [String; 2],
    /// K = 29, λ = 1: time until the objective first reached F ≤ 5.38, and the whole fit.
    pub dictionary_to_target: Timing,
    pub dictionary_to_target_iterations: usize,
    pub dictionary_full: Timing,
    pub dictionary_iterations: usize,
    pub dictionary_objective: f64,
    /// All patches coded with γ = 1 by feature-sign search.
    pub coding: Timing,
    /// One feature-sign solve per patch (the same coding, one thread).
    pub feature_sign: SolveTimes,
    /// One stratified 10-fold cross validation of the linear SVM on the K = 29 codes.
    pub cv_10fold: Timing,
    pub cv_wsr: f64,
    /// The 108-configuration grid with 10-fold CV, end to end.
    pub grid: Option<Timing>,
    pub grid_best: Option<Config>,
    pub grid_best_wsr: Option<f64>,
    pub scaling_k: Vec<ScalingPoint>,
    pub scaling_grasps: Vec<ScalingPoint>,
}

/// Quantiles over patches of the time of one feature-sign solve from the zero code.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SolveTimes {
    /// Solves timed (patches × repeats).
    pub solves: usize,
    pub median_us: f64,
    pub p10_us: f64,
    pub p90_us: f64,
    /// Mean number of non-zero coefficients of the codes.
    pub mean_active: f64,
}

/// Time every patch's feature-sign solve (K bases of `dict`, penalty `gamma`) on this
/// thread, `repeats` times over, each from the zero code as `encode` starts.
fn feature_sign_times(
    dict: &Dictionary,
    x: ndarray::ArrayView2<f64>,
    gamma: f64,
    repeats: usize,
) -> SolveTimes {
    let d = &dict.atoms;
    let k = d.nrows();
    let g: Vec<f64> = d.dot(&d.t()).iter().copied().collect();
    let c: Vec<f64> = x.dot(&d.t()).iter().copied().collect();
    let mut fs = FeatureSign::new(k);
    let mut a = vec![0.0; k];
    let mut us = Vec::with_capacity(repeats * x.nrows());
    let mut active = 0usize;
    for _ in 0..repeats {
        for ci in c.chunks_exact(k) {
            a.fill(0.0);
            let t0 = Instant::now();
            fs.solve(&g, ci, gamma, &mut a);
            us.push(t0.elapsed().as_secs_f64() * 1e6);
            active += a.iter().filter(|v| **v != 0.0).count();
        }
    }
    us.sort_by(f64::total_cmp);
    let q = |f: f64| us[((us.len() - 1) as f64 * f).round() as usize];
    SolveTimes {
        solves: us.len(),
        median_us: q(0.5),
        p10_us: q(0.1),
        p90_us: q(0.9),
        mean_active: active as f64 / us.len() as f64,
    }
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

fn scaling_point(
    data: &StabilityData,
    k: usize,
    settings: &PipelineSettings,
) -> anyhow::Result<ScalingPoint> {
    let params = DictionaryParams {
        num_bases: k,
        beta: 1.0,
        ..settings.dictionary.clone()
    };
    let (fit, dictionary) = timed(|| params.fit(data.x.view(), &Progress::new()));
    let fit = fit?;
    let (codes, coding) = timed(|| fit.dictionary.encode(data.x.view(), 1.0));
    let features = stability::concatenated_codes(codes?, data.sensor_count());
    let folds = stratified_k_fold(&data.labels, 10, 0)?;
    let (cv, cv_t) = timed(|| cross_validate(features.view(), &data.labels, &folds, &settings.svm));
    cv?;
    Ok(ScalingPoint {
        num_bases: k,
        grasps: data.grasp_count(),
        dictionary,
        dictionary_iterations: fit.iterations,
        objective: fit.objective,
        coding,
        cv: cv_t,
    })
}

pub fn bench(a: &BenchStabilityArgs) -> anyhow::Result<BenchReport> {
    let session = open(&a.session)?;
    let data = StabilityData::from_session(&session, &DataOptions::default())?;
    let settings = PipelineSettings::default();
    let load0 = load_average();
    let repeats = a.repeats.max(1);
    // Dictionary learning K = 29, λ = 1.
    let params = DictionaryParams {
        num_bases: 29,
        beta: 1.0,
        ..settings.dictionary.clone()
    };
    let mut fits = Vec::new();
    let mut to_target = Vec::new();
    let mut full = Vec::new();
    for _ in 0..repeats {
        let (fit, t) = timed(|| params.fit(data.x.view(), &Progress::new()));
        let fit = fit?;
        let hit = fit.history.iter().find(|h| h.objective_after_codes <= 5.38);
        // Wall time to the target from the learner's own clock; CPU in proportion.
        let wall = hit.map_or(f64::NAN, |h| h.secs);
        let cpu = t.cpu_secs * wall / fit.secs.max(1e-12);
        to_target.push(Timing {
            wall_secs: wall,
            cpu_secs: cpu,
        });
        full.push(t);
        fits.push(fit);
    }
    let fit = fits.pop().expect("at least one repeat");
    let target_iterations = fit
        .history
        .iter()
        .find(|h| h.objective_after_codes <= 5.38)
        .map_or(0, |h| h.iteration);
    // Coding.
    let mut coding = Vec::new();
    let mut codes = None;
    for _ in 0..repeats {
        let (c, t) = timed(|| fit.dictionary.encode(data.x.view(), 1.0));
        codes = Some(c?);
        coding.push(t);
    }
    let features = stability::concatenated_codes(codes.expect("coded"), data.sensor_count());
    let feature_sign = feature_sign_times(&fit.dictionary, data.x.view(), 1.0, repeats);
    // One 10-fold CV.
    let folds = stratified_k_fold(&data.labels, 10, 0)?;
    let mut cvs = Vec::new();
    let mut wsr = f64::NAN;
    for _ in 0..repeats {
        let (r, t) = timed(|| cross_validate(features.view(), &data.labels, &folds, &settings.svm));
        wsr = r?.weighted_success_rate;
        cvs.push(t);
    }
    // The grid.
    let (grid, grid_best, grid_best_wsr) = if a.skip_grid {
        (None, None, None)
    } else {
        let (g, t) = timed(|| {
            stability::grid_search(
                &data,
                &GridSpec::bench(),
                &settings,
                CvScheme::KFold { k: 10 },
                &Progress::new(),
            )
        });
        let g = g?;
        (
            Some(t),
            Some(g.best.config),
            Some(g.best.weighted_success_rate),
        )
    };
    // Scaling with K and with the number of grasps.
    let mut scaling_k = Vec::new();
    let mut scaling_grasps = Vec::new();
    if !a.skip_scaling {
        for k in [5, 10, 20, 29, 40, 60] {
            scaling_k.push(scaling_point(&data, k, &settings)?);
        }
        let n = data.grasp_count();
        for frac in [0.25, 0.5, 1.0] {
            // A stratified, seeded subsample.
            let mut order: Vec<usize> = (0..n).collect();
            crate::rng::Rng::new(7).shuffle(&mut order);
            let take = |fail: bool| -> Vec<usize> {
                let of: Vec<usize> = order
                    .iter()
                    .copied()
                    .filter(|&g| data.labels[g] == fail)
                    .collect();
                let m = ((of.len() as f64) * frac).round() as usize;
                of[..m].to_vec()
            };
            let mut idx = take(false);
            idx.extend(take(true));
            idx.sort_unstable();
            let sub = data.subset(&idx)?;
            scaling_grasps.push(scaling_point(&sub, 29, &settings)?);
        }
    }
    Ok(BenchReport {
        session: data.session_name.clone(),
        grasps: data.grasp_count(),
        patches: data.x.nrows(),
        threads: rayon::current_num_threads(),
        load_average: [load0, load_average()],
        dictionary_to_target: median(to_target),
        dictionary_to_target_iterations: target_iterations,
        dictionary_full: median(full),
        dictionary_iterations: fit.iterations,
        dictionary_objective: fit.objective,
        coding: median(coding),
        feature_sign,
        cv_10fold: median(cvs),
        cv_wsr: wsr,
        grid,
        grid_best,
        grid_best_wsr,
        scaling_k,
        scaling_grasps,
    })
}

fn fmt_t(t: &Timing) -> String {
    format!("{:.4} s wall, {:.2} s CPU", t.wall_secs, t.cpu_secs)
}

pub fn bench_report(b: &BenchReport) -> String {
    let mut out = format!(
        "{}: {} grasps, {} patches, {} threads, load average {} → {}\n",
        b.session, b.grasps, b.patches, b.threads, b.load_average[0], b.load_average[1]
    );
    out += &format!(
        "dictionary K = 29, λ = 1: F ≤ 5.38 after {} iterations in {}; converged F = {:.4} after {} iterations in {}\n",
        b.dictionary_to_target_iterations,
        fmt_t(&b.dictionary_to_target),
        b.dictionary_objective,
        b.dictionary_iterations,
        fmt_t(&b.dictionary_full)
    );
    out += &format!(
        "coding all {} patches (γ = 1): {}\n",
        b.patches,
        fmt_t(&b.coding)
    );
    let fs = &b.feature_sign;
    out += &format!(
        "feature-sign, one solve per patch (γ = 1, from 0, one thread): median {:.2} µs, p10 {:.2} µs, p90 {:.2} µs over {} solves; {:.2} active bases per code\n",
        fs.median_us, fs.p10_us, fs.p90_us, fs.solves, fs.mean_active
    );
    out += &format!(
        "one 10-fold CV on the codes: {} (weighted success rate {:.2} %)\n",
        fmt_t(&b.cv_10fold),
        100.0 * b.cv_wsr
    );
    if let Some(g) = &b.grid {
        out += &format!(
            "108-cell grid with 10-fold CV: {}; best {} at {:.2} %\n",
            fmt_t(g),
            b.grid_best.map(|c| c.to_string()).unwrap_or_default(),
            100.0 * b.grid_best_wsr.unwrap_or(f64::NAN)
        );
    }
    for (title, pts) in [
        ("scaling with K", &b.scaling_k),
        ("scaling with grasps (K = 29)", &b.scaling_grasps),
    ] {
        if pts.is_empty() {
            continue;
        }
        out += &format!(
            "{title}:\n    K  grasps  dictionary (iter)          coding     10-fold CV   F\n"
        );
        for p in pts {
            out += &format!(
                "  {:>3}  {:>6}  {:>7.3} s ({:>3}) {:>5.2} CPU  {:>7.4} s  {:>7.3} s    {:.4}\n",
                p.num_bases,
                p.grasps,
                p.dictionary.wall_secs,
                p.dictionary_iterations,
                p.dictionary.cpu_secs,
                p.coding.wall_secs,
                p.cv.wall_secs,
                p.objective
            );
        }
    }
    out
}

pub fn run_bench(a: BenchStabilityArgs) -> anyhow::Result<()> {
    crate::cli::bounds::at_most("--repeats", a.repeats, crate::cli::bounds::MAX_REPS)?;
    crate::cli::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    let b = in_pool(a.threads, || bench(&a))??;
    print!("{}", bench_report(&b));
    if let Some(path) = &a.json {
        write_json(path, &b)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
