//! A frontier's work: its items (one per size and repetition), preparing the session, computing one item, and assembling the points.

use super::*;

/// A unit of a frontier's work. Its seeds follow from the run's seed and the item alone,
/// so any machine computes it alike.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierItem {
    /// DS/GS: repetition `rep` of the supervised protocol at one size.
    Recognition {
        capacity: usize,
        tau: usize,
        rep: usize,
    },
    /// Sparse coding: one dictionary, coded and cross-validated at every gamma and
    /// repetition.
    Dictionary { num_bases: usize, beta: f64 },
    /// DU/GU: one learning run at one threshold, in order `rep`.
    Threshold { threshold: f64, rep: usize },
    /// k-means / SOM: k centres / units, order `rep`.
    Clusters { k: usize, rep: usize },
    /// RBF SVM: repetition `rep` of the cross validation at (C, gamma).
    Svm { c: f64, gamma: f64, rep: usize },
    /// A registered method: repetition `rep` of its cross validation at its `size`-th size.
    Classifier { size: usize, rep: usize },
}

/// One (num_bases, beta, gamma) cell: its scores over the repetitions and its timings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseCell {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
    pub scores: Vec<f64>,
    /// Microseconds per grasp.
    pub train_us: f64,
    pub predict_us: f64,
}

/// What an item leaves. Times are microseconds per step (DS/GS) or per grasp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierOutput {
    Recognition {
        all: f64,
        final_20: f64,
        train_us: f64,
        predict_us: f64,
    },
    Dictionary {
        cells: Vec<SparseCell>,
    },
    Threshold {
        run: ClusteringRun,
        train_us: f64,
        predict_us: f64,
    },
    Clusters {
        nmi: f64,
        effective: usize,
        train_us: f64,
        predict_us: f64,
    },
    Svm {
        accuracy: f64,
        /// Support vectors summed over the one-vs-one machines: kernel evaluations per
        /// prediction.
        support_vectors: usize,
        train_us: f64,
        predict_us: f64,
    },
    Classifier {
        accuracy: f64,
        train_us: f64,
        predict_us: f64,
    },
}

/// What every item of a frontier shares.
pub enum FrontierPrep {
    Recognition(Box<RecognitionParams>, RecognitionPrep),
    Sparse(Box<StabilityData>),
    Clustering(Box<ClusteringParams>, ClusteringPrep),
    /// The Table I features (z-scored for the clusterers; raw for the SVM, which scales
    /// inside each training fold) and the objects.
    Table {
        x: Array2<f64>,
        labels: Vec<usize>,
    },
    /// A registered method's sequences and objects.
    Classifier(Box<ClassifierPrep>),
}

/// Folds of a registered method's cross validation.
pub const CLASSIFIER_FOLDS: usize = 10;

impl FrontierParams {
    /// "DS, all features", "sparse coding + SVM", "sequential k-means".
    pub fn label(&self) -> String {
        let m = self.method;
        if m.uses_features() {
            format!("{}, {} features", m.title(), self.features.name())
        } else if m == MethodId::KMeans {
            crate::cluster::KMEANS_NAME.into()
        } else {
            m.title().to_string()
        }
    }

    /// The protocol of DS/GS at the paper's size (items set capacity and tau).
    pub(super) fn recognition(&self) -> RecognitionParams {
        RecognitionParams {
            // Only DS and GS frontiers run the protocol.
            learner: SupervisedLearner::of(self.method).unwrap_or(SupervisedLearner::Gs),
            features: self.features,
            reps: self.reps,
            seed: self.seed,
            early_fractions: Vec::new(),
            ..RecognitionParams::default()
        }
    }

    /// The clustering run of DU/GU over the thresholds, without the baselines.
    pub(super) fn clustering(&self) -> ClusteringParams {
        // Only DU and GU frontiers run the clustering.
        let learner = UnsupervisedLearner::of(self.method).unwrap_or(UnsupervisedLearner::Gu);
        let mut p = ClusteringParams {
            features: self.features,
            thresholds: self.thresholds.clone(),
            reps: self.reps,
            seed: self.seed,
            baseline_max_k: 0,
            ..ClusteringParams::for_learner(learner)
        };
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = self.expert_capacity.unwrap_or(gp.capacity);
            gp.tau = self.expert_tau.unwrap_or(gp.tau);
        }
        p
    }

    pub(super) fn sizes(&self) -> Vec<(usize, usize)> {
        self.capacities
            .iter()
            .flat_map(|&c| self.taus.iter().map(move |&t| (c, t)))
            .collect()
    }

    pub(super) fn svm_cells(&self) -> Vec<(f64, f64)> {
        self.svm_c
            .iter()
            .flat_map(|&c| self.svm_gamma.iter().map(move |&g| (c, g)))
            .collect()
    }

    pub(super) fn sparse_rep_seeds(&self) -> Vec<u64> {
        (0..self.reps)
            .map(|r| Rng::stream(self.seed, r as u64).next_u64())
            .collect()
    }
}

/// Check the parameters against the session and prepare what every item shares.
pub fn prepare_frontier(
    session: &Session,
    params: &FrontierParams,
) -> Result<FrontierPrep, ExperimentError> {
    params.validate()?;
    Ok(match params.method {
        MethodId::RawSvm => unreachable!("validate rejects a method without size knobs"),
        MethodId::Ds | MethodId::Gs => {
            let p = params.recognition();
            let prep = prepare_recognition(session, &p)?;
            FrontierPrep::Recognition(Box::new(p), prep)
        }
        MethodId::SparseSvm => FrontierPrep::Sparse(Box::new(StabilityData::from_session(
            session,
            &DataOptions::default(),
        )?)),
        MethodId::Du | MethodId::Gu => {
            let p = params.clustering();
            let prep = prepare_clustering(session, &p)?;
            FrontierPrep::Clustering(Box::new(p), prep)
        }
        MethodId::KMeans | MethodId::Som | MethodId::RbfSvm => {
            let (labels, _) = session_labels(session, "object")?;
            let raw = session_features(session)?;
            if let Some(k) = params.ks.iter().find(|&&k| k > raw.nrows())
                && params.method != MethodId::RbfSvm
            {
                return Err(ExperimentError::param(
                    "ks",
                    format!("{k} clusters for {} grasps", raw.nrows()),
                ));
            }
            let x = if params.method == MethodId::RbfSvm {
                raw
            } else {
                Normaliser::fit(Normalisation::ZScore, raw.view())
                    .and_then(|n| n.transform(raw.view()))?
            };
            FrontierPrep::Table { x, labels }
        }
        MethodId::Classifier(_) => FrontierPrep::Classifier(Box::new(prepare_classifier(
            session,
            params.features,
            "object",
        )?)),
    })
}

/// What an item costs relative to the others of its frontier: the experts' update grows
/// with their capacity, a dictionary's learning and coding with its bases, the clusterers
/// with their centres; an RBF SVM's or a registered method's cross validation costs about
/// the same at every size.
pub fn item_cost(item: &FrontierItem) -> f64 {
    match *item {
        // A sparse GP's update grows with its basis vectors, and with their square past a
        // few tens.
        FrontierItem::Recognition { capacity, .. } => {
            let c = capacity as f64;
            c + c * c / 50.0
        }
        FrontierItem::Dictionary { num_bases, .. } => num_bases as f64,
        FrontierItem::Clusters { k, .. } => k as f64,
        FrontierItem::Threshold { .. }
        | FrontierItem::Svm { .. }
        | FrontierItem::Classifier { .. } => 1.0,
    }
}

/// The items of a frontier, in the order its points are assembled: every size (or knob
/// value) with its repetitions in order.
pub fn frontier_items(params: &FrontierParams) -> Vec<FrontierItem> {
    let reps = 0..params.reps;
    match params.method {
        // No size knob: no items (validate says why).
        MethodId::RawSvm => Vec::new(),
        MethodId::Ds | MethodId::Gs => params
            .sizes()
            .into_iter()
            .flat_map(|(capacity, tau)| {
                reps.clone()
                    .map(move |rep| FrontierItem::Recognition { capacity, tau, rep })
            })
            .collect(),
        MethodId::SparseSvm => params
            .num_bases
            .iter()
            .flat_map(|&num_bases| {
                params
                    .beta
                    .iter()
                    .map(move |&beta| FrontierItem::Dictionary { num_bases, beta })
            })
            .collect(),
        MethodId::Du | MethodId::Gu => params
            .thresholds
            .iter()
            .flat_map(|&threshold| {
                reps.clone()
                    .map(move |rep| FrontierItem::Threshold { threshold, rep })
            })
            .collect(),
        MethodId::KMeans | MethodId::Som => params
            .ks
            .iter()
            .flat_map(|&k| {
                reps.clone()
                    .map(move |rep| FrontierItem::Clusters { k, rep })
            })
            .collect(),
        MethodId::RbfSvm => params
            .svm_cells()
            .into_iter()
            .flat_map(|(c, gamma)| {
                reps.clone()
                    .map(move |rep| FrontierItem::Svm { c, gamma, rep })
            })
            .collect(),
        MethodId::Classifier(c) => (0..params.classifier_sizes(c.method()).len())
            .flat_map(|size| {
                reps.clone()
                    .map(move |rep| FrontierItem::Classifier { size, rep })
            })
            .collect(),
    }
}

pub(super) fn wrong_item(item: &FrontierItem, params: &FrontierParams) -> ExperimentError {
    ExperimentError::param(
        "item",
        format!(
            "{item:?} is not an item of a {} frontier",
            params.method.title()
        ),
    )
}

pub(super) fn micros(secs: f64, units: usize) -> f64 {
    1e6 * secs / units.max(1) as f64
}

/// Compute one item.
pub fn frontier_item(
    session: &Session,
    params: &FrontierParams,
    prep: &FrontierPrep,
    item: &FrontierItem,
    progress: &Progress,
) -> Result<FrontierOutput, ExperimentError> {
    match (prep, *item) {
        (
            FrontierPrep::Recognition(base, prep),
            FrontierItem::Recognition { capacity, tau, rep },
        ) => {
            let mut p = (**base).clone();
            for gp in [&mut p.ds.gp, &mut p.gs.gp] {
                gp.capacity = capacity;
                gp.tau = tau;
            }
            let r = recognition_repetition(&p, session, prep, rep, progress)?;
            Ok(FrontierOutput::Recognition {
                all: r.all,
                final_20: r.final_20,
                train_us: micros(r.train_seconds, r.train_steps),
                predict_us: micros(r.predict_seconds, r.predict_steps),
            })
        }
        (FrontierPrep::Sparse(data), FrontierItem::Dictionary { num_bases, beta }) => {
            sparse_dictionary(params, data, num_bases, beta, progress)
                .map(|cells| FrontierOutput::Dictionary { cells })
        }
        (FrontierPrep::Clustering(base, prep), FrontierItem::Threshold { threshold, rep }) => {
            let run = one_run(
                base,
                &prep.feats.sequences,
                &prep.labels,
                prep.feats.dim(),
                threshold,
                rep,
                prep.pairs.as_ref(),
                progress,
            )?;
            // Per grasp, as the other clusterers: the observations of a grasp, each
            // scored by every expert.
            let seqs = &prep.feats.sequences;
            let per_grasp =
                seqs.iter().map(|s| s.nrows()).sum::<usize>() as f64 / seqs.len().max(1) as f64;
            Ok(FrontierOutput::Threshold {
                train_us: run.learn_step_us * per_grasp,
                predict_us: run.assign_step_us * per_grasp,
                run,
            })
        }
        (FrontierPrep::Table { x, labels }, FrontierItem::Clusters { k, rep }) => {
            let seed = baseline_seed(params.seed, k, rep);
            let t0 = Instant::now();
            let (pred, train) = match params.method {
                MethodId::KMeans => {
                    let m = SequentialKMeansParams { k, passes: 1, seed }.fit(x.view())?;
                    let train = t0.elapsed().as_secs_f64();
                    (m.assign(x.view())?, train)
                }
                MethodId::Som => {
                    let m = som_setup(k, seed).fit(x.view())?;
                    let train = t0.elapsed().as_secs_f64();
                    (m.assign(x.view())?, train)
                }
                MethodId::SparseSvm
                | MethodId::RawSvm
                | MethodId::Ds
                | MethodId::Gs
                | MethodId::Du
                | MethodId::Gu
                | MethodId::RbfSvm
                | MethodId::Classifier(_) => return Err(wrong_item(item, params)),
            };
            let predict = t0.elapsed().as_secs_f64() - train;
            Ok(FrontierOutput::Clusters {
                nmi: scores(labels, &pred).nmi,
                effective: distinct(&pred),
                train_us: micros(train, x.nrows()),
                predict_us: micros(predict, x.nrows()),
            })
        }
        (FrontierPrep::Table { x, labels }, FrontierItem::Svm { c, gamma, rep }) => {
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
        (FrontierPrep::Classifier(prep), FrontierItem::Classifier { size, rep }) => {
            let MethodId::Classifier(c) = params.method else {
                return Err(wrong_item(item, params));
            };
            let sizes = params.classifier_sizes(c.method());
            let Some(size) = sizes.get(size) else {
                return Err(wrong_item(item, params));
            };
            let s = cv_repetition(
                c.method(),
                size,
                prep,
                CLASSIFIER_FOLDS,
                params.seed,
                rep,
                progress,
            )?;
            Ok(FrontierOutput::Classifier {
                accuracy: s.accuracy,
                train_us: s.train_us,
                predict_us: s.predict_us,
            })
        }
        _ => Err(wrong_item(item, params)),
    }
}

/// Sweep the method's size knobs on `session`.
pub fn run_frontier(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<Frontier, ExperimentError> {
    let start = Instant::now();
    // Choosing the inputs costs about AUTO_REPETITIONS of the frontier's average item.
    let costs: Vec<f64> = frontier_items(params).iter().map(item_cost).collect();
    let auto = match params.features.is_auto() {
        true => {
            crate::experiments::recognition::AUTO_REPETITIONS * costs.iter().sum::<f64>()
                / costs.len().max(1) as f64
        }
        false => 0.0,
    };
    let parts = progress.parts(&[auto, costs.iter().sum()]);
    let (params, feature_choice) = choose_auto_features(session, params, &parts[0])?;
    let params = &params;
    let progress = &parts[1];
    let prep = prepare_frontier(session, params)?;
    let items = frontier_items(params);
    let label = params.label();
    progress.set(0.0, format!("frontier {label}: starting"));
    let outputs = compute_items(
        &items,
        progress,
        &format!("frontier {label}"),
        "runs",
        item_cost,
        |item, part| frontier_item(session, params, &prep, item, part),
    )?;
    let frontier = assemble_frontier(
        &session.meta.name,
        params,
        &items,
        outputs,
        start.elapsed().as_secs_f64(),
    )?;
    Ok(Frontier {
        feature_choice,
        ..frontier
    })
}

/// `params` with `auto` replaced by the feature set chosen by cross validation on the
/// object labels at the method's default size (DS, GS: the paper's capacity and tau; DU,
/// GU: their experts' size, scored by DS's and GS's experts; a registered method: its
/// default size), and that choice; or as they are.
pub fn choose_auto_features(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<(FrontierParams, Option<FeatureChoice>), ExperimentError> {
    if !params.features.is_auto() {
        return Ok((params.clone(), None));
    }
    progress.set(0.0, "auto features: cross validation");
    let defaults = RecognitionParams::default();
    let (mut ds, mut gs) = (defaults.ds, defaults.gs);
    for gp in [&mut ds.gp, &mut gs.gp] {
        gp.capacity = params.expert_capacity.unwrap_or(gp.capacity);
        gp.tau = params.expert_tau.unwrap_or(gp.tau);
    }
    let experts = |learner| ExpertsScorer {
        learner,
        ds: &ds,
        gs: &gs,
    };
    let choose = |scorer: &dyn FoldScorer| {
        choose_features(session, scorer, "object", AUTO_FOLDS, params.seed, progress)
    };
    let choice = match params.method {
        MethodId::Ds | MethodId::Du => choose(&experts(SupervisedLearner::Ds))?,
        MethodId::Gs | MethodId::Gu => choose(&experts(SupervisedLearner::Gs))?,
        MethodId::Classifier(c) => {
            let size = c.method().default_size();
            choose(&ClassifierScorer {
                method: c.method(),
                size: &size,
            })?
        }
        MethodId::SparseSvm
        | MethodId::RawSvm
        | MethodId::KMeans
        | MethodId::Som
        | MethodId::RbfSvm => {
            return Err(ExperimentError::param(
                "features",
                format!("auto: {} reads no feature sequences", params.method.key()),
            ));
        }
    };
    let chosen = FrontierParams {
        features: choice.chosen,
        ..params.clone()
    };
    Ok((chosen, Some(choice)))
}

/// The frontier from every item's output (in item order): the points, the best and the
/// recommended point, the Pareto fronts.
pub fn assemble_frontier(
    session: &str,
    params: &FrontierParams,
    items: &[FrontierItem],
    outputs: Vec<FrontierOutput>,
    wall_seconds: f64,
) -> Result<Frontier, ExperimentError> {
    if items.len() != outputs.len() {
        return Err(ExperimentError::Data(format!(
            "{} items but {} outputs",
            items.len(),
            outputs.len()
        )));
    }
    let pairs: Vec<(FrontierItem, FrontierOutput)> = items.iter().copied().zip(outputs).collect();
    params.validate()?;
    let (points, paper_default, score_name, unit) = match params.method {
        MethodId::RawSvm => unreachable!("validate rejects a method without size knobs"),
        MethodId::Ds | MethodId::Gs => {
            let (p, d, s) = recognition_points(params, &pairs);
            (p, d, s, "step")
        }
        MethodId::SparseSvm => {
            let (p, d) = sparse_points(params, pairs);
            (p, d, "weighted success rate".to_string(), "grasp")
        }
        MethodId::Du | MethodId::Gu => (
            threshold_points(params, &pairs),
            None,
            "NMI".into(),
            "grasp",
        ),
        MethodId::KMeans | MethodId::Som => {
            let (p, d) = cluster_points(params, &pairs);
            (p, d, "NMI".into(), "grasp")
        }
        MethodId::RbfSvm => (
            svm_points(params, &pairs),
            None,
            format!("accuracy ({SVM_FOLDS}-fold)"),
            "grasp",
        ),
        MethodId::Classifier(c) => (
            classifier_points(params, c.method(), &pairs),
            None,
            format!("accuracy ({CLASSIFIER_FOLDS}-fold)"),
            "grasp",
        ),
    };
    let (best, recommended) =
        recommend(&points, params.cost).ok_or_else(|| ExperimentError::Data("no sizes".into()))?;
    let front = |axis: CostAxis| {
        let x: Vec<f64> = points.iter().map(|p| p.cost(axis)).collect();
        let y: Vec<f64> = points.iter().map(|p| p.score).collect();
        crate::figures::pareto_front(&x, &y)
    };
    Ok(Frontier {
        session: session.to_string(),
        params: params.clone(),
        score_name,
        unit: unit.into(),
        pareto_training: front(CostAxis::Training),
        pareto_prediction: front(CostAxis::Prediction),
        points,
        best,
        recommended,
        paper_default,
        wall_seconds,
        feature_choice: None,
    })
}
