//! The points of each kind of method: scores and times by size, from the items' outputs.

use super::*;

/// A point from its repetitions' scores and times.
pub(super) fn point(
    label: String,
    detail: String,
    knobs: Vec<(&str, f64)>,
    scores: &[f64],
    train_us: Vec<f64>,
    predict_us: Vec<f64>,
) -> FrontierPoint {
    let (score, score_se) = mean_se(scores);
    FrontierPoint {
        label,
        detail,
        knobs: knobs.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        score,
        score_se,
        reps: scores.len(),
        train_us: median(train_us),
        predict_us: median(predict_us),
    }
}

pub(super) fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}

/// DS/GS: one point per capacity × tau.
pub(super) fn recognition_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> (Vec<FrontierPoint>, Option<usize>, String) {
    let sizes = params.sizes();
    let base = params.recognition();
    let paper = (base.gs.gp.capacity, base.gs.gp.tau);
    let points = sizes
        .iter()
        .map(|&(capacity, tau)| {
            let (mut scores, mut train, mut predict) = (Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
                if let (
                    FrontierItem::Recognition {
                        capacity: c,
                        tau: t,
                        ..
                    },
                    FrontierOutput::Recognition {
                        all,
                        final_20,
                        train_us,
                        predict_us,
                    },
                ) = (item, out)
                    && (*c, *t) == (capacity, tau)
                {
                    scores.push(match params.score {
                        RecognitionScore::All => *all,
                        RecognitionScore::Final20 => *final_20,
                    });
                    train.push(*train_us);
                    predict.push(*predict_us);
                }
            }
            point(
                format!("capacity {capacity} · τ {tau}"),
                format!(
                    "{}, {} features: capacity {capacity}, tau {tau}",
                    params.method.title(),
                    params.features.name()
                ),
                vec![("capacity", capacity as f64), ("tau", tau as f64)],
                &scores,
                train,
                predict,
            )
        })
        .collect();
    let paper_default = sizes.iter().position(|&s| s == paper);
    let score_name = match params.score {
        RecognitionScore::All => "accuracy (all)",
        RecognitionScore::Final20 => "accuracy (final 20 %)",
    };
    (points, paper_default, score_name.into())
}

/// Sparse coding: one dictionary coded at every gamma, each cross-validated over the
/// repetitions' fold assignments.
pub(super) fn sparse_dictionary(
    params: &FrontierParams,
    data: &StabilityData,
    num_bases: usize,
    beta: f64,
    progress: &Progress,
) -> Result<Vec<SparseCell>, ExperimentError> {
    let settings = PipelineSettings::default();
    let rep_seeds = params.sparse_rep_seeds();
    let fit = DictionaryParams {
        num_bases,
        beta,
        ..settings.dictionary.clone()
    }
    .fit_within(data.x.view(), progress)
    .map_err(crate::experiments::stability::StabilityError::sparse)?;
    let mut out = Vec::with_capacity(params.gamma.len());
    for &gamma in &params.gamma {
        progress.checkpoint()?;
        let codes = fit
            .dictionary
            .encode(data.x.view(), gamma)
            .map_err(crate::experiments::stability::StabilityError::sparse)?;
        let features = concatenated_codes(codes, data.sensor_count());
        let t1 = Instant::now();
        let svm = settings
            .svm
            .fit(features.view(), &data.labels)
            .map_err(crate::experiments::stability::StabilityError::svm)?;
        let fit_secs = t1.elapsed().as_secs_f64();
        let mut scores = Vec::with_capacity(rep_seeds.len());
        let mut coding = Vec::with_capacity(rep_seeds.len());
        let mut deciding = Vec::with_capacity(rep_seeds.len());
        for &seed in &rep_seeds {
            // Coding and deciding are timed once per repetition; the median resists the
            // machine's load.
            let t0 = Instant::now();
            std::hint::black_box(
                fit.dictionary
                    .encode(data.x.view(), gamma)
                    .map_err(crate::experiments::stability::StabilityError::sparse)?,
            );
            coding.push(t0.elapsed().as_secs_f64());
            let t2 = Instant::now();
            std::hint::black_box(svm.predict_all(features.view()));
            deciding.push(t2.elapsed().as_secs_f64());
            let folds = stratified_k_fold(&data.labels, 10, seed)
                .map_err(crate::experiments::stability::StabilityError::svm)?;
            let svm = crate::svm::LinearSvmParams {
                seed,
                ..settings.svm.clone()
            };
            let cv = cross_validate(features.view(), &data.labels, &folds, &svm)
                .map_err(crate::experiments::stability::StabilityError::svm)?;
            scores.push(cv.weighted_success_rate);
        }
        let grasps = data.grasp_count() as f64;
        out.push(SparseCell {
            num_bases,
            beta,
            gamma,
            scores,
            train_us: 1e6 * (fit.secs + median(coding.clone()) + fit_secs) / grasps,
            predict_us: 1e6 * (median(coding) + median(deciding)) / grasps,
        });
    }
    Ok(out)
}

/// Sparse coding + SVM: per num_bases, the (beta, gamma) with the best mean score.
pub(super) fn sparse_points(
    params: &FrontierParams,
    pairs: Vec<(FrontierItem, FrontierOutput)>,
) -> (Vec<FrontierPoint>, Option<usize>) {
    let cells: Vec<SparseCell> = pairs
        .into_iter()
        .flat_map(|(_, o)| match o {
            FrontierOutput::Dictionary { cells } => cells,
            _ => Vec::new(),
        })
        .collect();
    let mut ks = params.num_bases.clone();
    ks.sort_unstable();
    ks.dedup();
    let points: Vec<FrontierPoint> = ks
        .iter()
        .filter_map(|&k| {
            // Grid order breaks ties, so the choice does not depend on the thread count.
            cells
                .iter()
                .filter(|c| c.num_bases == k)
                .map(|c| (mean_se(&c.scores), c))
                .fold(
                    None,
                    |acc: Option<((f64, f64), &SparseCell)>, x| match acc {
                        Some(a) if a.0.0 >= x.0.0 => Some(a),
                        _ => Some(x),
                    },
                )
        })
        .map(|((score, score_se), c)| FrontierPoint {
            label: format!("K {}", c.num_bases),
            detail: format!(
                "sparse coding + SVM: num_bases {}, beta {}, gamma {}",
                c.num_bases, c.beta, c.gamma
            ),
            knobs: vec![
                ("num_bases".into(), c.num_bases as f64),
                ("beta".into(), c.beta),
                ("gamma".into(), c.gamma),
            ],
            score,
            score_se,
            reps: c.scores.len(),
            train_us: c.train_us,
            predict_us: c.predict_us,
        })
        .collect();
    let paper_default = ks.iter().position(|&k| k == SPARSE_PAPER_NUM_BASES);
    (points, paper_default)
}

/// DU/GU: one point per threshold, NMI over the orders with the clusters it leaves.
pub(super) fn threshold_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> Vec<FrontierPoint> {
    let c = params.clustering();
    let expert = match c.learner {
        UnsupervisedLearner::Du => (c.ds.gp.capacity, c.ds.gp.tau),
        UnsupervisedLearner::Gu => (c.gs.gp.capacity, c.gs.gp.tau),
    };
    params
        .thresholds
        .iter()
        .map(|&threshold| {
            let runs: Vec<(&ClusteringRun, f64, f64)> = pairs
                .iter()
                .filter_map(|(_, o)| match o {
                    FrontierOutput::Threshold {
                        run,
                        train_us,
                        predict_us,
                    } if run.threshold == threshold => Some((run, *train_us, *predict_us)),
                    _ => None,
                })
                .collect();
            let effective = mean(runs.iter().map(|r| r.0.effective as f64));
            let created = mean(runs.iter().map(|r| r.0.clusters as f64));
            let nmi: Vec<f64> = runs.iter().map(|r| r.0.nmi).collect();
            point(
                format!("θ {threshold}"),
                format!(
                    "{}: threshold {threshold} (experts: capacity {}, tau {}); \
                     {effective:.1} effective clusters of {created:.1} created (means over \
                     the orders)",
                    params.label(),
                    expert.0,
                    expert.1
                ),
                vec![
                    ("threshold", threshold),
                    ("effective", effective),
                    ("created", created),
                ],
                &nmi,
                runs.iter().map(|r| r.1).collect(),
                runs.iter().map(|r| r.2).collect(),
            )
        })
        .collect()
}

/// k-means / SOM: one point per k.
pub(super) fn cluster_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> (Vec<FrontierPoint>, Option<usize>) {
    let points = params
        .ks
        .iter()
        .map(|&k| {
            let (mut nmi, mut eff, mut train, mut predict) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
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
            let what = match params.method {
                MethodId::Som => {
                    let s = som_setup(k, 0);
                    format!("SOM {} × {} units", s.rows, s.cols)
                }
                MethodId::KMeans => format!("sequential k-means, k {k}"),
                MethodId::SparseSvm
                | MethodId::RawSvm
                | MethodId::Ds
                | MethodId::Gs
                | MethodId::Du
                | MethodId::Gu
                | MethodId::RbfSvm
                | MethodId::Classifier(_) => format!("{}, k {k}", params.method.title()),
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
    (points, params.ks.iter().position(|&k| k == PAPER_K))
}

/// RBF SVM: one point per (C, gamma).
pub(super) fn svm_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> Vec<FrontierPoint> {
    params
        .svm_cells()
        .into_iter()
        .map(|(c, gamma)| {
            let (mut acc, mut sv, mut train, mut predict) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
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
        .collect()
}

/// A registered method: one point per size, its knobs named as the method names them.
pub(super) fn classifier_points(
    params: &FrontierParams,
    method: &dyn Classifier,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> Vec<FrontierPoint> {
    let knobs = method.info().size_knobs;
    params
        .classifier_sizes(method)
        .iter()
        .enumerate()
        .map(|(i, size)| {
            let (mut acc, mut train, mut predict) = (Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
                if let (
                    FrontierItem::Classifier { size: s, .. },
                    FrontierOutput::Classifier {
                        accuracy,
                        train_us,
                        predict_us,
                    },
                ) = (item, out)
                    && *s == i
                {
                    acc.push(*accuracy);
                    train.push(*train_us);
                    predict.push(*predict_us);
                }
            }
            let named: Vec<(&str, f64)> = knobs.iter().map(|k| k.name).zip(size.clone()).collect();
            let words = named
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(" · ");
            point(
                words.clone(),
                format!("{}: {words}", method.info().title),
                named,
                &acc,
                train,
                predict,
            )
        })
        .collect()
}
