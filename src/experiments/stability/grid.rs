//! The grid search over (num_bases, beta, gamma) and its parsimonious choice.

use super::*;

/// The grid: every combination of the three lists.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridSpec {
    pub num_bases: Vec<usize>,
    pub beta: Vec<f64>,
    pub gamma: Vec<f64>,
}

impl GridSpec {
    /// The default: num_bases 2..=60 and log grids of beta and gamma suited to
    /// z-scored patches (0.25 to 4, factor 2); on raw pressures the penalties scale with
    /// the squared patch norm, so the grids are multiplied by the mean patch energy per
    /// taxel (which is 1 for z-scored data).
    pub fn default_for(data: &StabilityData) -> Self {
        let energy = data.x.iter().map(|v| v * v).sum::<f64>() / data.x.len().max(1) as f64;
        let scale = if data.patches.scaling == PatchScaling::None {
            energy.max(1e-12)
        } else {
            1.0
        };
        let log = [0.25, 0.5, 1.0, 2.0, 4.0]
            .iter()
            .map(|v| v * scale)
            .collect::<Vec<_>>();
        GridSpec {
            num_bases: (2..=60).collect(),
            beta: log.clone(),
            gamma: log,
        }
    }

    /// The benchmark grid: num_bases 5..=60 step 5 × beta, gamma ∈ {0.5, 1, 2} (108 cells).
    pub fn bench() -> Self {
        GridSpec {
            num_bases: (1..=12).map(|i| 5 * i).collect(),
            beta: vec![0.5, 1.0, 2.0],
            gamma: vec![0.5, 1.0, 2.0],
        }
    }

    pub fn cells(&self) -> usize {
        self.num_bases.len() * self.beta.len() * self.gamma.len()
    }

    pub fn validate(&self) -> Result<(), StabilityError> {
        if self.cells() == 0 {
            return Err(StabilityError::param("the grid is empty".into()));
        }
        if self.num_bases.contains(&0) {
            return Err(StabilityError::param("num_bases must be ≥ 1".into()));
        }
        for (name, v) in [("beta", &self.beta), ("gamma", &self.gamma)] {
            if let Some(b) = v.iter().find(|b| !(**b > 0.0 && b.is_finite())) {
                return Err(StabilityError::param(format!(
                    "{name} must be finite and > 0, got {b}"
                )));
            }
        }
        Ok(())
    }
}

/// Grid search results.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridResult {
    pub spec: GridSpec,
    pub cv: CvScheme,
    /// Every cell, ordered by num_bases, then beta, then gamma.
    pub cells: Vec<CellResult>,
    /// For each num_bases (ascending), its best cell: the paper's Fig. 5.
    pub best_per_num_bases: Vec<CellResult>,
    /// The cell with the highest weighted success rate (ties: fewer bases first).
    pub best: CellResult,
    /// The smallest num_bases whose best score is within one standard error (of the
    /// best cell's per-fold scores) of the best: the recommended model.
    pub parsimonious: CellResult,
    pub best_dictionary: Dictionary,
    pub parsimonious_dictionary: Dictionary,
    pub secs: f64,
    pub threads: usize,
}

/// One task of the grid: a (num_bases, beta) dictionary, its gamma values coded and
/// cross-validated in turn. The unit of parallel work here and of a sharded sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridTask {
    pub num_bases: usize,
    pub beta: f64,
}

/// What a grid task leaves: its cells (in gamma order) and its dictionary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridTaskOutput {
    pub cells: Vec<CellResult>,
    pub dictionary: Dictionary,
}

impl GridSpec {
    /// The grid's tasks in grid order (num_bases, then beta).
    pub fn tasks(&self) -> Vec<GridTask> {
        self.num_bases
            .iter()
            .flat_map(|&num_bases| {
                self.beta
                    .iter()
                    .map(move |&beta| GridTask { num_bases, beta })
            })
            .collect()
    }
}

/// Check the grid and the settings, and make the folds of the selection protocol.
pub fn grid_folds(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    cv: CvScheme,
) -> Result<Folds, StabilityError> {
    spec.validate()?;
    settings
        .dictionary
        .validate()
        .map_err(StabilityError::sparse)?;
    settings.svm.validate().map_err(StabilityError::svm)?;
    cv.folds(data, settings.cv_seed)
}

/// Learn the task's dictionary and score it with every gamma on `folds`; `on_cell` is told
/// of each finished cell. Depends on nothing but its arguments (every seed is in
/// `settings`), so any machine computes the same task alike.
pub fn grid_task(
    data: &StabilityData,
    gamma: &[f64],
    folds: &Folds,
    settings: &PipelineSettings,
    task: GridTask,
    progress: &Progress,
    on_cell: &(dyn Fn(&CellResult) + Sync),
) -> Result<GridTaskOutput, StabilityError> {
    progress.checkpoint()?;
    let GridTask { num_bases, beta } = task;
    let params = DictionaryParams {
        num_bases,
        beta,
        ..settings.dictionary.clone()
    };
    let fit = params
        .fit_within(data.x.view(), progress)
        .map_err(StabilityError::sparse)?;
    let mut cells = Vec::with_capacity(gamma.len());
    for &gamma in gamma {
        progress.checkpoint()?;
        let ScoredCodes {
            sparsity: (sparsity, active),
            cv: cvr,
            coding_secs,
            cv_secs,
            ..
        } = score_codes(data, &fit.dictionary, gamma, folds, settings)?;
        let cell = CellResult {
            config: Config {
                num_bases,
                beta,
                gamma,
            },
            weighted_success_rate: cvr.weighted_success_rate,
            failure_recall: cvr.failure_recall,
            fold_wsr_mean: cvr.fold_wsr_mean,
            fold_wsr_se: cvr.fold_wsr_se,
            sparsity,
            active_bases_per_patch: active,
            dictionary_objective: fit.objective,
            dictionary_iterations: fit.iterations,
            dictionary_secs: fit.secs,
            coding_secs,
            cv_secs,
        };
        on_cell(&cell);
        cells.push(cell);
    }
    Ok(GridTaskOutput {
        cells,
        dictionary: fit.dictionary,
    })
}

/// The grid's result from the outputs of its tasks (in the order of `tasks`).
pub fn assemble_grid(
    spec: &GridSpec,
    cv: CvScheme,
    tasks: &[GridTask],
    outputs: Vec<GridTaskOutput>,
    secs: f64,
    threads: usize,
) -> GridResult {
    let mut cells = Vec::with_capacity(spec.cells());
    let mut dicts = Vec::with_capacity(tasks.len());
    for out in outputs {
        cells.extend(out.cells);
        dicts.push(out.dictionary);
    }
    let dict_of = |cell: &CellResult| -> Dictionary {
        let i = tasks
            .iter()
            .position(|t| t.num_bases == cell.config.num_bases && t.beta == cell.config.beta)
            .expect("every cell comes from a task");
        dicts[i].clone()
    };
    let (best_per_num_bases, best, parsimonious) = choose(&cells, &spec.num_bases);
    GridResult {
        spec: spec.clone(),
        cv,
        best_dictionary: dict_of(&best),
        parsimonious_dictionary: dict_of(&parsimonious),
        cells,
        best_per_num_bases,
        best,
        parsimonious,
        secs,
        threads,
    }
}

/// Run the grid in parallel (rayon: one [`GridTask`] per (num_bases, beta) dictionary; the
/// folds of each cross validation run in parallel too). Cancellable between dictionaries
/// and learning iterations; `progress` gets the fraction of cells done. The same seeds
/// give the same numbers whatever the thread count.
pub fn grid_search(
    data: &StabilityData,
    spec: &GridSpec,
    settings: &PipelineSettings,
    cv: CvScheme,
    progress: &Progress,
) -> Result<GridResult, StabilityError> {
    let folds = grid_folds(data, spec, settings, cv)?;
    let start = Instant::now();
    let tasks = spec.tasks();
    let total = spec.cells();
    let done = AtomicUsize::new(0);
    progress.set(0.0, format!("grid search: {total} configurations"));
    let on_cell = |c: &CellResult| {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress.set(
            n as f64 / total as f64,
            format!("grid search: {n}/{total} ({})", c.config),
        );
    };
    let outputs = tasks
        .par_iter()
        .map(|&t| grid_task(data, &spec.gamma, &folds, settings, t, progress, &on_cell))
        .collect::<Result<Vec<_>, _>>()?;
    // Workers report out of order; the last word is the whole grid.
    progress.set(
        1.0,
        format!("grid search: {total}/{total} configurations done"),
    );
    Ok(assemble_grid(
        spec,
        cv,
        &tasks,
        outputs,
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads(),
    ))
}

/// Best cell per num_bases, the best overall (ties: fewer bases, then grid order) and the
/// parsimonious choice: the smallest num_bases whose best score ≥ best − SE(best).
pub fn choose(
    cells: &[CellResult],
    num_bases: &[usize],
) -> (Vec<CellResult>, CellResult, CellResult) {
    let mut ks: Vec<usize> = num_bases.to_vec();
    ks.sort_unstable();
    ks.dedup();
    let better = |a: &CellResult, b: &CellResult| a.weighted_success_rate > b.weighted_success_rate;
    let per_k: Vec<CellResult> = ks
        .iter()
        .filter_map(|&k| {
            cells.iter().filter(|c| c.config.num_bases == k).fold(
                None,
                |acc: Option<&CellResult>, c| match acc {
                    Some(a) if !better(c, a) => Some(a),
                    _ => Some(c),
                },
            )
        })
        .cloned()
        .collect();
    let best = per_k
        .iter()
        .fold(None, |acc: Option<&CellResult>, c| match acc {
            Some(a) if !better(c, a) => Some(a),
            _ => Some(c),
        })
        .cloned()
        .expect("a non-empty grid");
    let bar = best.weighted_success_rate - best.fold_wsr_se.max(0.0);
    let parsimonious = per_k
        .iter()
        .find(|c| c.weighted_success_rate >= bar)
        .cloned()
        .unwrap_or_else(|| best.clone());
    (per_k, best, parsimonious)
}
