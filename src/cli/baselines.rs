//! `baselines`: sequential k-means, SOM and the offline RBF SVM on the Table I per-grasp
//! features (the second paper's Tables II and IV, Fig. 13).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};

use crate::cluster::{Schedule, SomParams};
use crate::experiments::baselines::{
    BaselinesParams, BaselinesResult, ScoreSummary, run_baselines,
};
use crate::features::{Normalisation, table_one::session_features};
use crate::jobs::Progress;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum NormalisationArg {
    ZScore,
    MinMax,
}

#[derive(Args, Debug)]
pub struct BaselinesArgs {
    /// A native session file, or the iCub dataset folder (imported on the fly).
    pub session: PathBuf,
    /// Write the machine-readable results here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Label set holding the true classes (`--target`, as on recognition and clustering).
    #[arg(long, visible_alias = "target", default_value = "object")]
    pub label_set: String,
    /// Random presentation orders for k-means and the SOM.
    #[arg(long, default_value_t = 50)]
    pub orders: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Clusters (k-means centres; SOM units = rows × cols) of the headline comparison.
    #[arg(long, default_value_t = 10)]
    pub k: usize,
    /// Cluster counts of the NMI sweep, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20"
    )]
    pub k_sweep: Vec<usize>,
    /// Skip the NMI sweep.
    #[arg(long)]
    pub no_sweep: bool,
    #[arg(long, value_enum, default_value = "min-max")]
    pub normalisation: NormalisationArg,
    #[arg(long, default_value_t = 1)]
    pub kmeans_passes: usize,
    /// SOM grid of the headline comparison (rows × cols must equal k).
    #[arg(long, default_value_t = 2)]
    pub som_rows: usize,
    #[arg(long, default_value_t = 5)]
    pub som_cols: usize,
    #[arg(long, default_value_t = 20)]
    pub som_passes: usize,
    /// SOM learning rate, exponential decay from start to end.
    #[arg(long, default_value_t = 0.5)]
    pub som_rate_start: f64,
    #[arg(long, default_value_t = 0.01)]
    pub som_rate_end: f64,
    /// SOM neighbourhood radius (grid units), exponential decay; start defaults to cols / 2.
    #[arg(long)]
    pub som_radius_start: Option<f64>,
    #[arg(long, default_value_t = 0.3)]
    pub som_radius_end: f64,
    /// SVM grid: penalties C and RBF widths gamma, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,10,100,1000")]
    pub svm_c: Vec<f64>,
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.001,0.003,0.01,0.03,0.1"
    )]
    pub svm_gamma: Vec<f64>,
    /// Repetitions of the SVM's 5-fold cross-validation (0: skip the SVM).
    #[arg(long, default_value_t = 10)]
    pub cv_repeats: usize,
    /// Save each baseline fitted on every grasp with the run's settings as a model file:
    /// MODEL.json gives MODEL.kmeans.json, MODEL.som.json and MODEL.rbf-svm.json.
    #[arg(long, value_name = "MODEL.json")]
    pub save_model: Option<PathBuf>,
}

/// Where `--save-model PATH` puts the model of `method`: PATH with the method's key before
/// its extension.
fn model_path(path: &std::path::Path, method: crate::catalogue::MethodId) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.{}.json", method.key()))
}

fn line(name: &str, s: &ScoreSummary) -> String {
    format!(
        "{name:<20} {:.3} ({:.3})  {:.3} ({:.3})  {:.3} ({:.3})  {:.1}",
        s.mean.purity,
        s.sd.purity,
        s.mean.ari,
        s.sd.ari,
        s.mean.nmi,
        s.sd.nmi,
        s.effective_clusters_mean
    )
}

pub fn report(r: &BaselinesResult) -> String {
    let mut out = format!(
        "{} grasps × {} Table I features, {:?} normalisation, {} orders\n",
        r.samples, r.features, r.params.normalisation, r.params.orders
    );
    out += &format!(
        "{:<20} purity         ARI            NMI            eff.\n",
        format!("k = {}", r.params.k)
    );
    out += &line("sequential k-means", &r.kmeans);
    out.push('\n');
    out += &line(
        &format!("SOM {}×{}", r.params.som.rows, r.params.som.cols),
        &r.som,
    );
    out.push('\n');
    if !r.sweep.is_empty() {
        out += "NMI sweep:  k  k-means (eff.)   SOM grid (eff.)\n";
        for p in &r.sweep {
            out += &format!(
                "          {:>3}  {:.3} ({:>4.1})    {:.3} {}×{} ({:>4.1})\n",
                p.k,
                p.kmeans.mean.nmi,
                p.kmeans.effective_clusters_mean,
                p.som.mean.nmi,
                p.som_grid.0,
                p.som_grid.1,
                p.som.effective_clusters_mean
            );
        }
    }
    if let Some(svm) = &r.svm {
        out += &format!(
            "RBF SVM {}-fold ×{}: accuracy {:.3} ({:.3}) at C = {}, gamma = {} (best of {} cells)\n",
            svm.folds,
            svm.repeats,
            svm.best.accuracy_mean,
            svm.best.accuracy_sd,
            svm.best.c,
            svm.best.gamma,
            svm.grid.len()
        );
    }
    out
}

pub fn run(a: BaselinesArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    if let Some(path) = &a.save_model {
        use crate::catalogue::MethodId;
        for m in [MethodId::KMeans, MethodId::Som, MethodId::RbfSvm] {
            super::refuse_input_as_output(Some(&model_path(path, m)), &[&a.session])?;
        }
    }
    {
        use super::bounds::{MAX_K, MAX_REPS, all_at_most, at_most};
        at_most("--k", a.k, MAX_K)?;
        all_at_most("--k-sweep", &a.k_sweep, MAX_K)?;
        at_most("--orders", a.orders, MAX_REPS)?;
        at_most("--cv-repeats", a.cv_repeats, MAX_REPS)?;
        at_most("--som-rows", a.som_rows, MAX_K)?;
        at_most("--som-cols", a.som_cols, MAX_K)?;
    }
    if a.som_rows * a.som_cols != a.k {
        bail!(
            "the SOM grid {} × {} must have k = {} units",
            a.som_rows,
            a.som_cols,
            a.k
        );
    }
    let session = super::recognition::open_session(&a.session)?;
    let set = session.label_set(&a.label_set).with_context(|| {
        let names: Vec<&str> = session.label_sets.iter().map(|l| l.name.as_str()).collect();
        format!(
            "the session has no label set {:?}; its label sets: {}",
            a.label_set,
            names.join(", ")
        )
    })?;
    let truth = session.labels_of(set);
    let grasps = session.grasps.len();
    super::bounds::at_most_grasps("--k", &[a.k], grasps)?;
    if !a.no_sweep {
        super::bounds::at_most_grasps("--k-sweep", &a.k_sweep, grasps)?;
    }
    let features = session_features(&session)?;
    let params = BaselinesParams {
        orders: a.orders,
        seed: a.seed,
        k: a.k,
        k_sweep: if a.no_sweep { Vec::new() } else { a.k_sweep },
        normalisation: match a.normalisation {
            NormalisationArg::ZScore => Normalisation::ZScore,
            NormalisationArg::MinMax => Normalisation::MinMax,
        },
        kmeans_passes: a.kmeans_passes,
        som: SomParams {
            rows: a.som_rows,
            cols: a.som_cols,
            passes: a.som_passes,
            learning_rate: Schedule::Exponential {
                start: a.som_rate_start,
                end: a.som_rate_end,
            },
            radius: Schedule::Exponential {
                start: a
                    .som_radius_start
                    .unwrap_or((0.5 * a.som_cols.max(a.som_rows) as f64).max(0.5)),
                end: a.som_radius_end,
            },
            seed: a.seed,
        },
        svm_c: a.svm_c,
        svm_gamma: a.svm_gamma,
        cv_folds: 5,
        cv_repeats: a.cv_repeats,
    };
    let result = run_baselines(features.view(), &truth, &params, &Progress::new())?;
    print!("{}", report(&result));
    if let Some(path) = &a.json {
        let text = serde_json::to_string_pretty(&result)?;
        crate::fsutil::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &a.save_model {
        for file in crate::models::table_one_files_of_run(&session, &a.label_set, &result)? {
            let out = model_path(path, file.provenance.method);
            crate::models::save(&file, &out)?;
            println!("wrote {} ({})", out.display(), file.provenance.summary());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use crate::cli::{Cli, Command};

    /// The command line end to end on the iCub dataset folder, with few orders.
    #[test]
    fn baselines_command_writes_json() {
        let Some(dir) = crate::test_datasets::dataset("icub-grasp") else {
            return;
        };
        let dir = dir.to_str().expect("a UTF-8 path");
        let out = std::env::temp_dir().join(format!("baselines-{}.json", std::process::id()));
        let out_arg = out.to_string_lossy().into_owned();
        let args = [
            "tactile-workbench",
            "baselines",
            dir,
            "--json",
            &out_arg,
            "--orders",
            "2",
            "--k-sweep",
            "5,10",
            "--cv-repeats",
            "0",
        ];
        let Some(Command::Baselines(a)) = Cli::try_parse_from(args).unwrap().command else {
            panic!("not parsed as `baselines`");
        };
        super::run(a).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let _ = std::fs::remove_file(&out);
        let r: crate::experiments::baselines::BaselinesResult =
            serde_json::from_str(&text).unwrap();
        assert_eq!((r.samples, r.features), (200, 165));
        assert_eq!(r.sweep.len(), 2);
        assert!(r.svm.is_none());
        // a grid that does not hold k units is refused
        let bad = ["tactile-workbench", "baselines", dir, "--som-rows", "3"];
        let Some(Command::Baselines(a)) = Cli::try_parse_from(bad).unwrap().command else {
            panic!("not parsed as `baselines`");
        };
        assert!(super::run(a).is_err());
    }
}
