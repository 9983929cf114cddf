//! Object-recognition tasks: DS, GS, the unsupervised learners and the baselines under a perturbation.

use super::*;

/// Express `perturbed` (normalised on itself) in the clean session's normalisation, as a
/// model calibrated on the clean session would see it.
pub(super) fn renormalise(
    perturbed: &FeatureSequences,
    clean: &FeatureSequences,
) -> FeatureSequences {
    let mut out = perturbed.clone();
    for m in &mut out.sequences {
        for mut row in m.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                let raw = perturbed.min[j] + *v * (perturbed.max[j] - perturbed.min[j]);
                let range = clean.max[j] - clean.min[j];
                *v = if range > 0.0 {
                    (raw - clean.min[j]) / range
                } else {
                    0.0
                };
            }
        }
    }
    out.min = clean.min.clone();
    out.max = clean.max.clone();
    out
}

pub(super) fn recognition_task(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    pert: Option<(Perturbation, f64)>,
    perturbed: Option<&Session>,
    rep: usize,
) -> Result<Vec<f64>, ExperimentError> {
    let rc = &params.recognition;
    let scope = pert.map(|(p, _)| p.scope());
    let feats = perturbed_sequences(params, prep, scope, perturbed)?;
    let train_seqs = match (&feats, scope) {
        (Some(f), Some(Scope::All)) => f,
        _ => &prep.clean,
    };
    let test_seqs = feats.as_ref().unwrap_or(&prep.clean);
    let table = table_features(prep, scope, perturbed)?;
    // The same order as `run_recognition`'s repetition `rep` (without noise).
    let mut rng = Rng::stream(params.seed, rep as u64);
    let (teach, order) = protocol_order(&prep.labels, prep.n_classes, &mut rng);
    let n_test = ((rc.test_fraction * order.len() as f64).round() as usize).min(order.len());
    let n_train = order.len() - n_test;
    let mut aux = Rng::stream(params.seed, PROTOCOL_STREAM + rep as u64);
    let keep = training_kept(
        pert,
        &prep.labels,
        prep.n_classes,
        &order[..n_train],
        true,
        &mut aux,
    );
    // The unsupervised methods learn from every grasp; a training perturbation leaves
    // them the same subset of grasps as it leaves the supervised ones to learn from.
    let all: Vec<usize> = (0..prep.labels.len()).collect();
    let kept_all = training_kept(pert, &prep.labels, prep.n_classes, &all, false, &mut aux);
    let subset: Vec<usize> = all.iter().copied().filter(|&g| kept_all[g]).collect();
    let sub_labels: Vec<usize> = subset.iter().map(|&g| prep.labels[g]).collect();
    // The subset's sequences, copied once for DU and GU.
    let sub_seqs: Vec<Array2<f64>> =
        if (params.methods.iter()).any(|m| matches!(m, MethodId::Du | MethodId::Gu)) {
            subset
                .iter()
                .map(|&g| test_seqs.sequences[g].clone())
                .collect()
        } else {
            Vec::new()
        };
    let k = rc.clusters.unwrap_or(prep.n_classes);
    let cluster_seed = Rng::stream(params.seed, CLUSTER_STREAM + rep as u64).next_u64();
    let mut out = Vec::with_capacity(params.methods.len());
    for &method in &params.methods {
        let score = match method {
            MethodId::Ds | MethodId::Gs => {
                let kind = if method == MethodId::Ds {
                    SupervisedLearner::Ds
                } else {
                    SupervisedLearner::Gs
                };
                supervised_score(
                    kind, rc, prep, train_seqs, test_seqs, &teach, &order, n_train, &keep,
                )?
            }
            MethodId::Du | MethodId::Gu => {
                unsupervised_nmi(method, params, &sub_seqs, &sub_labels, test_seqs.dim(), rep)?
            }
            MethodId::KMeans | MethodId::Som => {
                let Some((_, test)) = &table else {
                    return Err(ExperimentError::Data("no Table I features".into()));
                };
                baseline_nmi(method, k, cluster_seed, test, &subset, &sub_labels)?
            }
            MethodId::RbfSvm => {
                let Some((train_x, test_x)) = &table else {
                    return Err(ExperimentError::Data("no Table I features".into()));
                };
                rbf_accuracy(params, prep, train_x, test_x, pert, rep)?
            }
            MethodId::Classifier(c) => {
                // The online protocol's split: taught and kept training grasps, then the
                // test part.
                let train: Vec<usize> = (teach.iter().copied())
                    .chain(
                        (order[..n_train].iter().zip(&keep)).filter_map(|(&g, &k)| k.then_some(g)),
                    )
                    .collect();
                let seed = Rng::stream(params.seed, CLASSIFIER_STREAM + rep as u64).next_u64();
                train_test(
                    c.method(),
                    &c.method().default_size(),
                    train_seqs,
                    test_seqs,
                    &prep.labels,
                    prep.n_classes,
                    &train,
                    &order[n_train..],
                    seed,
                    &Progress::new(),
                )?
                .accuracy
            }
            MethodId::SparseSvm | MethodId::RawSvm => {
                return Err(ExperimentError::param(
                    "methods",
                    format!("{} is a grasp-stability method", method.key()),
                ));
            }
        };
        out.push(score);
    }
    Ok(out)
}

/// The perturbed session's feature sequences when a sequence method needs them: normalised
/// on themselves when the perturbation is there all along, else in the clean session's
/// normalisation. None without a perturbed session or a sequence method.
fn perturbed_sequences(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    scope: Option<Scope>,
    perturbed: Option<&Session>,
) -> Result<Option<FeatureSequences>, ExperimentError> {
    let sequences = params
        .methods
        .iter()
        .any(|m| m.input() != catalogue::Input::TableOne);
    Ok(match perturbed {
        Some(ps) if sequences => {
            let f = feature_sequences(
                ps,
                &SequenceParams {
                    features: params.recognition.features,
                    taxel_noise_variance: 0.0,
                    seed: params.seed,
                },
            )?;
            Some(if scope == Some(Scope::All) {
                f
            } else {
                renormalise(&f, &prep.clean)
            })
        }
        _ => None,
    })
}

/// Table I features of the training and of the test grasps (every grasp in each).
type TrainTest = (Array2<f64>, Array2<f64>);

/// Table I features: (training rows, test rows), z-scored as the clean session unless
/// the perturbation is there all along.
fn table_features(
    prep: &RecognitionPrep,
    scope: Option<Scope>,
    perturbed: Option<&Session>,
) -> Result<Option<TrainTest>, ExperimentError> {
    Ok(match (&prep.table, perturbed) {
        (Some((clean, norm)), Some(ps)) => {
            let raw = session_features(ps)?;
            if scope == Some(Scope::All) {
                let own = Normaliser::fit(Normalisation::ZScore, raw.view())
                    .and_then(|n| n.transform(raw.view()))?;
                Some((own.clone(), own))
            } else {
                let t = norm.transform(raw.view())?;
                Some((clean.clone(), t))
            }
        }
        (Some((clean, _)), None) => Some((clean.clone(), clean.clone())),
        _ => None,
    })
}

/// DU's or GU's NMI on the kept grasps, one run at the setup's threshold in repetition
/// `rep`'s order.
fn unsupervised_nmi(
    method: MethodId,
    params: &RobustnessParams,
    sub_seqs: &[Array2<f64>],
    sub_labels: &[usize],
    dim: usize,
    rep: usize,
) -> Result<f64, ExperimentError> {
    let rc = &params.recognition;
    let threshold = if method == MethodId::Du {
        rc.du_threshold
    } else {
        rc.gu_threshold
    };
    let cp = ClusteringParams {
        learner: if method == MethodId::Du {
            UnsupervisedLearner::Du
        } else {
            UnsupervisedLearner::Gu
        },
        features: rc.features,
        thresholds: vec![threshold],
        reps: 1,
        seed: params.seed,
        label_set: rc.label_set.clone(),
        ds: rc.ds.clone(),
        gs: rc.gs.clone(),
        gu_aggregate: rc.gu_aggregate,
        gu_min_grasps: rc.gu_min_grasps,
        baseline_max_k: 0,
        // The rest as the clustering experiment's defaults.
        ..ClusteringParams::default()
    };
    // One threshold on a subset: as short as the other tasks, cancelled between them.
    Ok(one_run(
        &cp,
        sub_seqs,
        sub_labels,
        dim,
        threshold,
        rep,
        None,
        &Progress::new(),
    )?
    .nmi)
}

/// Sequential k-means' or the SOM's NMI on the Table I test rows of the kept grasps.
fn baseline_nmi(
    method: MethodId,
    k: usize,
    cluster_seed: u64,
    test: &Array2<f64>,
    subset: &[usize],
    sub_labels: &[usize],
) -> Result<f64, ExperimentError> {
    let data = gather(test.view(), subset);
    let pred = if method == MethodId::KMeans {
        SequentialKMeansParams {
            k,
            passes: 1,
            seed: cluster_seed,
        }
        .fit(data.view())
        .and_then(|m| m.assign(data.view()))
    } else {
        som_setup(k, cluster_seed)
            .fit(data.view())
            .and_then(|m| m.assign(data.view()))
    }?;
    Ok(scores(sub_labels, &pred).nmi)
}

/// DS or GS through the supervised protocol: teach one grasp per class, then predict and
/// learn the training part (the grasps `keep` leaves), then predict the test part.
#[allow(clippy::too_many_arguments)]
pub(super) fn supervised_score(
    kind: SupervisedLearner,
    rc: &RecognitionSetup,
    prep: &RecognitionPrep,
    train_seqs: &FeatureSequences,
    test_seqs: &FeatureSequences,
    teach: &[usize],
    order: &[usize],
    n_train: usize,
    keep: &[bool],
) -> Result<f64, ExperimentError> {
    let mut learner = new_learner(kind, prep.clean.dim(), prep.n_classes, &rc.ds, &rc.gs)?;
    for &g in teach {
        learner.train_sequence(train_seqs.sequences[g].view(), prep.labels[g]);
    }
    let mut hits = 0usize;
    for (i, &g) in order.iter().enumerate() {
        let is_test = i >= n_train;
        if !is_test && !keep[i] {
            continue;
        }
        let seqs = if is_test { test_seqs } else { train_seqs };
        let seq = seqs.sequences[g].view();
        let dist = learner.predict_sequence(seq);
        if is_test {
            hits += usize::from(learner.decide(dist.view()) == prep.labels[g]);
        } else {
            learner.train_sequence(seq, prep.labels[g]);
        }
    }
    let n_test = order.len() - n_train;
    Ok(if n_test > 0 {
        hits as f64 / n_test as f64
    } else {
        0.0
    })
}

/// Stratified k-fold accuracy of the RBF SVM: trained on `train_x` rows of the training
/// folds (thinned by a training perturbation), tested on `test_x` rows of the test fold.
pub(super) fn rbf_accuracy(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    train_x: &Array2<f64>,
    test_x: &Array2<f64>,
    pert: Option<(Perturbation, f64)>,
    rep: usize,
) -> Result<f64, ExperimentError> {
    let rc = &params.recognition;
    let labels = &prep.labels;
    let fold_seed = Rng::stream(params.seed, rep as u64).next_u64();
    let fold_of = stratified_folds(labels, rc.svm_folds, fold_seed);
    let mut aux = Rng::stream(params.seed, SVM_STREAM + rep as u64);
    let mut correct = 0usize;
    for f in 0..rc.svm_folds {
        let train: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] != f).collect();
        let test: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] == f).collect();
        let kept = training_kept(pert, labels, prep.n_classes, &train, false, &mut aux);
        let train: Vec<usize> = train
            .iter()
            .zip(&kept)
            .filter(|(_, k)| **k)
            .map(|(&i, _)| i)
            .collect();
        let y: Vec<usize> = train.iter().map(|&i| labels[i]).collect();
        let model = rc.svm.fit(gather(train_x.view(), &train).view(), &y)?;
        let pred = model.predict(gather(test_x.view(), &test).view())?;
        correct += test
            .iter()
            .zip(&pred)
            .filter(|(i, p)| labels[**i] == **p)
            .count();
    }
    Ok(correct as f64 / labels.len().max(1) as f64)
}

/// Which grasps of the training part are learned from: all, or those left by class
/// imbalance (half the classes, drawn at random, keep `share` of their training grasps)
/// or few examples (the first n of each class; n − 1 when one grasp per class was
/// `taught` before the training part).
pub(super) fn training_kept(
    pert: Option<(Perturbation, f64)>,
    labels: &[usize],
    n_classes: usize,
    train_part: &[usize],
    taught: bool,
    rng: &mut Rng,
) -> Vec<bool> {
    let mut seen = vec![0usize; n_classes];
    let total: Vec<usize> = (0..n_classes)
        .map(|c| train_part.iter().filter(|&&g| labels[g] == c).count())
        .collect();
    let limit: Vec<usize> = match pert {
        Some((Perturbation::FewExamples, n)) => {
            vec![(n as usize).saturating_sub(usize::from(taught)); n_classes]
        }
        Some((Perturbation::Imbalance, share)) => {
            let mut classes: Vec<usize> = (0..n_classes).collect();
            rng.shuffle(&mut classes);
            let mut limit = total.clone();
            for &c in &classes[..n_classes / 2] {
                limit[c] = (share * total[c] as f64).round() as usize;
            }
            limit
        }
        _ => total,
    };
    train_part
        .iter()
        .map(|&g| {
            let c = labels[g];
            seen[c] += 1;
            seen[c] <= limit[c]
        })
        .collect()
}
