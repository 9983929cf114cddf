//! Nested cross validation of the grid's selection.

use super::*;

/// One outer fold of a nested cross validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NestedFold {
    pub fold: usize,
    pub train: usize,
    pub test: usize,
    /// The configuration the one-standard-error rule chose from the inner cross validation
    /// on the outer training grasps, and its inner weighted success rate.
    pub chosen: Config,
    pub chosen_inner_wsr: f64,
    /// The inner grid's highest-scoring configuration and its inner score.
    pub best: Config,
    pub best_inner_wsr: f64,
    /// The chosen model, trained on the outer training grasps, on the outer test grasps.
    pub confusion: Confusion,
    pub weighted_success_rate: Option<f64>,
    /// The raw linear SVM on the same split.
    pub raw_confusion: Confusion,
    pub raw_weighted_success_rate: Option<f64>,
}

/// Nested cross validation: the outer folds score, the grid search with its
/// one-standard-error rule runs inside every outer training fold (inner folds of the same
/// protocol), so no selection sees the labels of the grasps it is scored on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NestedResult {
    /// The protocol of the outer and the inner folds.
    pub protocol: CvScheme,
    pub description: String,
    pub folds: Vec<NestedFold>,
    /// Pooled over the outer test folds (every grasp tested once), and the per-fold mean
    /// and standard error over the folds holding both classes.
    pub weighted_success_rate: f64,
    pub failure_recall: f64,
    pub fold_wsr_mean: f64,
    pub fold_wsr_se: f64,
    /// The raw linear SVM under the same outer folds.
    pub raw_weighted_success_rate: f64,
    pub raw_failure_recall: f64,
    pub secs: f64,
}

/// Nested cross validation of the grid search under `protocol` (outer folds from the
/// settings' seed).
pub fn nested_cv(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    protocol: CvScheme,
    progress: &Progress,
) -> Result<NestedResult, StabilityError> {
    let outer = protocol.folds(data, settings.cv_seed)?;
    nested_cv_on(data, spec, settings, protocol, &outer, progress)
}

/// Inner folds of `protocol` over the grasps `train` (indices into `data`).
pub(super) fn inner_folds(
    data: &StabilityData,
    train: &[usize],
    protocol: CvScheme,
    seed: u64,
) -> Result<Folds, StabilityError> {
    Ok(match protocol {
        CvScheme::KFold { k } => {
            let y: Vec<bool> = train.iter().map(|&g| data.labels[g]).collect();
            stratified_k_fold(&y, k, seed).map_err(StabilityError::svm)?
        }
        CvScheme::LeaveObjectsOut { folds } => {
            let objects: Vec<usize> = train.iter().map(|&g| data.objects[g]).collect();
            group_k_fold(&objects, folds, seed).map_err(StabilityError::svm)?
        }
    })
}

/// Every cell's inner scores and outer-test predictions for one outer fold.
pub(super) struct NestedCell {
    pub(super) config: Config,
    pub(super) inner: CvResult,
    pub(super) test_predictions: Vec<bool>,
}

/// [`nested_cv`] with given outer folds. Dictionaries are learned once per (num_bases,
/// beta) on all patches without labels, as in the grid search; every label the selection
/// uses comes from the outer training grasps.
pub fn nested_cv_on(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    protocol: CvScheme,
    outer: &Folds,
    progress: &Progress,
) -> Result<NestedResult, StabilityError> {
    spec.validate()?;
    settings
        .dictionary
        .validate()
        .map_err(StabilityError::sparse)?;
    settings.svm.validate().map_err(StabilityError::svm)?;
    if outer.fold_of.len() != data.grasp_count() {
        return Err(StabilityError::data(format!(
            "{} outer fold assignments for {} grasps",
            outer.fold_of.len(),
            data.grasp_count()
        )));
    }
    let start = Instant::now();
    let splits: Vec<OuterSplit> = (0..outer.count)
        .map(|f| {
            let train = outer.train_indices(f);
            let inner = inner_folds(data, &train, protocol, settings.cv_seed)?;
            Ok((train, outer.test_indices(f), inner))
        })
        .collect::<Result<_, StabilityError>>()?;
    let cells = nested_cells(data, spec, settings, protocol, &splits, progress)?;
    let raw = cross_validate(data.images().view(), &data.labels, outer, &settings.svm)
        .map_err(StabilityError::svm)?;
    let mut pooled = Confusion::default();
    let mut folds = Vec::with_capacity(splits.len());
    for (f, split) in splits.iter().enumerate() {
        let fold = outer_fold(data, spec, &cells, &raw, f, split);
        pooled.add(&fold.confusion);
        folds.push(fold);
    }
    let per_fold: Vec<f64> = folds
        .iter()
        .filter_map(|f| f.weighted_success_rate)
        .collect();
    let (fold_wsr_mean, fold_wsr_se) = crate::svm::mean_se(&per_fold);
    Ok(NestedResult {
        protocol,
        description: format!(
            "nested: outer {}, grid and one-SE rule on inner {} of each outer training fold",
            protocol.describe(),
            protocol.describe()
        ),
        folds,
        weighted_success_rate: pooled.weighted_success_rate().unwrap_or(f64::NAN),
        failure_recall: pooled.failure_recall().unwrap_or(f64::NAN),
        fold_wsr_mean,
        fold_wsr_se,
        raw_weighted_success_rate: raw.weighted_success_rate,
        raw_failure_recall: raw.failure_recall,
        secs: start.elapsed().as_secs_f64(),
    })
}

/// One outer fold: its training grasps, its test grasps and the inner folds over the
/// training grasps.
type OuterSplit = (Vec<usize>, Vec<usize>, Folds);

/// Every grid cell on every outer fold, as `cells[cell][outer fold]` (cells in the grid's
/// order: num_bases, then beta, then gamma), one dictionary per (num_bases, beta) in
/// parallel.
fn nested_cells(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    protocol: CvScheme,
    splits: &[OuterSplit],
    progress: &Progress,
) -> Result<Vec<Vec<NestedCell>>, StabilityError> {
    let tasks: Vec<(usize, f64)> = spec
        .num_bases
        .iter()
        .flat_map(|&k| spec.beta.iter().map(move |&b| (k, b)))
        .collect();
    let done = AtomicUsize::new(0);
    let total = spec.cells();
    progress.set(
        0.0,
        format!("nested {}: {total} configurations", protocol.describe()),
    );
    // cells[task][gamma][outer fold]
    let cells: Vec<Vec<Vec<NestedCell>>> = tasks
        .par_iter()
        .map(|&(k, beta)| {
            progress.checkpoint()?;
            let fit = DictionaryParams {
                num_bases: k,
                beta,
                ..settings.dictionary.clone()
            }
            .fit_within(data.x.view(), progress)
            .map_err(StabilityError::sparse)?;
            let mut per_gamma = Vec::with_capacity(spec.gamma.len());
            for &gamma in &spec.gamma {
                progress.checkpoint()?;
                let codes = fit
                    .dictionary
                    .encode(data.x.view(), gamma)
                    .map_err(StabilityError::sparse)?;
                let features = data.features(codes, settings.inputs);
                let config = Config {
                    num_bases: k,
                    beta,
                    gamma,
                };
                per_gamma.push(cell_on_splits(data, &features, config, settings, splits)?);
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress.set(
                    n as f64 / total as f64,
                    format!("nested {}: {n}/{total}", protocol.describe()),
                );
            }
            Ok(per_gamma)
        })
        .collect::<Result<_, StabilityError>>()?;
    Ok(cells.into_iter().flatten().collect())
}

/// One cell on every outer fold: its inner cross validation on the outer training grasps,
/// and the SVM trained on them predicting the outer test grasps.
fn cell_on_splits(
    data: &StabilityData,
    features: &Array2<f64>,
    config: Config,
    settings: &PipelineSettings,
    splits: &[OuterSplit],
) -> Result<Vec<NestedCell>, StabilityError> {
    let mut per_fold = Vec::with_capacity(splits.len());
    for (train, test, inner) in splits {
        let xt = crate::svm::gather(features.view(), train);
        let yt: Vec<bool> = train.iter().map(|&g| data.labels[g]).collect();
        let cv =
            cross_validate(xt.view(), &yt, inner, &settings.svm).map_err(StabilityError::svm)?;
        let model = settings
            .svm
            .fit(xt.view(), &yt)
            .map_err(StabilityError::svm)?;
        per_fold.push(NestedCell {
            config,
            inner: cv,
            test_predictions: test
                .iter()
                .map(|&g| model.predict(features.row(g)))
                .collect(),
        });
    }
    Ok(per_fold)
}

/// Outer fold `f`: the one-standard-error rule's choice from the inner scores, scored on
/// the outer test grasps beside the raw SVM's score on the same fold.
fn outer_fold(
    data: &StabilityData,
    spec: &GridSpec,
    cells: &[Vec<NestedCell>],
    raw: &CvResult,
    f: usize,
    (train, test, _): &OuterSplit,
) -> NestedFold {
    let inner: Vec<CellResult> = cells
        .iter()
        .map(|c| {
            let cv = &c[f].inner;
            CellResult {
                config: c[f].config,
                weighted_success_rate: cv.weighted_success_rate,
                failure_recall: cv.failure_recall,
                fold_wsr_mean: cv.fold_wsr_mean,
                fold_wsr_se: cv.fold_wsr_se,
                sparsity: 0.0,
                active_bases_per_patch: 0.0,
                dictionary_objective: 0.0,
                dictionary_iterations: 0,
                dictionary_secs: 0.0,
                coding_secs: 0.0,
                cv_secs: 0.0,
            }
        })
        .collect();
    let (_, best, chosen) = choose(&inner, &spec.num_bases);
    let cell = cells
        .iter()
        .map(|c| &c[f])
        .find(|c| c.config == chosen.config)
        .expect("the choice is a cell");
    let truth: Vec<bool> = test.iter().map(|&g| data.labels[g]).collect();
    let confusion = Confusion::from_predictions(&truth, &cell.test_predictions);
    let raw_fold = raw
        .folds
        .iter()
        .find(|r| r.fold == f)
        .expect("one score per outer fold");
    NestedFold {
        fold: f,
        train: train.len(),
        test: test.len(),
        chosen: chosen.config,
        chosen_inner_wsr: chosen.weighted_success_rate,
        best: best.config,
        best_inner_wsr: best.weighted_success_rate,
        weighted_success_rate: confusion.weighted_success_rate(),
        confusion,
        raw_confusion: raw_fold.confusion,
        raw_weighted_success_rate: raw_fold.weighted_success_rate,
    }
}
