//! The human-readable summary of a `stability` run.

use crate::experiments::stability::{PipelineInputs, StabilityReport};

fn pct(v: f64) -> String {
    format!("{:.2} %", 100.0 * v)
}

/// The human-readable summary of a report.
pub fn report(r: &StabilityReport) -> String {
    let mut out = String::new();
    let mut line = |s: String| {
        out.push_str(&s);
        out.push('\n');
    };
    line(format!(
        "{}: {} grasps ({} {}), {} objects, {} sensors × {} taxels",
        r.session, r.grasps, r.failures, r.failure_class, r.objects, r.sensors, r.patch_dim
    ));
    line(format!("scaling: {}", r.scaling));
    line(format!("objective: {}", r.convention));
    if r.options.settings.inputs == PipelineInputs::CodesAndRaw {
        line("the SVM reads each grasp's codes followed by its scaled key-frame values".into());
    }
    if let Some(g) = &r.grid {
        line(format!(
            "grid: {} cells ({} num_bases × {} beta × {} gamma), selection by {}, {:.1} s on {} threads",
            g.cells.len(),
            g.spec.num_bases.len(),
            g.spec.beta.len(),
            g.spec.gamma.len(),
            r.selection_cv,
            g.secs,
            g.threads
        ));
        line("best per num_bases (Fig. 5):  K    beta   gamma   WSR       ± SE     failure recall  sparsity   F".into());
        for c in &g.best_per_num_bases {
            line(format!(
                "                             {:>3}  {:>5}  {:>5}   {:>8}  {:>6.2}   {:>8}        {:>8}   {:.4}",
                c.config.num_bases,
                c.config.beta,
                c.config.gamma,
                pct(c.weighted_success_rate),
                100.0 * c.fold_wsr_se,
                pct(c.failure_recall),
                pct(c.sparsity),
                c.dictionary_objective
            ));
        }
    }
    for (name, e) in [("best", &r.best), ("parsimonious", &r.parsimonious)] {
        if name == "parsimonious" && r.grid.is_none() {
            break;
        }
        line(format!(
            "{name} ({}): F = {:.4} ({} iterations, {:.2} s), sparsity {}, {:.2} active bases per patch",
            e.config,
            e.dictionary_objective,
            e.dictionary_iterations,
            e.dictionary_secs,
            pct(e.sparsity),
            e.active_bases_per_patch
        ));
        line(format!(
            "    {}: weighted success rate {}, failure recall {}",
            r.kfold_cv,
            pct(e.kfold.weighted_success_rate),
            pct(e.kfold.failure_recall)
        ));
        line(format!(
            "    {}: weighted success rate {}, failure recall {}",
            r.objects_cv,
            pct(e.objects.weighted_success_rate),
            pct(e.objects.failure_recall)
        ));
    }
    line(format!(
        "baseline (linear SVM on the {} scaled raw values): {} {} / {}; {} {} / {}  (WSR / failure recall)",
        r.baseline.features,
        r.kfold_cv,
        pct(r.baseline.kfold.weighted_success_rate),
        pct(r.baseline.kfold.failure_recall),
        r.objects_cv,
        pct(r.baseline.objects.weighted_success_rate),
        pct(r.baseline.objects.failure_recall)
    ));
    for n in &r.nested {
        line(format!(
            "{} ({:.1} s): WSR {} (per fold {} ± {:.2}), failure recall {}; raw linear SVM, same outer folds: WSR {}, failure recall {}",
            n.description,
            n.secs,
            pct(n.weighted_success_rate),
            pct(n.fold_wsr_mean),
            100.0 * n.fold_wsr_se,
            pct(n.failure_recall),
            pct(n.raw_weighted_success_rate),
            pct(n.raw_failure_recall)
        ));
        for f in &n.folds {
            line(format!(
                "    outer fold {:>2}: chose {} (inner WSR {}; inner best {} at {}); outer test WSR {}, raw {}",
                f.fold,
                f.chosen,
                pct(f.chosen_inner_wsr),
                f.best,
                pct(f.best_inner_wsr),
                f.weighted_success_rate.map_or("n/a".into(), pct),
                f.raw_weighted_success_rate.map_or("n/a".into(), pct)
            ));
        }
    }
    let a = &r.analyses;
    line(format!(
        "analyses of the recommended model: active bases per patch {:.2} ({} {:.2}, {} {:.2}); sparsity {} ({} {}, {} {})",
        a.active_bases_per_patch[0],
        r.success_class,
        a.active_bases_per_patch[1],
        r.failure_class,
        a.active_bases_per_patch[2],
        pct(a.sparsity[0]),
        r.success_class,
        pct(a.sparsity[1]),
        r.failure_class,
        pct(a.sparsity[2])
    ));
    line(format!("total {:.1} s", r.secs));
    out
}
