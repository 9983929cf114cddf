//! The run: preparing the clean data, one task per (perturbation, strength, repetition), and the assembly of curves and break points.

use super::*;

/// What every task of a run shares, prepared once per run (or once per shard of a sweep).
pub struct Prepared {
    pub(super) kind: PreparedKind,
}

pub(super) enum PreparedKind {
    Stability(Box<StabilityPrep>),
    Recognition(Box<RecognitionPrep>),
}

pub(super) struct StabilityPrep {
    pub(super) data: StabilityData,
    pub(super) dictionary: Dictionary,
    /// Clean grasp features of each method.
    pub(super) sparse: Array2<f64>,
    pub(super) raw: Array2<f64>,
}

pub(super) struct RecognitionPrep {
    pub(super) clean: FeatureSequences,
    pub(super) labels: Vec<usize>,
    pub(super) n_classes: usize,
    /// The clean per-grasp Table I features and their z-scoring (when a baseline runs).
    pub(super) table: Option<(Array2<f64>, Normaliser)>,
}

/// A task: the clean protocol (`sweep` None) or one strength of one sweep (indices into
/// the parameters' sweeps and their strengths), one repetition. Its seeds follow from the
/// run's seed and `rep`, so any machine computes it alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Task {
    pub sweep: Option<usize>,
    pub strength: usize,
    pub rep: usize,
}

/// A task's score for each method (in the parameters' order) and its seconds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskScores {
    pub scores: Vec<f64>,
    pub seconds: f64,
}

/// Stream indices: the folds / order of repetition r use stream r; these offsets keep the
/// other random choices of the same repetition independent of them.
pub(super) const PERTURB_STREAM: u64 = 1 << 40;
pub(super) const PROTOCOL_STREAM: u64 = 2 << 40;
/// k-means' and the SOM's seed in repetition r: the first draw of stream
/// `CLUSTER_STREAM + r` of the run's seed.
pub const CLUSTER_STREAM: u64 = 3 << 40;
pub(super) const SVM_STREAM: u64 = 4 << 40;
pub(super) const CLASSIFIER_STREAM: u64 = 5 << 40;

/// The run's tasks, in order: the clean protocol's repetitions, then every applicable
/// sweep's strengths and repetitions. Checks the parameters against the session first.
pub fn robustness_tasks(
    session: &Session,
    params: &RobustnessParams,
) -> Result<Vec<Task>, ExperimentError> {
    params.validate()?;
    if let Some(sw) = params
        .sweeps
        .iter()
        .find(|sw| sw.perturbation == Perturbation::DeadSensor)
        && let Some(&s) = sw
            .strengths
            .iter()
            .find(|&&s| s as usize > session.sensors.len())
    {
        return Err(ExperimentError::param(
            "strengths",
            format!(
                "dead-sensor: {s} sensors, but the session has {}",
                session.sensors.len()
            ),
        ));
    }
    let mut tasks: Vec<Task> = (0..params.reps)
        .map(|rep| Task {
            sweep: None,
            strength: 0,
            rep,
        })
        .collect();
    for (i, sw) in params.sweeps.iter().enumerate() {
        if applicability(session, params.family, sw.perturbation).is_some() {
            continue;
        }
        for s in 0..sw.strengths.len() {
            for rep in 0..params.reps {
                tasks.push(Task {
                    sweep: Some(i),
                    strength: s,
                    rep,
                });
            }
        }
    }
    Ok(tasks)
}

/// What a task costs relative to the others: every task runs every method once, on data of
/// one size, but a grasp-stability task whose perturbation reaches the training grasps
/// (noise) learns a dictionary of its own, some fifteen times the rest of a task.
fn task_cost(params: &RobustnessParams, task: &Task) -> f64 {
    let own_dictionary = params.family == Family::Stability
        && task
            .sweep
            .and_then(|i| params.sweeps.get(i))
            .is_some_and(|sw| sw.perturbation.scope() == Scope::All);
    if own_dictionary { 15.0 } else { 1.0 }
}

/// Run every sweep. Cancellable between tasks; `progress` gets the share of tasks done.
pub fn run_robustness(
    session: &Session,
    params: &RobustnessParams,
    progress: &Progress,
) -> Result<RobustnessResult, ExperimentError> {
    let tasks = robustness_tasks(session, params)?;
    let start = Instant::now();
    progress.set(0.0, "robustness: preparing");
    // What every task shares (a dictionary, the clean features) costs about two tasks.
    let parts = progress.parts(&[2.0, tasks.len() as f64]);
    let prepared = prepare(session, params, &parts[0])?;
    parts[0].set_fraction(1.0);
    let progress = &parts[1];
    let setup_seconds = start.elapsed().as_secs_f64();
    let total = tasks.len();
    let results = compute_items(
        &tasks,
        progress,
        "robustness",
        "runs",
        |t| task_cost(params, t),
        |t, _| robustness_task(session, params, &prepared, *t),
    )?;
    progress.set(1.0, format!("robustness: {total}/{total} runs done"));
    Ok(assemble_robustness(
        session,
        params,
        &tasks,
        &results,
        setup_seconds,
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads(),
    ))
}

/// The curves, clean scores and break points from the tasks' scores (in `tasks` order).
pub fn assemble_robustness(
    session: &Session,
    params: &RobustnessParams,
    tasks: &[Task],
    results: &[TaskScores],
    setup_seconds: f64,
    wall_seconds: f64,
    threads: usize,
) -> RobustnessResult {
    let not_applicable: Vec<Option<String>> = params
        .sweeps
        .iter()
        .map(|sw| applicability(session, params.family, sw.perturbation))
        .collect();
    // Assemble: results follow `tasks` order.
    let m = params.methods.len();
    let scores_of = |pred: &dyn Fn(&Task) -> bool, method: usize| -> (Vec<f64>, f64) {
        let mut v = Vec::new();
        let mut secs = 0.0;
        for (t, r) in tasks.iter().zip(results) {
            if pred(t) {
                v.push(r.scores[method]);
                secs += r.seconds / m as f64;
            }
        }
        (v, secs)
    };
    let clean: Vec<CleanScore> = params
        .methods
        .iter()
        .enumerate()
        .map(|(mi, &method)| {
            let (scores, _) = scores_of(&|t: &Task| t.sweep.is_none(), mi);
            CleanScore {
                method,
                score: MeanSd::of(scores.iter().copied()),
                scores,
            }
        })
        .collect();
    let mut curves = Vec::new();
    for (si, sw) in params.sweeps.iter().enumerate() {
        for (mi, &method) in params.methods.iter().enumerate() {
            let clean_mean = clean[mi].score.mean;
            let mut points = Vec::new();
            let mut task_seconds = 0.0;
            if not_applicable[si].is_none() {
                for (k, &strength) in sw.strengths.iter().enumerate() {
                    let (scores, secs) =
                        scores_of(&|t: &Task| t.sweep == Some(si) && t.strength == k, mi);
                    task_seconds += secs;
                    let score = MeanSd::of(scores.iter().copied());
                    points.push(SweepPoint {
                        strength,
                        relative: (clean_mean > 0.0).then(|| score.mean / clean_mean),
                        score,
                        scores,
                    });
                }
            }
            let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.strength, p.score.mean)).collect();
            curves.push(Curve {
                method,
                perturbation: sw.perturbation,
                scope: sw.perturbation.scope(),
                not_applicable: not_applicable[si].clone(),
                break_point: break_point(
                    sw.perturbation.neutral(),
                    clean_mean,
                    &xy,
                    params.fraction,
                ),
                points,
                task_seconds,
            });
        }
    }
    RobustnessResult {
        params: params.clone(),
        session: session.meta.name.clone(),
        score_name: params.family.score_name().into(),
        clean,
        curves,
        setup_seconds,
        wall_seconds,
        threads,
    }
}

/// Why a perturbation cannot be applied to this session and family (None: it can).
pub(super) fn applicability(session: &Session, family: Family, p: Perturbation) -> Option<String> {
    let one_frame = session.grasps.iter().all(|g| g.frames.len() <= 1);
    match p {
        Perturbation::Truncation | Perturbation::MissingFrames if one_frame => Some(
            "every grasp is a single frame: there is no sequence to cut or frames to drop".into(),
        ),
        Perturbation::NewObjects if family == Family::Recognition => Some(
            "each object is its own class here: a never-seen object is a class the model was never taught".into(),
        ),
        _ => None,
    }
}

/// Prepare what every task shares: the stability data and its clean dictionary, or the
/// clean feature sequences and labels.
pub fn prepare(
    session: &Session,
    params: &RobustnessParams,
    progress: &Progress,
) -> Result<Prepared, ExperimentError> {
    let kind = match params.family {
        Family::Stability => {
            let st = &params.stability;
            let data = StabilityData::from_session(session, &st.data)?;
            let dictionary = learn_dictionary(&data, st, progress)?;
            let (sparse, raw) = stability_features(&data, &dictionary, st.config.gamma)?;
            PreparedKind::Stability(Box::new(StabilityPrep {
                data,
                dictionary,
                sparse,
                raw,
            }))
        }
        Family::Recognition => {
            let rc = &params.recognition;
            let (labels, classes) = session_labels(session, &rc.label_set)?;
            let clean = feature_sequences(
                session,
                &SequenceParams {
                    features: rc.features,
                    taxel_noise_variance: 0.0,
                    seed: params.seed,
                },
            )?;
            let table = if Needs::of(&params.methods).table {
                let raw = session_features(session)?;
                let norm = Normaliser::fit(Normalisation::ZScore, raw.view())?;
                Some((norm.transform(raw.view())?, norm))
            } else {
                None
            };
            PreparedKind::Recognition(Box::new(RecognitionPrep {
                clean,
                labels,
                n_classes: classes.len(),
                table,
            }))
        }
    };
    Ok(Prepared { kind })
}

/// One task's scores, timed.
pub fn robustness_task(
    session: &Session,
    params: &RobustnessParams,
    prepared: &Prepared,
    task: Task,
) -> Result<TaskScores, ExperimentError> {
    let t0 = Instant::now();
    let scores = run_task(session, params, prepared, task)?;
    Ok(TaskScores {
        scores,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

pub(super) fn run_task(
    session: &Session,
    params: &RobustnessParams,
    prepared: &Prepared,
    task: Task,
) -> Result<Vec<f64>, ExperimentError> {
    let sweep = task.sweep.map(|i| &params.sweeps[i]);
    let pert = sweep.map(|sw| (sw.perturbation, sw.strengths[task.strength]));
    // The perturbed session, where the perturbation acts on the data.
    let perturbed = match pert.and_then(|(p, s)| p.session_kind().map(|k| (k, s))) {
        Some((kind, strength)) => Some(perturb(
            session,
            &PerturbParams {
                kind,
                strength,
                seed: Rng::stream(params.seed, PERTURB_STREAM + task.rep as u64).next_u64(),
                saturate: params.saturate,
            },
        )?),
        None => None,
    };
    match &prepared.kind {
        PreparedKind::Stability(prep) => {
            stability_task(params, prep, pert, perturbed.as_ref(), task.rep)
        }
        PreparedKind::Recognition(prep) => {
            recognition_task(params, prep, pert, perturbed.as_ref(), task.rep)
        }
    }
}
