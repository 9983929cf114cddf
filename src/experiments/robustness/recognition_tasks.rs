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

/// One repetition of the recognition protocol under one perturbation (or none): what
/// every method of the task reads.
pub(super) struct RecognitionRep<'a> {
    pub(super) params: &'a RobustnessParams,
    pub(super) prep: &'a RecognitionPrep,
    pub(super) pert: Option<(Perturbation, f64)>,
    pub(super) rep: usize,
    /// The sequences learned from and those tested on: perturbed where the perturbation
    /// reaches, else the clean ones.
    pub(super) train_seqs: &'a FeatureSequences,
    pub(super) test_seqs: &'a FeatureSequences,
    /// Table I features (training rows, test rows), when a method reads them.
    pub(super) table: Option<TrainTest>,
    /// The supervised protocol: one grasp per class taught, then `order`, whose first
    /// `n_train` grasps are the training part, of which those `keep` marks are learned.
    pub(super) teach: Vec<usize>,
    pub(super) order: Vec<usize>,
    pub(super) n_train: usize,
    pub(super) keep: Vec<bool>,
    /// The grasps the unsupervised methods learn from, their labels and (when needed)
    /// their sequences.
    pub(super) subset: Vec<usize>,
    pub(super) sub_labels: Vec<usize>,
    pub(super) sub_seqs: Vec<Array2<f64>>,
    /// The clusters k-means and the SOM are given, and their seed.
    pub(super) k: usize,
    pub(super) cluster_seed: u64,
}

impl RecognitionRep<'_> {
    pub(super) fn table(&self) -> Result<&TrainTest, ExperimentError> {
        (self.table.as_ref()).ok_or_else(|| ExperimentError::Data("no Table I features".into()))
    }
}

pub(super) fn recognition_task(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    pert: Option<(Perturbation, f64)>,
    perturbed: Option<&Session>,
    rep: usize,
) -> Result<Vec<f64>, ExperimentError> {
    let rc = &params.recognition;
    let needs = Needs::of(&params.methods);
    let scope = pert.map(|(p, _)| p.scope());
    let feats = perturbed_sequences(params, prep, needs, scope, perturbed)?;
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
    // The subset's sequences, copied once for the methods that learn from them.
    let sub_seqs: Vec<Array2<f64>> = if needs.subset_sequences {
        subset
            .iter()
            .map(|&g| test_seqs.sequences[g].clone())
            .collect()
    } else {
        Vec::new()
    };
    let ctx = RecognitionRep {
        params,
        prep,
        pert,
        rep,
        train_seqs,
        test_seqs,
        table,
        teach,
        order,
        n_train,
        keep,
        subset,
        sub_labels,
        sub_seqs,
        k: rc.clusters.unwrap_or(prep.n_classes),
        cluster_seed: Rng::stream(params.seed, CLUSTER_STREAM + rep as u64).next_u64(),
    };
    (params.methods.iter())
        .map(|&m| recognition_method(m)?.score(&ctx))
        .collect()
}

/// The perturbed session's feature sequences when a sequence method needs them: normalised
/// on themselves when the perturbation is there all along, else in the clean session's
/// normalisation. None without a perturbed session or a sequence method.
fn perturbed_sequences(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    needs: Needs,
    scope: Option<Scope>,
    perturbed: Option<&Session>,
) -> Result<Option<FeatureSequences>, ExperimentError> {
    Ok(match perturbed {
        Some(ps) if needs.sequences => {
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
pub(super) type TrainTest = (Array2<f64>, Array2<f64>);

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
