//! The baselines on the second paper's Table I features: sequential k-means and the SOM
//! (k centres / units, scored by NMI over seeded orders) and the RBF SVM (C × gamma,
//! scored by repeated stratified 5-fold accuracy).

use super::method::{
    FrontierItem, FrontierMethod, FrontierOutput, FrontierPrep, MethodPoints, SweepKnob, each_rep,
    micros, plain_label, reals, wholes, wrong_item,
};
use super::*;
use crate::cluster::{SequentialKMeansParams, scores};
use crate::experiments::clustering::{baseline_seed, distinct, som_setup};
use crate::experiments::labels::session_labels;
use crate::features::{Normalisation, Normaliser, table_one::session_features};
use crate::svm::kernel_svm::{self, KernelSvmParams};
use ndarray::Array2;

/// The papers' k of the clustering baselines (Table IV: 10 clusters, the SOM 2 × 5).
const PAPER_K: usize = 10;

/// The Table I features (z-scored for the clusterers; raw for the SVM, which scales
/// inside each training fold) and the objects.
struct Table {
    x: Array2<f64>,
    labels: Vec<usize>,
}

/// The session's Table I features and objects; `ks`: the cluster counts asked for, each
/// at most the grasps.
fn table(session: &Session, ks: &[usize], z_score: bool) -> Result<FrontierPrep, ExperimentError> {
    let (labels, _) = session_labels(session, "object")?;
    let raw = session_features(session)?;
    if let Some(k) = ks.iter().find(|&&k| k > raw.nrows()) {
        return Err(ExperimentError::param(
            "ks",
            format!("{k} clusters for {} grasps", raw.nrows()),
        ));
    }
    let x = if z_score {
        Normaliser::fit(Normalisation::ZScore, raw.view()).and_then(|n| n.transform(raw.view()))?
    } else {
        raw
    };
    Ok(FrontierPrep::new(Table { x, labels }))
}

/// Sequential k-means or the SOM.
pub(super) enum TableClusterer {
    KMeans,
    Som,
}

impl FrontierMethod for TableClusterer {
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError> {
        if params.ks.is_empty() || params.ks.contains(&0) {
            return Err(ExperimentError::param(
                "ks",
                "k-means and the SOM need cluster counts ≥ 1",
            ));
        }
        Ok(())
    }

    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob> {
        vec![SweepKnob::new(
            "k",
            "numbers of clusters k",
            true,
            reals(&params.ks),
        )]
    }

    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]) {
        params.ks = wholes(&lists[0]);
    }

    fn prepare(
        &self,
        session: &Session,
        params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError> {
        table(session, &params.ks, true)
    }

    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem> {
        each_rep(params.ks.iter().copied(), params.reps, |k, rep| {
            FrontierItem::Clusters { k, rep }
        })
    }

    fn item(
        &self,
        _session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        _progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        let (Some(Table { x, labels }), FrontierItem::Clusters { k, rep }) =
            (prep.get::<Table>(), *item)
        else {
            return Err(wrong_item(item, params));
        };
        let seed = baseline_seed(params.seed, k, rep);
        let t0 = Instant::now();
        let (pred, train) = match self {
            TableClusterer::KMeans => {
                let m = SequentialKMeansParams { k, passes: 1, seed }.fit(x.view())?;
                let train = t0.elapsed().as_secs_f64();
                (m.assign(x.view())?, train)
            }
            TableClusterer::Som => {
                let m = som_setup(k, seed).fit(x.view())?;
                let train = t0.elapsed().as_secs_f64();
                (m.assign(x.view())?, train)
            }
        };
        let predict = t0.elapsed().as_secs_f64() - train;
        Ok(FrontierOutput::Clusters {
            nmi: scores(labels, &pred).nmi,
            effective: distinct(&pred),
            train_us: micros(train, x.nrows()),
            predict_us: micros(predict, x.nrows()),
        })
    }

    /// One point per k.
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints {
        let points = params
            .ks
            .iter()
            .map(|&k| {
                let (mut nmi, mut eff, mut train, mut predict) =
                    (Vec::new(), Vec::new(), Vec::new(), Vec::new());
                for (item, out) in &pairs {
                    if let (
                        FrontierItem::Clusters { k: kk, .. },
                        FrontierOutput::Clusters {
                            nmi: n,
                            effective,
                            train_us,
                            predict_us,
                        },
                    ) = (item, out)
                        && *kk == k
                    {
                        nmi.push(*n);
                        eff.push(*effective as f64);
                        train.push(*train_us);
                        predict.push(*predict_us);
                    }
                }
                let effective = mean(eff.into_iter());
                let what = match self {
                    TableClusterer::Som => {
                        let s = som_setup(k, 0);
                        format!("SOM {} × {} units", s.rows, s.cols)
                    }
                    TableClusterer::KMeans => format!("sequential k-means, k {k}"),
                };
                point(
                    format!("k {k}"),
                    format!("{what}; {effective:.1} effective clusters (mean over the orders)"),
                    vec![("k", k as f64), ("effective", effective)],
                    &nmi,
                    train,
                    predict,
                )
            })
            .collect();
        MethodPoints {
            points,
            paper_default: params.ks.iter().position(|&k| k == PAPER_K),
            score_name: "NMI".into(),
            unit: "grasp",
        }
    }

    fn label(&self, params: &FrontierParams) -> String {
        match self {
            // The catalogue's "k-means" is the sequential one the second paper runs.
            TableClusterer::KMeans => crate::cluster::KMEANS_NAME.into(),
            TableClusterer::Som => plain_label(params),
        }
    }
}

/// The offline RBF SVM.
pub(super) struct RbfSvm;

fn svm_cells(params: &FrontierParams) -> Vec<(f64, f64)> {
    params
        .svm_c
        .iter()
        .flat_map(|&c| params.svm_gamma.iter().map(move |&g| (c, g)))
        .collect()
}

impl FrontierMethod for RbfSvm {
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError> {
        if params.svm_c.is_empty() || params.svm_gamma.is_empty() {
            return Err(ExperimentError::param(
                "svm_c",
                "the RBF SVM needs at least one C and one gamma",
            ));
        }
        positive("svm_c", &params.svm_c)?;
        positive("svm_gamma", &params.svm_gamma)
    }

    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob> {
        vec![
            SweepKnob::new("C", "penalties C", false, params.svm_c.clone()),
            SweepKnob::new("γ", "kernel widths γ", false, params.svm_gamma.clone()),
        ]
    }

    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]) {
        params.svm_c = lists[0].clone();
        params.svm_gamma = lists[1].clone();
    }

    fn prepare(
        &self,
        session: &Session,
        _params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError> {
        table(session, &[], false)
    }

    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem> {
        each_rep(svm_cells(params), params.reps, |(c, gamma), rep| {
            FrontierItem::Svm { c, gamma, rep }
        })
    }

    fn item(
        &self,
        _session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        _progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        let (Some(Table { x, labels }), FrontierItem::Svm { c, gamma, rep }) =
            (prep.get::<Table>(), *item)
        else {
            return Err(wrong_item(item, params));
        };
        let p = KernelSvmParams {
            c,
            gamma,
            ..KernelSvmParams::default()
        };
        // The fold seeds of the `baselines` grid search: the same cell scores alike.
        let seed = Rng::stream(params.seed, rep as u64).next_u64();
        let cv = kernel_svm::cross_validate(&p, x.view(), labels, SVM_FOLDS, seed)?;
        let t0 = Instant::now();
        let model = p.fit(x.view(), labels)?;
        let train = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        std::hint::black_box(model.predict(x.view())?);
        let predict = t1.elapsed().as_secs_f64();
        Ok(FrontierOutput::Svm {
            accuracy: cv.accuracy,
            support_vectors: model
                .machines
                .iter()
                .map(|m| m.support_vectors.nrows())
                .sum(),
            train_us: micros(train, x.nrows()),
            predict_us: micros(predict, x.nrows()),
        })
    }

    /// One point per (C, gamma).
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints {
        let points = svm_cells(params)
            .into_iter()
            .map(|(c, gamma)| {
                let (mut acc, mut sv, mut train, mut predict) =
                    (Vec::new(), Vec::new(), Vec::new(), Vec::new());
                for (item, out) in &pairs {
                    if let (
                        FrontierItem::Svm {
                            c: cc, gamma: gg, ..
                        },
                        FrontierOutput::Svm {
                            accuracy,
                            support_vectors,
                            train_us,
                            predict_us,
                        },
                    ) = (item, out)
                        && (*cc, *gg) == (c, gamma)
                    {
                        acc.push(*accuracy);
                        sv.push(*support_vectors as f64);
                        train.push(*train_us);
                        predict.push(*predict_us);
                    }
                }
                let support = mean(sv.into_iter());
                point(
                    format!("C {c} γ {gamma}"),
                    format!(
                        "RBF SVM: C {c}, gamma {gamma}; {support:.0} support vectors over its \
                         one-vs-one machines"
                    ),
                    vec![("c", c), ("gamma", gamma), ("support_vectors", support)],
                    &acc,
                    train,
                    predict,
                )
            })
            .collect();
        MethodPoints {
            points,
            paper_default: None,
            score_name: format!("accuracy ({SVM_FOLDS}-fold)"),
            unit: "grasp",
        }
    }
}
