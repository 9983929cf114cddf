//! Step and protocol timings of the online learners (bench-recognition): synthetic sequences and the session's own, medians with p10 and p90.

use super::*;

/// CPU seconds (user + system) used so far by the calling thread, or by the whole process
/// with `process = true`, from Linux's /proc (clock ticks of 10 ms); None elsewhere. The
/// machine is shared, so wall-clock times mix in other work: CPU time does not.
pub fn cpu_seconds(process: bool) -> Option<f64> {
    let path = if process {
        "/proc/self/stat"
    } else {
        "/proc/thread-self/stat"
    };
    let text = std::fs::read_to_string(path).ok()?;
    let after = &text[text.rfind(')')? + 1..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Per-observation cost of the learners on synthetic data of a given size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepBenchParams {
    pub dim: usize,
    pub classes: usize,
    pub capacity: usize,
    pub tau: usize,
    /// Training sequences per class before timing (fills the BV budget).
    pub warmup_sequences: usize,
    /// Steps of each timed sequence, and timed sequences.
    pub steps: usize,
    pub sequences: usize,
    pub adaptation: bool,
    pub seed: u64,
}

impl Default for StepBenchParams {
    fn default() -> Self {
        StepBenchParams {
            dim: 34,
            classes: 10,
            capacity: 50,
            tau: 15,
            warmup_sequences: 8,
            steps: 20,
            sequences: 60,
            adaptation: true,
            seed: 0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepBench {
    pub params: StepBenchParams,
    pub learner: SupervisedLearner,
    /// Wall-clock microseconds per prediction step over all classes.
    pub predict_step_us: f64,
    /// Wall-clock microseconds per training step (DS: all experts observed, two updated).
    pub train_step_us: f64,
    /// The same in CPU time of the timing thread (None where /proc is missing).
    pub predict_step_cpu_us: Option<f64>,
    pub train_step_cpu_us: Option<f64>,
    /// Mean BVs per expert and experts still adapting when timed.
    pub mean_basis: f64,
    pub adapting: usize,
}

pub(super) fn synthetic_sequence(
    dim: usize,
    steps: usize,
    class: usize,
    rng: &mut Rng,
) -> Array2<f64> {
    let mut x = Array2::zeros((steps, dim));
    for j in 0..dim {
        let mut v = 0.1 * ((class * 7 + j * 3) % 10) as f64;
        for t in 0..steps {
            v = (v + 0.05 * rng.normal()).clamp(0.0, 1.0);
            x[[t, j]] = v;
        }
    }
    x
}

/// DS and GS settings of a benchmark: experts of `capacity` and `tau`, with or without
/// hyperparameter adaptation.
pub(super) fn bench_learners(
    capacity: usize,
    tau: usize,
    adaptation: bool,
) -> (DsParams, GsParams) {
    let mut ds = DsParams::default();
    let mut gs = GsParams::default();
    for gp in [&mut ds.gp, &mut gs.gp] {
        gp.capacity = capacity;
        gp.tau = tau;
        if !adaptation {
            gp.adaptation = None;
        }
    }
    (ds, gs)
}

/// Time per-observation prediction and training on one thread.
pub fn bench_steps(
    learner: SupervisedLearner,
    params: &StepBenchParams,
) -> Result<StepBench, ExperimentError> {
    let (ds, gs) = bench_learners(params.capacity, params.tau, params.adaptation);
    let mut l = new_learner(learner, params.dim, params.classes, &ds, &gs)?;
    let mut rng = Rng::new(params.seed);
    for _ in 0..params.warmup_sequences {
        for c in 0..params.classes {
            let s = synthetic_sequence(params.dim, params.steps, c, &mut rng);
            l.train_sequence(s.view(), c);
        }
    }
    let seqs: Vec<(usize, Array2<f64>)> = (0..params.sequences)
        .map(|i| {
            let c = i % params.classes;
            (c, synthetic_sequence(params.dim, params.steps, c, &mut rng))
        })
        .collect();
    let mean_basis =
        l.models().iter().map(|m| m.n_basis() as f64).sum::<f64>() / l.models().len().max(1) as f64;
    let adapting = l.models().iter().filter(|m| m.adapting()).count();
    let total_steps = (params.sequences * params.steps).max(1) as f64;
    let per_step = |a: Option<f64>, b: Option<f64>| Some(1e6 * (b? - a?) / total_steps);
    let (t0, c0) = (Instant::now(), cpu_seconds(false));
    for (_, s) in &seqs {
        l.predict_sequence(s.view());
    }
    let predict_step_us = 1e6 * t0.elapsed().as_secs_f64() / total_steps;
    let predict_step_cpu_us = per_step(c0, cpu_seconds(false));
    let (t0, c0) = (Instant::now(), cpu_seconds(false));
    for (c, s) in &seqs {
        l.train_sequence(s.view(), *c);
    }
    let train_step_us = 1e6 * t0.elapsed().as_secs_f64() / total_steps;
    let train_step_cpu_us = per_step(c0, cpu_seconds(false));
    Ok(StepBench {
        params: params.clone(),
        learner,
        predict_step_us,
        train_step_us,
        predict_step_cpu_us,
        train_step_cpu_us,
        mean_basis,
        adapting,
    })
}

/// Per-step cost on a session's grasps (the Table II protocol's order, all features).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionBenchParams {
    pub learner: SupervisedLearner,
    pub capacity: usize,
    pub tau: usize,
    pub adaptation: bool,
    /// Protocol repetitions (orders); steps are timed in all of them.
    pub reps: usize,
    pub seed: u64,
}

/// Median and 10th / 90th percentiles of per-step times, µs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepTimes {
    pub median: f64,
    pub p10: f64,
    pub p90: f64,
    pub steps: usize,
}

impl StepTimes {
    /// Nearest-rank percentiles of `us` (NaN when empty).
    pub fn of(mut us: Vec<f64>) -> StepTimes {
        us.sort_by(f64::total_cmp);
        let at = |q: f64| match us.len() {
            0 => f64::NAN,
            n => us[((q * n as f64).ceil() as usize).clamp(1, n) - 1],
        };
        StepTimes {
            median: at(0.5),
            p10: at(0.1),
            p90: at(0.9),
            steps: us.len(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionStepBench {
    pub params: SessionBenchParams,
    /// A prediction step: every expert observes the step, the class distribution follows.
    pub predict: StepTimes,
    /// A training step (DS: every expert observes, the true class's expert and the most
    /// probable wrong one are updated; GS: the true class's expert is updated).
    pub train: StepTimes,
    /// Experts still adapting their hyperparameters at the end (all repetitions).
    pub adapting: usize,
    pub experts: usize,
}

/// Time every step of the protocol on `session` (each grasp predicted, then trained) once
/// every expert holds its full BV budget, on one thread.
pub fn bench_session_steps(
    session: &Session,
    params: &SessionBenchParams,
) -> Result<SessionStepBench, ExperimentError> {
    let (labels, classes) = session_labels(session, "object")?;
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features: FeatureSet::ALL,
            taxel_noise_variance: 0.0,
            seed: params.seed,
        },
    )?;
    let (ds, gs) = bench_learners(params.capacity, params.tau, params.adaptation);
    let dim = feats.dim();
    let (mut predict_us, mut train_us) = (Vec::new(), Vec::new());
    let (mut adapting, mut experts) = (0, 0);
    for rep in 0..params.reps {
        let mut l = new_learner(params.learner, dim, classes.len(), &ds, &gs)?;
        let mut rng = Rng::stream(params.seed, rep as u64);
        let (teach, order) = protocol_order(&labels, classes.len(), &mut rng);
        let mut dist = vec![0.0; classes.len()];
        for g in teach.into_iter().chain(order) {
            let timed = l.models().iter().all(|m| m.n_basis() == params.capacity);
            let seq = feats.sequences[g].as_standard_layout();
            let steps = seq.as_slice().unwrap_or_default().chunks_exact(dim);
            l.start_sequence();
            for o in steps.clone() {
                let t0 = Instant::now();
                l.predict_step(o, &mut dist);
                if timed {
                    predict_us.push(1e6 * t0.elapsed().as_secs_f64());
                }
            }
            l.start_sequence();
            for o in steps {
                let t0 = Instant::now();
                l.train_step(o, labels[g]);
                if timed {
                    train_us.push(1e6 * t0.elapsed().as_secs_f64());
                }
            }
        }
        adapting += l.models().iter().filter(|m| m.adapting()).count();
        experts += l.models().len();
    }
    Ok(SessionStepBench {
        params: params.clone(),
        predict: StepTimes::of(predict_us),
        train: StepTimes::of(train_us),
        adapting,
        experts,
    })
}

/// Where and when [`LIBOTL_US`] were measured: a benchmark prints this beside them and
/// shows no ratio to them (a ratio across machines and loads says little).
pub const LIBOTL_MEASURED: &str = "the authors' C++ library built -O3, measured on another \
     machine (a 2-core Intel Xeon with AVX-512, load under 1), recorded 2026-11-25 in \
     docs/recognition-speed.md; not comparable as a ratio";

/// libOTL's figures at the anchor's settings (the authors' C++ library built `-O3`, on the
/// machine of docs/recognition-speed.md: iCub features, 10 classes, capacity 50, tau 15, no
/// adaptation, medians once every expert holds 50 BVs), µs.
pub const LIBOTL_US: AnchorFigures = AnchorFigures {
    update: 17.0,
    predict: 307.0,
    ds_train: 387.0,
    all_updated: 458.0,
};

/// One figure per step the anchor times.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct AnchorFigures<T = f64> {
    /// One `Sogp::update` alone (with the deletion it triggers at the budget).
    pub update: T,
    /// A 10-class prediction step: every expert observes, the class distribution follows.
    pub predict: T,
    /// A DS training step: every expert observes, the true class's expert and the most
    /// probable wrong one are updated.
    pub ds_train: T,
    /// Every expert observes and every expert is updated (+1 the true class, −1 the rest).
    pub all_updated: T,
}

/// The steps libOTL was timed on, timed here the same way (DS experts, adaptation off, the
/// Table II protocol's orders, one thread), with libOTL's figures beside them.
#[derive(Debug, serde::Serialize)]
pub struct AnchorBench {
    pub capacity: usize,
    pub tau: usize,
    pub orders: usize,
    pub ours: AnchorFigures<StepTimes>,
    pub libotl: AnchorFigures,
    /// Distinct inputs the experts' BVs hold at the end of each DS-trained order, summed
    /// over the experts, and held once in the table they share: the sum over the held is
    /// the factor by which sharing cuts the new distances per step.
    pub inputs_summed: Vec<usize>,
    pub inputs_held: Vec<usize>,
}

/// DS's experts, trained step by step over the protocol's orders of `session` as DS trains
/// them (`all` = false) or with every expert updated at every step, timing each part.
pub fn anchor_steps(
    session: &Session,
    capacity: usize,
    tau: usize,
    orders: usize,
) -> Result<AnchorBench, ExperimentError> {
    use crate::experiments::{labels::session_labels, recognition::protocol_order};
    use crate::features::{FeatureSet, SequenceParams, feature_sequences};
    use crate::gp::{SharedInputs, Sogp, SogpParams, Window};
    use crate::learners::DsParams;
    use crate::rng::Rng;

    let (labels, classes) = session_labels(session, "object")?;
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features: FeatureSet::ALL,
            taxel_noise_variance: 0.0,
            seed: 0,
        },
    )?;
    let dim = feats.dim();
    let gp = SogpParams {
        capacity,
        tau,
        adaptation: None,
        ..DsParams::default().gp
    };
    let us = |t0: Instant| 1e6 * t0.elapsed().as_secs_f64();
    let (mut update, mut predict, mut ds_train, mut all_updated) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut inputs_summed, mut inputs_held) = (Vec::new(), Vec::new());
    for all in [false, true] {
        for rep in 0..orders {
            let mut experts = vec![
                Sogp::new(dim, 1, &gp)
                    .map_err(|e| ExperimentError::Learner(e.into()))?;
                classes.len()
            ];
            // Without adaptation the experts share their distinct inputs, as DS's do.
            let mut shared = SharedInputs::new(experts[0].kernel());
            for m in &mut experts {
                m.join(&mut shared);
            }
            let mut q = vec![0.0; classes.len()];
            let mut window = Window::new(dim, tau);
            let mut rng = Rng::stream(0, rep as u64);
            let (teach, order) = protocol_order(&labels, classes.len(), &mut rng);
            for g in teach.into_iter().chain(order) {
                let timed = experts.iter().all(|m| m.n_basis() == capacity);
                let seq = feats.sequences[g].as_standard_layout();
                let steps = seq.as_slice().unwrap_or_default().chunks_exact(dim);
                window.reset();
                for o in steps.clone() {
                    let t0 = Instant::now();
                    window.push(o);
                    for (m, q) in experts.iter_mut().zip(q.iter_mut()) {
                        m.observe_in(&mut shared, window.as_slice(), window.stamp());
                        *q = m.probability();
                    }
                    let sum: f64 = q.iter().sum();
                    for q in q.iter_mut() {
                        *q /= sum;
                    }
                    if timed && !all {
                        predict.push(us(t0));
                    }
                }
                window.reset();
                for o in steps {
                    let t0 = Instant::now();
                    window.push(o);
                    for (m, q) in experts.iter_mut().zip(q.iter_mut()) {
                        m.observe_in(&mut shared, window.as_slice(), window.stamp());
                        *q = m.probability();
                    }
                    let class = labels[g];
                    if all {
                        for (c, m) in experts.iter_mut().enumerate() {
                            m.update_in(&mut shared, &[if c == class { 1.0 } else { -1.0 }]);
                        }
                        if timed {
                            all_updated.push(us(t0));
                        }
                        continue;
                    }
                    let wrong = (0..experts.len())
                        .filter(|&c| c != class)
                        .max_by(|&a, &b| q[a].total_cmp(&q[b]));
                    for (c, y) in [(Some(class), 1.0), (wrong, -1.0)] {
                        let Some(c) = c else { continue };
                        let t1 = Instant::now();
                        experts[c].update_in(&mut shared, &[y]);
                        if timed {
                            update.push(us(t1));
                        }
                    }
                    if timed {
                        ds_train.push(us(t0));
                    }
                }
            }
            if !all {
                inputs_summed.push(experts.iter().map(Sogp::distinct_inputs).sum());
                inputs_held.push(shared.distinct());
            }
        }
    }
    Ok(AnchorBench {
        capacity,
        tau,
        orders,
        ours: AnchorFigures {
            update: StepTimes::of(update),
            predict: StepTimes::of(predict),
            ds_train: StepTimes::of(ds_train),
            all_updated: StepTimes::of(all_updated),
        },
        libotl: LIBOTL_US,
        inputs_summed,
        inputs_held,
    })
}
