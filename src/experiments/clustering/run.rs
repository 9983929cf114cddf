//! A clustering run as items a sweep can spread over machines (one presentation order
//! under every threshold, or one seeded run of the baselines), their assembly into a
//! result, and the run on this machine.

use super::*;

/// A unit of a clustering run: one presentation order learned under every threshold (see
/// [`order_runs`]) or one seeded run of the k-means and SOM baselines with `k` centres /
/// units. Its seeds follow from the run's seed and the item, so any machine computes it
/// alike.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClusteringItem {
    Order { rep: usize },
    Baseline { k: usize, rep: usize },
}

/// What an item leaves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClusteringOutput {
    /// One run per threshold, in the thresholds' order.
    Order {
        runs: Vec<ClusteringRun>,
    },
    Baseline {
        kmeans: Scored,
        som: Scored,
    },
}

/// What every item shares: the labels, the feature sequences, the baselines' z-scored
/// Table I features (None without baselines) and DU's pair table of the inputs.
pub struct ClusteringPrep {
    pub labels: Vec<usize>,
    pub class_names: Vec<String>,
    pub feats: FeatureSequences,
    pub table: Option<Array2<f64>>,
    /// The distances between the sequences' inputs and the kernel between their windows
    /// under DU's initial hyperparameters: every order learns and re-assigns the same
    /// grasps, so the experts read them here until they adapt (None for GU, or past
    /// [`crate::gp::MAX_PAIR_INPUTS`] inputs; no window kernels past as many windows).
    pub pairs: Option<Arc<PairDistances>>,
}

/// Check the parameters and prepare what every item shares.
pub fn prepare_clustering(
    session: &Session,
    params: &ClusteringParams,
) -> Result<ClusteringPrep, ExperimentError> {
    params.validate()?;
    let (labels, class_names) = session_labels(session, &params.label_set)?;
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features: params.features,
            taxel_noise_variance: 0.0,
            seed: params.seed,
        },
    )?;
    // Fail early on parameters the learners reject.
    Gs::new(feats.dim(), &params.gs)?;
    let table = if params.baseline_max_k >= 2 {
        let raw = session_features(session)?;
        Some(
            Normaliser::fit(Normalisation::ZScore, raw.view())
                .and_then(|n| n.transform(raw.view()))?,
        )
    } else {
        None
    };
    let pairs = match params.learner {
        UnsupervisedLearner::Du => du_pairs(&feats, &params.ds)?,
        UnsupervisedLearner::Gu => None,
    };
    Ok(ClusteringPrep {
        labels,
        class_names,
        feats,
        table,
        pairs,
    })
}

/// The pair table of the sequences' inputs and windows under the hyperparameters DU's
/// experts start with (None past [`crate::gp::MAX_PAIR_INPUTS`] inputs; no window kernels
/// past as many windows).
fn du_pairs(
    feats: &FeatureSequences,
    ds: &DsParams,
) -> Result<Option<Arc<PairDistances>>, ExperimentError> {
    let kernel = Sogp::new(feats.dim(), 1, &ds.gp)
        .map_err(crate::learners::LearnerError::from)?
        .kernel()
        .clone();
    let seqs: Vec<_> = feats
        .sequences
        .iter()
        .map(|s| s.as_standard_layout())
        .collect();
    let steps = seqs.iter().filter_map(|s| s.as_slice());
    Ok(PairDistances::new(&kernel, steps).map(Arc::new))
}

/// What an item costs, relative to the others of its run on a session of `steps` steps
/// and `grasps` grasps: an order learns every step under every threshold; a baseline's
/// sequential k-means and SOM pass once over the grasps' Table I features per centre, ten
/// times cheaper a grasp than a step of the experts.
pub fn item_cost(
    params: &ClusteringParams,
    steps: usize,
    grasps: usize,
    item: ClusteringItem,
) -> f64 {
    match item {
        ClusteringItem::Order { .. } => (steps * params.thresholds.len()) as f64,
        ClusteringItem::Baseline { k, .. } => 0.1 * (grasps * k) as f64,
    }
}

/// The items of a run on `grasps` grasps: every order, then every (k, order) of the
/// baselines.
pub fn clustering_items(params: &ClusteringParams, grasps: usize) -> Vec<ClusteringItem> {
    let mut items: Vec<ClusteringItem> = (0..params.reps)
        .map(|rep| ClusteringItem::Order { rep })
        .collect();
    if params.baseline_max_k >= 2 {
        items
            .extend((2..=params.baseline_max_k.min(grasps)).flat_map(|k| {
                (0..params.reps).map(move |rep| ClusteringItem::Baseline { k, rep })
            }));
    }
    items
}

/// Compute one item.
pub fn clustering_item(
    params: &ClusteringParams,
    prep: &ClusteringPrep,
    item: ClusteringItem,
    progress: &Progress,
) -> Result<ClusteringOutput, ExperimentError> {
    match item {
        ClusteringItem::Order { rep } => Ok(ClusteringOutput::Order {
            runs: order_runs(
                params,
                &prep.feats.sequences,
                &prep.labels,
                prep.feats.dim(),
                &params.thresholds,
                rep,
                prep.pairs.as_ref(),
                progress,
            )?,
        }),
        ClusteringItem::Baseline { k, rep } => {
            let data = prep.table.as_ref().ok_or_else(|| {
                ExperimentError::param("baseline_max_k", "the baselines are switched off")
            })?;
            let seed = baseline_seed(params.seed, k, rep);
            let km = SequentialKMeansParams { k, passes: 1, seed }
                .fit(data.view())
                .and_then(|m| m.assign(data.view()))?;
            let som = som_setup(k, seed)
                .fit(data.view())
                .and_then(|m| m.assign(data.view()))?;
            let (a, b) = (scores(&prep.labels, &km), scores(&prep.labels, &som));
            Ok(ClusteringOutput::Baseline {
                kmeans: (distinct(&km), a.purity, a.ari, a.nmi),
                som: (distinct(&som), b.purity, b.ari, b.nmi),
            })
        }
    }
}

/// The sweep's summaries, the effective-cluster curves and Table IV from the items'
/// outputs (in item order).
pub fn assemble_clustering(
    params: &ClusteringParams,
    prep: ClusteringPrep,
    outputs: Vec<ClusteringOutput>,
    wall_seconds: f64,
) -> ClusteringResult {
    let mut orders = Vec::new();
    let mut base: Vec<(Scored, Scored)> = Vec::new();
    for o in outputs {
        match o {
            ClusteringOutput::Order { runs } => orders.push(runs.into_iter()),
            ClusteringOutput::Baseline { kmeans, som } => base.push((kmeans, som)),
        }
    }
    // Threshold by threshold, each in order of the orders.
    let mut runs = Vec::new();
    for _ in &params.thresholds {
        runs.extend(orders.iter_mut().filter_map(Iterator::next));
    }
    let sweep = params
        .thresholds
        .iter()
        .map(|&t| {
            let rs: Vec<&ClusteringRun> = runs.iter().filter(|r| r.threshold == t).collect();
            ThresholdSummary {
                threshold: t,
                clusters: MeanSd::of(rs.iter().map(|r| r.clusters as f64)),
                effective: MeanSd::of(rs.iter().map(|r| r.effective as f64)),
                purity: MeanSd::of(rs.iter().map(|r| r.purity)),
                ari: MeanSd::of(rs.iter().map(|r| r.ari)),
                nmi: MeanSd::of(rs.iter().map(|r| r.nmi)),
            }
        })
        .collect();
    let threshold_choice = params
        .choose_threshold
        .and_then(|c| label_free_choice(c, &params.thresholds, &runs));
    for r in runs.iter_mut().filter(|r| r.rep != 0) {
        r.assignment = None;
    }
    let by_eff = by_effective(runs.iter().map(|r| (r.effective, r.purity, r.ari, r.nmi)));
    let kmeans = by_effective(base.iter().map(|x| x.0));
    let som = by_effective(base.iter().map(|x| x.1));
    ClusteringResult {
        params: params.clone(),
        at_10: at(&by_eff, 10),
        kmeans_at_10: at(&kmeans, 10),
        som_at_10: at(&som, 10),
        runs,
        sweep,
        by_effective: by_eff,
        kmeans,
        som,
        som_setup: som_setup(10, params.seed),
        wall_seconds,
        threshold_choice,
        labels: prep.labels,
        class_names: prep.class_names,
        features_used: Some(prep.feats.families),
        feature_choice: None,
    }
}

/// The threshold `criterion` chooses from the runs' clusterings (never their labels).
fn label_free_choice(
    criterion: ThresholdCriterion,
    thresholds: &[f64],
    runs: &[ClusteringRun],
) -> Option<ThresholdChoice> {
    let per_threshold: Vec<(f64, Vec<&[usize]>)> = thresholds
        .iter()
        .map(|&t| {
            let c = runs
                .iter()
                .filter(|r| r.threshold == t)
                .filter_map(|r| r.assignment.as_deref())
                .collect();
            (t, c)
        })
        .collect();
    choose_threshold(criterion, &per_threshold)
}

impl ClusteringResult {
    /// The sweep's summary at the label-free threshold.
    pub fn at_choice(&self) -> Option<&ThresholdSummary> {
        let t = self.threshold_choice.as_ref()?.threshold;
        self.sweep.iter().find(|s| s.threshold == t)
    }

    /// The threshold with the best mean NMI, chosen with the labels: the yardstick of the
    /// label-free choice, not a choice a user without labels could make.
    pub fn best_by_labels(&self) -> Option<&ThresholdSummary> {
        self.sweep
            .iter()
            .fold(None, |best: Option<&ThresholdSummary>, s| match best {
                Some(b) if b.nmi.mean >= s.nmi.mean => Some(b),
                _ => Some(s),
            })
    }
}

pub fn run_clustering(
    session: &Session,
    params: &ClusteringParams,
    progress: &Progress,
) -> Result<ClusteringResult, ExperimentError> {
    let start = Instant::now();
    let items = clustering_items(params, session.grasps.len());
    let steps = session.total_frames();
    let grasps = session.grasps.len();
    // Choosing the inputs costs about AUTO_REPETITIONS repetitions of the supervised
    // protocol, each about as much as learning a step under 1.5 thresholds.
    let auto = match params.features.is_auto() {
        true => crate::experiments::recognition::AUTO_REPETITIONS * 1.5 * steps as f64,
        false => 0.0,
    };
    let work: f64 = (items.iter())
        .map(|&item| item_cost(params, steps, grasps, item))
        .sum();
    let parts = progress.parts(&[auto, work]);
    let (params, feature_choice) = choose_auto_features(session, params, &parts[0])?;
    let params = &params;
    let prep = prepare_clustering(session, params)?;
    let progress = &parts[1];
    progress.set(0.0, "clustering: starting");
    let outputs = compute_items(
        &items,
        progress,
        "clustering",
        "items",
        |&item| item_cost(params, steps, grasps, item),
        |&item, part| clustering_item(params, &prep, item, part),
    )?;
    Ok(ClusteringResult {
        feature_choice,
        ..assemble_clustering(params, prep, outputs, start.elapsed().as_secs_f64())
    })
}

/// `params` with `auto` replaced by the family chosen by cross validation of the experts
/// the learner is built from (DU: DS's, GU: GS's; see `feature_choice`), or as they are.
pub fn choose_auto_features(
    session: &Session,
    params: &ClusteringParams,
    progress: &Progress,
) -> Result<(ClusteringParams, Option<FeatureChoice>), ExperimentError> {
    if !params.features.is_auto() {
        return Ok((params.clone(), None));
    }
    progress.set(0.0, "auto features: cross validation");
    let learner = match params.learner {
        UnsupervisedLearner::Du => SupervisedLearner::Ds,
        UnsupervisedLearner::Gu => SupervisedLearner::Gs,
    };
    let scorer = ExpertsScorer {
        learner,
        ds: &params.ds,
        gs: &params.gs,
    };
    let choice = choose_features(
        session,
        &scorer,
        &params.label_set,
        AUTO_FOLDS,
        params.seed,
        progress,
    )?;
    let chosen = ClusteringParams {
        features: choice.chosen,
        ..params.clone()
    };
    Ok((chosen, Some(choice)))
}
