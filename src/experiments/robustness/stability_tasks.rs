//! Grasp-stability tasks: sparse coding + linear SVM and the raw linear SVM under a perturbation.

use super::*;

pub(super) fn learn_dictionary(
    data: &StabilityData,
    st: &StabilitySetup,
    progress: &Progress,
) -> Result<Dictionary, ExperimentError> {
    let params = DictionaryParams {
        num_bases: st.config.num_bases,
        beta: st.config.beta,
        ..st.settings.dictionary.clone()
    };
    params
        .validate()
        .map_err(|source| ExperimentError::Parameter {
            name: "dictionary",
            source,
        })?;
    let fit = params
        .fit_within(data.x.view(), progress)
        .map_err(StabilityError::sparse)?;
    Ok(fit.dictionary)
}

/// Grasp features of both methods from scaled key-frame images (grasps × sensors·dim).
pub(super) fn features_of_images(
    images: Array2<f64>,
    sensors: usize,
    dim: usize,
    dictionary: &Dictionary,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    let g = images.nrows();
    // One grasp's image is its sensors' patches side by side: a view, not a copy.
    let patches = images.view().into_shape_with_order((g * sensors, dim))?;
    let codes = dictionary
        .encode(patches, gamma)
        .map_err(StabilityError::sparse)?;
    Ok((concatenated_codes(codes, sensors), images))
}

pub(super) fn stability_features(
    data: &StabilityData,
    dictionary: &Dictionary,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    features_of_images(
        data.images(),
        data.sensor_count(),
        data.dim(),
        dictionary,
        gamma,
    )
}

/// A perturbed session's features under the clean session's scaling and dictionary.
pub(super) fn stability_features_scaled_as(
    prep: &StabilityPrep,
    perturbed: &Session,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    let pressures = KeyFramePatches::from_session(perturbed, PatchScaling::None)
        .map_err(StabilityError::from)?
        .pressures;
    let images = match &prep.data.patches.scaler {
        Some(s) => s.transform(pressures.view()),
        None => pressures,
    };
    features_of_images(
        images,
        prep.data.sensor_count(),
        prep.data.dim(),
        &prep.dictionary,
        gamma,
    )
}

/// Train on `train` rows of (`train_x`, labels), predict `test` rows of `test_x`.
pub(super) fn svm_confusion(
    train_x: &Array2<f64>,
    test_x: &Array2<f64>,
    labels: &[bool],
    train: &[usize],
    test: &[usize],
    svm: &LinearSvmParams,
) -> Result<Confusion, ExperimentError> {
    let xt = gather(train_x.view(), train);
    let yt: Vec<bool> = train.iter().map(|&i| labels[i]).collect();
    let model = svm.fit(xt.view(), &yt).map_err(StabilityError::svm)?;
    let truth: Vec<bool> = test.iter().map(|&i| labels[i]).collect();
    let pred: Vec<bool> = test.iter().map(|&i| model.predict(test_x.row(i))).collect();
    Ok(Confusion::from_predictions(&truth, &pred))
}

/// Keep `train` grasps so that failures make `share` of them (every success kept; at least
/// one failure); unchanged when failures are already that rare.
pub(super) fn imbalance_train(
    train: &[usize],
    labels: &[bool],
    share: f64,
    rng: &mut Rng,
) -> Vec<usize> {
    let (mut fail, succ): (Vec<usize>, Vec<usize>) = train.iter().partition(|&&i| labels[i]);
    let want = if share >= 1.0 {
        fail.len()
    } else {
        ((share / (1.0 - share) * succ.len() as f64).round() as usize).max(1)
    };
    if want < fail.len() {
        rng.shuffle(&mut fail);
        fail.truncate(want);
    }
    let mut out: Vec<usize> = succ.into_iter().chain(fail).collect();
    out.sort_unstable();
    out
}

/// At most `n` grasps of each class of `train`, chosen at random.
pub(super) fn few_train(train: &[usize], classes: &[usize], n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut order = train.to_vec();
    rng.shuffle(&mut order);
    let mut count = std::collections::BTreeMap::<usize, usize>::new();
    let mut out: Vec<usize> = order
        .into_iter()
        .filter(|&i| {
            let c = count.entry(classes[i]).or_insert(0);
            *c += 1;
            *c <= n
        })
        .collect();
    out.sort_unstable();
    out
}

/// One stability repetition: the confusions of both pipelines pooled over its folds.
#[derive(Default)]
pub(super) struct StabilityRep {
    pub(super) sparse: Confusion,
    pub(super) raw: Confusion,
}

/// Sparse coding of the key-frame patches + linear SVM (the first paper).
pub(super) struct SparseSvm;

/// The linear SVM on the scaled raw key-frame values (the first paper's baseline).
pub(super) struct RawSvm;

impl StabilityMethod for SparseSvm {
    fn score(&self, r: &StabilityRep) -> f64 {
        r.sparse.weighted_success_rate().unwrap_or(0.0)
    }
}

impl StabilityMethod for RawSvm {
    fn score(&self, r: &StabilityRep) -> f64 {
        r.raw.weighted_success_rate().unwrap_or(0.0)
    }
}

pub(super) fn stability_task(
    params: &RobustnessParams,
    prep: &StabilityPrep,
    pert: Option<(Perturbation, f64)>,
    perturbed: Option<&Session>,
    rep: usize,
) -> Result<Vec<f64>, ExperimentError> {
    let st = &params.stability;
    let gamma = st.config.gamma;
    let labels = &prep.data.labels;
    let rep_seed = Rng::stream(params.seed, rep as u64).next_u64();
    let mut rng = Rng::stream(params.seed, PROTOCOL_STREAM + rep as u64);
    // (train features, test features) of both methods.
    let owned;
    let (train_sparse, train_raw, test_sparse, test_raw) = match (pert, perturbed) {
        (Some((p, _)), Some(ps)) if p.scope() == Scope::All => {
            // The sensor is noisy all along: the session's scaling and dictionary are
            // learned on what it recorded.
            let data = StabilityData::from_session(ps, &st.data)?;
            // A task's own progress: cancellation is checked between tasks (each well
            // under a second), and the run's progress counts tasks, not iterations.
            let dict = learn_dictionary(&data, st, &Progress::new())?;
            owned = [stability_features(&data, &dict, gamma)?];
            (&owned[0].0, &owned[0].1, &owned[0].0, &owned[0].1)
        }
        (_, Some(ps)) => {
            owned = [stability_features_scaled_as(prep, ps, gamma)?];
            (&prep.sparse, &prep.raw, &owned[0].0, &owned[0].1)
        }
        _ => (&prep.sparse, &prep.raw, &prep.sparse, &prep.raw),
    };
    let mut pooled = StabilityRep::default();
    let mut add = |train: &[usize], test: &[usize]| -> Result<(), ExperimentError> {
        let c0 = svm_confusion(
            train_sparse,
            test_sparse,
            labels,
            train,
            test,
            &st.settings.svm,
        )?;
        let c1 = svm_confusion(train_raw, test_raw, labels, train, test, &st.settings.svm)?;
        pooled.sparse.add(&c0);
        pooled.raw.add(&c1);
        Ok(())
    };
    if let Some((Perturbation::NewObjects, share)) = pert {
        let (train, test) = hold_out_objects(&prep.data, share, &mut rng)?;
        add(&train, &test)?;
    } else {
        let folds = stratified_k_fold(labels, st.folds, rep_seed).map_err(StabilityError::svm)?;
        let classes: Vec<usize> = labels.iter().map(|&l| l as usize).collect();
        for f in 0..folds.count {
            let mut train = folds.train_indices(f);
            match pert {
                Some((Perturbation::Imbalance, share)) => {
                    train = imbalance_train(&train, labels, share, &mut rng);
                }
                Some((Perturbation::FewExamples, n)) => {
                    train = few_train(&train, &classes, n as usize, &mut rng);
                }
                _ => {}
            }
            add(&train, &folds.test_indices(f))?;
        }
    }
    (params.methods.iter())
        .map(|&m| Ok(stability_method(m)?.score(&pooled)))
        .collect()
}

/// Hold out round(share · objects) objects (at least one, and at least one left to learn
/// from), drawn until the held-out grasps hold both outcomes.
pub(super) fn hold_out_objects(
    data: &StabilityData,
    share: f64,
    rng: &mut Rng,
) -> Result<(Vec<usize>, Vec<usize>), ExperimentError> {
    let n_obj = data.object_names.len();
    if n_obj < 2 {
        return Err(ExperimentError::Data(
            "new-objects needs at least two objects".into(),
        ));
    }
    let n_held = ((share * n_obj as f64).round() as usize).clamp(1, n_obj - 1);
    for _ in 0..1000 {
        let perm = rng.permutation(n_obj);
        let mut held = vec![false; n_obj];
        for &o in &perm[..n_held] {
            held[o] = true;
        }
        let (test, train): (Vec<usize>, Vec<usize>) =
            (0..data.grasp_count()).partition(|&g| held[data.objects[g]]);
        let both = |idx: &[usize]| {
            idx.iter().any(|&g| data.labels[g]) && idx.iter().any(|&g| !data.labels[g])
        };
        if both(&test) && both(&train) {
            return Ok((train, test));
        }
    }
    Err(ExperimentError::Data(format!(
        "no draw of {n_held} held-out objects gives both outcomes on each side"
    )))
}
