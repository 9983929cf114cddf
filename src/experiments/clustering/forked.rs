//! One presentation order learned under every threshold of a sweep at once.
//!
//! A threshold enters DU's and GU's learning only where a grasp's novelty is compared with
//! it ([`NoveltyLearner`]). Learners that differ only in their threshold therefore compute
//! the same until a grasp's novelty falls between their thresholds. One learner learns for
//! all of them; where a grasp's novelty parts them, a copy of it goes on for the thresholds
//! that keep the grasp in its winner, and each re-assignment is computed once per final
//! learner. Every threshold's run is the one it would learn alone, bit for bit.
//!
//! The learner is copied after assessing the grasp that parts the thresholds, before
//! training on it. A branch is learned to the end before the next one is started (depth
//! first), so that one learner's state stays in the caches.

use std::time::Instant;

use ndarray::{Array2, ArrayView2};

use crate::experiments::ExperimentError;
use crate::jobs::Progress;
use crate::learners::NoveltyLearner;

/// One threshold's run on the order.
#[derive(Clone, Debug, PartialEq)]
pub struct ThresholdOutcome {
    pub clusters: usize,
    /// The cluster of every grasp (session order) after re-assignment.
    pub assignment: Vec<usize>,
    /// Seconds of this threshold's learner (what learning it alone takes; the shared part
    /// is counted for every threshold that shared it, copying for none).
    pub learn_seconds: f64,
    pub assign_seconds: f64,
}

/// A learner and the thresholds it learns for, from position `next` of the order.
struct Branch<L: NoveltyLearner> {
    learner: L,
    /// Indices into the thresholds.
    members: Vec<usize>,
    next: usize,
    /// A copy's grasp at `next`, already assessed: it goes to its winner.
    assessed: Option<L::Assessment>,
}

/// Learn the grasps `seqs` in `order` under each of `thresholds`, starting from `learner`
/// (its own threshold is not used), then re-assign every grasp; one outcome per threshold,
/// in their order. Stops at the next grasp once `progress` is cancelled. Progress counts
/// the grasps learned under each threshold: branches part within the first grasps, so
/// from there on a grasp costs about the same in every branch.
pub fn learn_order<L: NoveltyLearner>(
    learner: L,
    seqs: &[Array2<f64>],
    order: &[usize],
    thresholds: &[f64],
    progress: &Progress,
) -> Result<Vec<ThresholdOutcome>, ExperimentError> {
    let views: Vec<ArrayView2<f64>> = seqs.iter().map(|s| s.view()).collect();
    let mut learn_seconds = vec![0.0; thresholds.len()];
    let mut outcomes: Vec<(usize, ThresholdOutcome)> = Vec::with_capacity(thresholds.len());
    let total = (thresholds.len() * order.len()).max(1) as f64;
    let mut learned = 0usize;
    let mut pending = vec![Branch {
        learner,
        members: (0..thresholds.len()).collect(),
        next: 0,
        assessed: None,
    }];
    while let Some(mut b) = pending.pop() {
        if let Some(a) = b.assessed.take() {
            let t0 = Instant::now();
            b.learner
                .commit(seqs[order[b.next]].view(), Some(a), false)?;
            add(&mut learn_seconds, &b.members, t0.elapsed().as_secs_f64());
            b.next += 1;
            learned += b.members.len();
        }
        for (i, &g) in order.iter().enumerate().skip(b.next) {
            progress.checkpoint()?;
            let seq = seqs[g].view();
            let t0 = Instant::now();
            let a = b.learner.assess(seq);
            let novelty = a.as_ref().map(L::novelty);
            let (create, keep): (Vec<usize>, Vec<usize>) = b
                .members
                .iter()
                .partition(|&&m| novelty.is_none_or(|nu| nu > thresholds[m]));
            let assessing = t0.elapsed().as_secs_f64();
            // Every branch learns for some threshold: a grasp opens a cluster in this one
            // if it does for any of them.
            let opens = !create.is_empty();
            if let (true, false, Some(a)) = (opens, keep.is_empty(), a.as_ref()) {
                add(&mut learn_seconds, &keep, assessing);
                pending.push(Branch {
                    learner: b.learner.clone(),
                    members: keep,
                    next: i,
                    assessed: Some(a.clone()),
                });
                b.members = create;
            }
            let t1 = Instant::now();
            b.learner.commit(seq, a, opens)?;
            add(
                &mut learn_seconds,
                &b.members,
                assessing + t1.elapsed().as_secs_f64(),
            );
            learned += b.members.len();
            progress.set_fraction(learned as f64 / total);
        }
        let t0 = Instant::now();
        let assignment = b.learner.assign_all(&views);
        let assign_seconds = t0.elapsed().as_secs_f64();
        for &m in &b.members {
            outcomes.push((
                m,
                ThresholdOutcome {
                    clusters: b.learner.n_clusters(),
                    assignment: assignment.clone(),
                    learn_seconds: learn_seconds[m],
                    assign_seconds,
                },
            ));
        }
    }
    outcomes.sort_by_key(|(m, _)| *m);
    Ok(outcomes.into_iter().map(|(_, o)| o).collect())
}

fn add(seconds: &mut [f64], members: &[usize], s: f64) {
    for &m in members {
        seconds[m] += s;
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::gp::{PairDistances, Sogp, SogpParams};
    use crate::learners::testing::{grasps, quick_adaptation};
    use crate::learners::{DsParams, Du, DuParams, GsParams, Gu, GuNoise, GuParams};

    const THRESHOLDS: [f64; 9] = [0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.8, 0.95];

    fn gp(adapting: bool, base: SogpParams) -> SogpParams {
        SogpParams {
            capacity: 10,
            tau: 4,
            adaptation: adapting.then(quick_adaptation),
            ..base
        }
    }

    fn du(adapting: bool) -> impl Fn(f64) -> Du {
        move |threshold| {
            let ds = DsParams {
                gp: gp(adapting, DsParams::default().gp),
            };
            let p = DuParams {
                ds,
                threshold,
                min_grasps: 2,
            };
            Du::new(3, &p).unwrap()
        }
    }

    fn gu(noise: GuNoise) -> impl Fn(f64) -> Gu {
        move |threshold| {
            let gs = GsParams {
                gp: gp(true, GsParams::default().gp),
            };
            let p = GuParams {
                gs,
                threshold,
                noise,
                min_grasps: 2,
                ..GuParams::default()
            };
            Gu::new(3, &p).unwrap()
        }
    }

    fn grasps_and_order() -> (Vec<Array2<f64>>, Vec<usize>) {
        let seqs: Vec<Array2<f64>> = grasps(5, 30, 5, 3).into_iter().map(|g| g.1).collect();
        let order = (0..seqs.len()).map(|i| (7 * i) % seqs.len()).collect();
        (seqs, order)
    }

    /// Every threshold's outcome of the forked learning (from `forked`'s learner) is that
    /// of its own learner (`alone`'s), learning the grasps one by one and then re-assigning
    /// them one by one; returns how many different clusterings the thresholds ended with.
    fn forked_equals_alone<L: NoveltyLearner>(
        forked: impl Fn(f64) -> L,
        alone: impl Fn(f64) -> L,
    ) -> usize {
        let (seqs, order) = grasps_and_order();
        let forked =
            learn_order(forked(0.5), &seqs, &order, &THRESHOLDS, &Progress::new()).unwrap();
        assert_eq!(forked.len(), THRESHOLDS.len());
        for (&t, o) in THRESHOLDS.iter().zip(&forked) {
            let mut alone = alone(t);
            for &g in &order {
                alone.learn(seqs[g].view()).unwrap();
            }
            // One grasp at a time (the forked learning re-assigns them all at once).
            let assignment: Vec<usize> = seqs
                .iter()
                .map(|s| alone.assign_all(&[s.view()])[0])
                .collect();
            assert_eq!(
                (o.clusters, &o.assignment),
                (alone.n_clusters(), &assignment),
                "threshold {t}"
            );
        }
        let mut outcomes: Vec<(usize, &[usize])> = forked
            .iter()
            .map(|o| (o.clusters, &o.assignment[..]))
            .collect();
        outcomes.sort();
        outcomes.dedup();
        outcomes.len()
    }

    /// DU (with the experts' shared input table, and adapting with tables of their own)
    /// and GU (with the shared and the per-dimension noise) forked where the thresholds'
    /// decisions part learn what each threshold learns alone; the thresholds part several
    /// times (at least four different clusterings), so copies are taken mid-run.
    #[test]
    fn forked_learning_equals_each_threshold_learned_alone() {
        for adapting in [false, true] {
            let n = forked_equals_alone(du(adapting), du(adapting));
            assert!(n >= 4, "DU adapting {adapting}: {n} clusterings");
        }
        for noise in [GuNoise::Shared, GuNoise::PerDimension] {
            let n = forked_equals_alone(gu(noise), gu(noise));
            assert!(n >= 4, "GU {noise:?}: {n} clusterings");
        }
    }

    /// DU whose experts read a pair table of the grasps' inputs (until they adapt) learns,
    /// forked, what each threshold learns alone with tables of their own.
    #[test]
    fn forked_du_reading_a_pair_table_equals_each_threshold_learned_alone() {
        for adapting in [false, true] {
            let plain = du(adapting);
            let gp = gp(adapting, DsParams::default().gp);
            let kernel = Sogp::new(3, 1, &gp).unwrap().kernel().clone();
            let seqs = grasps_and_order().0;
            let steps = seqs.iter().map(|s| s.as_slice().unwrap());
            let pairs = Arc::new(PairDistances::new(&kernel, steps).unwrap());
            let paired = |t: f64| {
                let mut d = plain(t);
                d.use_pairs(pairs.clone());
                d
            };
            let n = forked_equals_alone(paired, du(adapting));
            assert!(n >= 4, "DU adapting {adapting}: {n} clusterings");
        }
    }

    /// A cancelled sweep stops at the next grasp: an order under every threshold is long,
    /// and a cancel must not wait for its end.
    #[test]
    fn a_cancelled_order_stops_at_the_next_grasp() {
        let (seqs, order) = grasps_and_order();
        let progress = Progress::new();
        progress.cancel();
        let r = learn_order(du(true)(0.5), &seqs, &order, &THRESHOLDS, &progress);
        assert!(matches!(r, Err(ExperimentError::Cancelled)), "{r:?}");
    }
}
