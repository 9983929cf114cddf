use ndarray::Array2;
use tactile_workbench::cluster::scores;
use tactile_workbench::gp::SngdParams;
use tactile_workbench::learners::{
    Du, DuParams, EvtDraws, Gu, GuAggregate, GuParams, NoveltyLearner, du_novelty,
};
use tactile_workbench::rng::Rng;

fn sequence(class: usize, rng: &mut Rng) -> Array2<f64> {
    Array2::from_shape_fn((10, 2), |(t, d)| {
        let x = t as f64 / 10.0;
        let centre = [0.1, 0.5, 0.9][class];
        let v = if d == 0 { centre } else { centre * x };
        v + 0.01 * rng.normal()
    })
}

fn data(seed: u64) -> (Vec<Array2<f64>>, Vec<usize>) {
    let mut rng = Rng::new(seed);
    let labels: Vec<usize> = (0..24).map(|i| i % 3).collect();
    (
        labels.iter().map(|&c| sequence(c, &mut rng)).collect(),
        labels,
    )
}

/// Experts whose lengthscale is short against the gaps between the objects.
fn small(mut p: tactile_workbench::gp::SogpParams) -> tactile_workbench::gp::SogpParams {
    p.lengthscale = 0.15;
    p.tau = 3;
    p.capacity = 15;
    p.adaptation = Some(SngdParams {
        start_after: 40,
        ..Default::default()
    });
    p
}

/// The three objects lie 0.4 apart with noise of 0.01: a learner that finds them recovers
/// the classes almost exactly (NMI and ARI are 1 for a perfect clustering and near 0 by
/// chance). Purity alone cannot tell: one cluster per grasp has purity 1. So the cluster
/// count is bounded from both sides (at least one, at most two clusters per object).
fn assert_recovers_the_objects(labels: &[usize], pred: &[usize], n_clusters: usize, what: &str) {
    assert!(
        (3..=6).contains(&n_clusters),
        "{what}: {n_clusters} clusters for 3 objects"
    );
    let s = scores(labels, pred);
    assert!(
        s.nmi >= 0.9 && s.ari >= 0.9 && s.purity >= 0.95,
        "{what}: {s:?}"
    );
}

#[test]
fn du_novelty_matches_eq_28() {
    assert_eq!(du_novelty([1.0, 1.0].into_iter()), 0.0);
    assert_eq!(du_novelty([0.5, 0.2].into_iter()), 1.0);
    assert!((du_novelty([1.0, 0.5].into_iter()) - 0.5).abs() < 1e-15);
    assert!((du_novelty([0.75].into_iter()) - 0.5).abs() < 1e-15);
}

#[test]
fn du_finds_separated_objects_and_threshold_one_keeps_one_cluster() {
    let (seqs, labels) = data(3);
    let mut p = DuParams::default();
    p.ds.gp = small(p.ds.gp);
    p.threshold = 0.5;
    let mut du = Du::new(2, &p).unwrap();
    for s in &seqs {
        du.learn(s.view()).unwrap();
    }
    let pred: Vec<usize> = seqs.iter().map(|s| du.assign(s.view())).collect();
    assert_recovers_the_objects(&labels, &pred, du.n_clusters(), "DU");
    // Fresh grasps of the learned objects are familiar: below the threshold, no new cluster.
    let (fresh, _) = data(30);
    for s in &fresh {
        let a = du.learn(s.view()).unwrap();
        assert!(!a.created && a.novelty <= 0.5, "{a:?}");
    }
    p.threshold = 1.0;
    let mut one = Du::new(2, &p).unwrap();
    for s in &seqs {
        let a = one.learn(s.view()).unwrap();
        assert!((0.0..=1.0).contains(&a.novelty));
    }
    assert_eq!(one.n_clusters(), 1);
}

#[test]
fn gu_finds_separated_objects_and_threshold_one_keeps_one_cluster() {
    let (seqs, labels) = data(4);
    // Far from its data an expert predicts its broad prior, where few steps look extreme:
    // the mean over steps needs a low threshold. With m = grasps it must still exceed the
    // novelty an expert trained on one grasp gives its object's next grasp (EVT over two
    // draws: about 0.14 here, against 0.25 and more for a new object), or every grasp
    // opens a cluster of its own.
    for (aggregate, draws, threshold) in [
        (GuAggregate::Max, EvtDraws::Grasps, 0.5),
        (GuAggregate::Mean, EvtDraws::Grasps, 0.2),
        (GuAggregate::Mean, EvtDraws::Steps, 0.05),
        (GuAggregate::Joint, EvtDraws::Grasps, 0.5),
    ] {
        let mut p = GuParams::default();
        // Far from its data a short-lengthscale expert predicts its prior, which a grasp's
        // joint density rarely finds extreme: the whole-grasp score keeps the paper's 10.0.
        if aggregate != GuAggregate::Joint {
            p.gs.gp = small(p.gs.gp);
        }
        p.threshold = threshold;
        p.aggregate = aggregate;
        p.draws = draws;
        let mut gu = Gu::new(2, &p).unwrap();
        for s in &seqs {
            gu.learn(s.view()).unwrap();
        }
        let what = format!("GU {aggregate:?}, {draws:?}");
        let pred: Vec<usize> = seqs.iter().map(|s| gu.assign(s.view())).collect();
        assert_recovers_the_objects(&labels, &pred, gu.n_clusters(), &what);
        let (fresh, _) = data(31);
        for s in &fresh {
            let a = gu.learn(s.view()).unwrap();
            assert!(!a.created && a.novelty <= threshold, "{what}: {a:?}");
        }
        p.threshold = 1.0;
        let mut one = Gu::new(2, &p).unwrap();
        for s in &seqs {
            one.learn(s.view()).unwrap();
        }
        assert_eq!(one.n_clusters(), 1);
    }
}

#[test]
fn thresholds_outside_the_unit_interval_are_errors() {
    let p = DuParams {
        threshold: 1.5,
        ..DuParams::default()
    };
    assert!(
        Du::new(2, &p)
            .unwrap_err()
            .to_string()
            .contains("threshold")
    );
    let p = GuParams {
        threshold: -0.1,
        ..GuParams::default()
    };
    assert!(
        Gu::new(2, &p)
            .unwrap_err()
            .to_string()
            .contains("threshold")
    );
}

#[test]
fn training_from_the_predicted_q_changes_nothing() {
    use tactile_workbench::learners::{Ds, DsParams, SequenceClassifier};
    let (seqs, labels) = data(5);
    let mut p = DsParams::default();
    p.gp = small(p.gp);
    let mut full = Ds::new(2, &p).unwrap();
    for _ in 0..3 {
        full.add_class().unwrap();
    }
    let mut fast = full.clone();
    for (s, &c) in seqs.iter().zip(&labels) {
        full.predict_q_and_p(s.view());
        full.train_sequence(s.view(), c);
        let (q, _) = fast.predict_q_and_p(s.view());
        fast.train_sequence_predicted(s.view(), c, q.view());
        assert_eq!(full.q(), fast.q());
    }
    let mut rng = Rng::new(9);
    for c in 0..3 {
        let probe = sequence(c, &mut rng);
        assert_eq!(
            full.predict_sequence(probe.view()),
            fast.predict_sequence(probe.view()),
            "the experts differ after training"
        );
    }
}

/// DU with GU's confirmation rule: a one-off grasp far from the three objects opens a
/// cluster that no later grasp confirms. Every cluster kept, it wins that grasp back; with
/// `min_grasps` 3 the grasp goes to a confirmed object's cluster, and every other grasp
/// keeps its cluster.
#[test]
fn du_leaves_an_unconfirmed_cluster_out_of_the_reassignment() {
    let (mut seqs, _) = data(3);
    let odd = Array2::from_shape_fn(
        (10, 2),
        |(t, d)| {
            if d == 0 { 1.6 } else { 1.6 * t as f64 / 10.0 }
        },
    );
    seqs.insert(12, odd);
    let reassign = |min_grasps: usize| {
        let mut p = DuParams::default();
        p.ds.gp = small(p.ds.gp);
        p.threshold = 0.5;
        p.min_grasps = min_grasps;
        let mut du = Du::new(2, &p).unwrap();
        let learned: Vec<usize> = seqs
            .iter()
            .map(|s| du.learn(s.view()).unwrap().cluster)
            .collect();
        let assigned: Vec<usize> = seqs.iter().map(|s| du.assign(s.view())).collect();
        (learned, assigned)
    };
    let (learned, all) = reassign(1);
    let odd_cluster = learned[12];
    assert_eq!(
        learned.iter().filter(|&&c| c == odd_cluster).count(),
        1,
        "the one-off opens its own cluster: {learned:?}"
    );
    assert_eq!(all[12], odd_cluster);
    let (_, confirmed) = reassign(3);
    assert_ne!(confirmed[12], odd_cluster);
    assert!(learned.iter().filter(|&&c| c == confirmed[12]).count() >= 3);
    for (i, (a, b)) in all.iter().zip(&confirmed).enumerate() {
        if i != 12 {
            assert_eq!(a, b, "grasp {i}");
        }
    }
}

/// A cluster opens when nu_D exceeds theta_D (eq. 28), so theta_D = 1 never opens one.
/// Far from every grasp learned (1e3 away, lengthscale 0.15) the expert's GP predicts its
/// prior mean 0, so q = Φ(0) = 1/2 at every step, max(0, 2q − 1) = 0 and nu_D = 1 exactly:
/// the most novel grasp there is equals the threshold without exceeding it.
#[test]
fn du_novelty_equal_to_the_threshold_opens_no_cluster() {
    let (seqs, _) = data(3);
    let mut p = DuParams::default();
    p.ds.gp = small(p.ds.gp);
    p.threshold = 1.0;
    let mut du = Du::new(2, &p).unwrap();
    for s in &seqs {
        du.learn(s.view()).unwrap();
    }
    let far = Array2::from_elem((10, 2), 1e3);
    let a = du.learn(far.view()).unwrap();
    assert_eq!((a.novelty, a.created), (1.0, false), "{a:?}");
    assert_eq!(du.n_clusters(), 1);
}

#[test]
fn a_du_min_grasps_of_zero_is_an_error() {
    let p = DuParams {
        min_grasps: 0,
        ..DuParams::default()
    };
    assert!(
        Du::new(2, &p)
            .unwrap_err()
            .to_string()
            .contains("min_grasps")
    );
}

/// GU's counterpart of the test above: a cluster opens when nu_G exceeds theta_U (the
/// paper's GU, as eq. 28 for DU). 1e3 away from every grasp learned the expert predicts its
/// prior, the squared Mahalanobis radius of each step is of order 1e6 against the few
/// units of c_m's, so (f(o)/c_m)^α_m underflows to 0 and each step's novelty
/// exp(−(f(o)/c_m)^α_m) is exactly 1, as is their mean: the most novel grasp there is
/// equals theta_U = 1 without exceeding it.
#[test]
fn gu_novelty_equal_to_the_threshold_opens_no_cluster() {
    let (seqs, _) = data(3);
    let mut p = GuParams::default();
    p.gs.gp = small(p.gs.gp);
    p.threshold = 1.0;
    let mut gu = Gu::new(2, &p).unwrap();
    for s in &seqs {
        gu.learn(s.view()).unwrap();
    }
    let far = Array2::from_elem((10, 2), 1e3);
    let a = gu.learn(far.view()).unwrap();
    assert_eq!((a.novelty, a.created), (1.0, false), "{a:?}");
    assert_eq!(gu.n_clusters(), 1);
}

/// Before any cluster is confirmed (`min_grasps` 3, two grasps learned), DU's
/// re-assignment takes every cluster into account ("all if none is"): grasps of two objects
/// 0.4 apart, each in a cluster of its own, go back to their own.
#[test]
fn du_with_no_confirmed_cluster_assigns_among_all() {
    let (seqs, labels) = data(3);
    assert_ne!(labels[0], labels[1]);
    let mut p = DuParams::default();
    p.ds.gp = small(p.ds.gp);
    p.threshold = 0.5;
    p.min_grasps = 3;
    let mut du = Du::new(2, &p).unwrap();
    let learned: Vec<usize> = seqs[..2]
        .iter()
        .map(|s| du.learn(s.view()).unwrap().cluster)
        .collect();
    assert_eq!(learned, [0, 1]);
    for (s, c) in seqs.iter().zip(learned) {
        assert_eq!(du.assign(s.view()), c);
    }
}

/// A predicted q of the wrong shape (a cluster added, or steps missing, since it was
/// predicted) is read only where it exists: the experts and steps it does not cover are
/// observed again, and training ends where training from scratch does.
#[test]
fn training_from_a_partial_predicted_q_changes_nothing() {
    use ndarray::s;
    use tactile_workbench::learners::{Ds, DsParams, SequenceClassifier};
    let (seqs, labels) = data(6);
    let mut p = DsParams::default();
    p.gp = small(p.gp);
    // (rows, columns) of the predicted q kept: one expert fewer, or the first 4 steps.
    for (rows, cols) in [(10, 2), (4, 3)] {
        let mut full = Ds::new(2, &p).unwrap();
        for _ in 0..3 {
            full.add_class().unwrap();
        }
        let mut fast = full.clone();
        for (s, &c) in seqs.iter().zip(&labels) {
            full.predict_q_and_p(s.view());
            full.train_sequence(s.view(), c);
            let (q, _) = fast.predict_q_and_p(s.view());
            fast.train_sequence_predicted(s.view(), c, q.slice(s![..rows, ..cols]));
            assert_eq!(full.q(), fast.q(), "q kept {rows} × {cols}");
        }
        let probe = sequence(1, &mut Rng::new(9));
        assert_eq!(
            full.predict_sequence(probe.view()),
            fast.predict_sequence(probe.view()),
            "q kept {rows} × {cols}: the experts differ after training"
        );
    }
}
