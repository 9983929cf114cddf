//! Scores and folds on hand-computed cases: weighted success rate, failure recall,
//! confusion, stratified k-fold, leave-objects-out (never one object in train and test),
//! and cross validation bookkeeping.

use ndarray::Array2;
use tactile_workbench::rng::Rng;
use tactile_workbench::svm::{
    Confusion, LinearSvmParams, Loss, cross_validate, gather, group_k_fold, mean_se,
    stratified_k_fold,
};

#[test]
fn weighted_success_rate_and_failure_recall_by_hand() {
    // 6 successes (false), 4 failures (true).
    let truth = [
        false, false, false, false, false, false, true, true, true, true,
    ];
    let pred = [
        false, false, false, false, true, true, true, true, true, false,
    ];
    let c = Confusion::from_predictions(&truth, &pred);
    assert_eq!(c.matrix, [[4, 2], [1, 3]]);
    assert_eq!(
        (c.total_successes(), c.total_failures(), c.total()),
        (6, 4, 10)
    );
    // CCS/TS = 4/6, CCF/TF = 3/4, WSR = (4/6 + 3/4) / 2 = 17/24.
    assert!((c.success_recall().unwrap() - 4.0 / 6.0).abs() < 1e-15);
    assert!((c.failure_recall().unwrap() - 0.75).abs() < 1e-15);
    assert!((c.weighted_success_rate().unwrap() - 17.0 / 24.0).abs() < 1e-15);
    assert!((c.accuracy().unwrap() - 0.7).abs() < 1e-15);
    // The paper's numbers: 405 successes, 135 failures.
    let paper = Confusion {
        matrix: [[300, 105], [22, 113]],
    };
    assert!((paper.failure_recall().unwrap() - 113.0 / 135.0).abs() < 1e-15);
    // Undefined without one class.
    let only = Confusion::from_predictions(&[false, false], &[false, true]);
    assert_eq!(only.weighted_success_rate(), None);
    assert_eq!(only.failure_recall(), None);
    let mut sum = c;
    sum.add(&only);
    assert_eq!(sum.matrix, [[5, 3], [1, 3]]);
}

#[test]
fn mean_and_standard_error_by_hand() {
    let (m, se) = mean_se(&[0.8, 0.9, 1.0]);
    assert!((m - 0.9).abs() < 1e-15);
    // sd = 0.1, se = 0.1 / sqrt(3).
    assert!((se - 0.1 / 3f64.sqrt()).abs() < 1e-12);
    assert_eq!(mean_se(&[0.5]), (0.5, 0.0));
}

#[test]
fn stratified_folds_keep_class_proportions_and_sizes() {
    let labels: Vec<bool> = (0..103).map(|i| i % 4 == 0).collect(); // 26 true, 77 false
    let f = stratified_k_fold(&labels, 10, 3).unwrap();
    assert_eq!(f.count, 10);
    let sizes: Vec<usize> = (0..10).map(|k| f.test_indices(k).len()).collect();
    assert!(
        sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1,
        "{sizes:?}"
    );
    assert_eq!(sizes.iter().sum::<usize>(), 103);
    for k in 0..10 {
        let pos = f.test_indices(k).iter().filter(|&&i| labels[i]).count();
        assert!((2..=3).contains(&pos), "fold {k} has {pos} positives");
        // Train and test partition the samples.
        let (tr, te) = (f.train_indices(k), f.test_indices(k));
        assert_eq!(tr.len() + te.len(), 103);
        assert!(te.iter().all(|i| !tr.contains(i)));
    }
    // Seeded: same seed same folds, another seed other folds.
    assert_eq!(f, stratified_k_fold(&labels, 10, 3).unwrap());
    assert_ne!(f, stratified_k_fold(&labels, 10, 4).unwrap());
    assert!(stratified_k_fold(&labels, 1, 0).is_err());
    assert!(stratified_k_fold(&labels[..5], 10, 0).is_err());
}

#[test]
fn leave_objects_out_never_splits_an_object() {
    let mut rng = Rng::new(1);
    let groups: Vec<usize> = (0..300).map(|_| rng.below(17)).collect();
    for k in [None, Some(5), Some(10)] {
        let f = group_k_fold(&groups, k, 2).unwrap();
        for g in 0..17 {
            let folds: std::collections::BTreeSet<usize> = (0..300)
                .filter(|&i| groups[i] == g)
                .map(|i| f.fold_of[i])
                .collect();
            assert!(folds.len() <= 1, "object {g} in folds {folds:?}");
        }
        for fold in 0..f.count {
            let train = f.train_indices(fold);
            for &i in &f.test_indices(fold) {
                assert!(train.iter().all(|&t| groups[t] != groups[i]));
            }
        }
    }
    // One fold per object when none is given.
    assert_eq!(group_k_fold(&groups, None, 0).unwrap().count, 17);
    // Balanced: with 10 folds no fold is more than one object's size above the smallest.
    let f = group_k_fold(&groups, Some(5), 0).unwrap();
    let sizes: Vec<usize> = (0..5).map(|k| f.test_indices(k).len()).collect();
    let max_group = (0..17)
        .map(|g| groups.iter().filter(|&&x| x == g).count())
        .max()
        .unwrap();
    assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= max_group);
    assert!(group_k_fold(&groups, Some(18), 0).is_err());
    assert!(group_k_fold(&[0, 0, 0], None, 0).is_err());
}

#[test]
fn cross_validation_tests_every_sample_once_and_is_deterministic() {
    let mut rng = Rng::new(2);
    let n = 120;
    let y: Vec<bool> = (0..n).map(|i| i % 3 == 0).collect();
    let x = Array2::from_shape_fn((n, 4), |(i, j)| {
        rng.normal() + if y[i] && j == 0 { 1.5 } else { 0.0 }
    });
    let folds = stratified_k_fold(&y, 10, 0).unwrap();
    let p = LinearSvmParams::default();
    let r = cross_validate(x.view(), &y, &folds, &p).unwrap();
    assert_eq!(r.confusion.total(), n);
    assert_eq!(r.folds.len(), 10);
    assert_eq!(r.folds.iter().map(|f| f.test).sum::<usize>(), n);
    // The pooled confusion is the sum of the folds' and matches the predictions.
    assert_eq!(Confusion::from_predictions(&y, &r.predictions), r.confusion);
    assert_eq!(
        r.weighted_success_rate,
        r.confusion.weighted_success_rate().unwrap()
    );
    assert!(r.weighted_success_rate > 0.7);
    // Same numbers on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let r1 = one.install(|| cross_validate(x.view(), &y, &folds, &p).unwrap());
    assert_eq!(r, r1);
}

/// Eq. 4's parts are undefined without their class: CCS/TS needs a success.
#[test]
fn success_recall_is_undefined_without_successes() {
    let failures_only = Confusion::from_predictions(&[true, true], &[true, false]);
    assert_eq!(failures_only.success_recall(), None);
    assert_eq!(failures_only.weighted_success_rate(), None);
    assert_eq!(failures_only.failure_recall(), Some(0.5));
    assert_eq!(failures_only.accuracy(), Some(0.5));
}

#[test]
fn accuracy_is_undefined_without_samples() {
    assert_eq!(Confusion::default().accuracy(), None);
}

/// Two values: sd = √((0.1² + 0.1²) / 1), se = sd / √2 = 0.1.
#[test]
fn standard_error_of_two_folds_by_hand() {
    let (m, se) = mean_se(&[0.6, 0.8]);
    assert!((m - 0.7).abs() < 1e-15);
    assert!((se - 0.1).abs() < 1e-12, "{se}");
    let (m, se) = mean_se(&[]);
    assert!(m.is_nan() && se.is_nan());
}

/// The dealing rule fixes how many of each class every fold gets, whatever the shuffle:
/// the 77 successes are dealt first from fold 0 (folds 0–6 get 8, folds 7–9 get 7), and
/// the 26 failures continue at fold 7 (folds 7, 8, 9, 0, 1, 2 get 3, the others 2).
/// The smallest legal k (2) and n = k (one sample a fold) are accepted.
#[test]
fn stratified_folds_deal_the_classes_in_turn() {
    let labels: Vec<bool> = (0..103).map(|i| i % 4 == 0).collect();
    for seed in [3, 4] {
        let f = stratified_k_fold(&labels, 10, seed).unwrap();
        let pos: Vec<usize> = (0..10)
            .map(|k| f.test_indices(k).iter().filter(|&&i| labels[i]).count())
            .collect();
        let neg: Vec<usize> = (0..10).map(|k| f.test_indices(k).len() - pos[k]).collect();
        assert_eq!(pos, [3, 3, 3, 2, 2, 2, 2, 3, 3, 3], "seed {seed}");
        assert_eq!(neg, [8, 8, 8, 8, 8, 8, 8, 7, 7, 7], "seed {seed}");
    }
    let two = stratified_k_fold(&labels, 2, 0).unwrap();
    assert_eq!(two.count, 2);
    assert_eq!(
        (two.test_indices(0).len(), two.test_indices(1).len()),
        (52, 51)
    );
    let each = stratified_k_fold(&labels[..4], 4, 0).unwrap();
    assert!((0..4).all(|k| each.test_indices(k).len() == 1));
}

/// Two folds are the fewest: objects of sizes 5, 4, 3, 2 (largest first, each to the
/// lighter fold) give folds of 5 + 2 and 4 + 3 samples.
#[test]
fn leave_objects_out_into_two_folds() {
    let groups: Vec<usize> = [(0, 5), (1, 4), (2, 3), (3, 2)]
        .iter()
        .flat_map(|&(g, n)| std::iter::repeat_n(g, n))
        .collect();
    for seed in 0..4 {
        let f = group_k_fold(&groups, Some(2), seed).unwrap();
        assert_eq!(f.count, 2);
        let mut sizes = [f.test_indices(0).len(), f.test_indices(1).len()];
        sizes.sort_unstable();
        assert_eq!(sizes, [7, 7], "seed {seed}");
        // The two largest objects never share a fold.
        assert_ne!(f.fold_of[0], f.fold_of[5]);
    }
}

#[test]
fn cross_validation_rejects_mismatched_lengths() {
    let x = Array2::<f64>::zeros((6, 2));
    let y = [false, true, false, true, false, true];
    let folds = stratified_k_fold(&y, 2, 0).unwrap();
    let p = LinearSvmParams::default();
    assert!(cross_validate(x.view(), &y[..5], &folds, &p).is_err());
    let short = stratified_k_fold(&y[..4], 2, 0).unwrap();
    assert!(cross_validate(x.view(), &y, &short, &p).is_err());
}

/// Cross validation reuses one set of solver buffers per thread across folds and calls;
/// its decision values must be those of each fold's SVM fitted afresh on the gathered
/// training rows (from the all-data model, as cross validation starts), to the bit, even
/// after a cross validation of another size on the same thread.
#[test]
fn cross_validation_equals_fresh_fits_of_every_fold() {
    let data = |n: usize, d: usize, seed: u64| {
        let mut rng = Rng::new(seed);
        let y: Vec<bool> = (0..n).map(|i| i % 3 == 0).collect();
        let x = Array2::from_shape_fn((n, d), |(i, j)| {
            rng.normal() * (1.0 + j as f64) + if y[i] && j < 2 { 1.0 } else { 0.0 }
        });
        (x, y)
    };
    let p = LinearSvmParams {
        loss: Loss::SquaredHinge,
        ..Default::default()
    };
    let (other_x, other_y) = data(300, 11, 4);
    let (x, y) = data(150, 6, 3);
    let folds = stratified_k_fold(&y, 10, 1).unwrap();
    let other_folds = stratified_k_fold(&other_y, 10, 1).unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let (r, r_again) = one.install(|| {
        let r = cross_validate(x.view(), &y, &folds, &p).unwrap();
        cross_validate(other_x.view(), &other_y, &other_folds, &p).unwrap();
        (r, cross_validate(x.view(), &y, &folds, &p).unwrap())
    });
    assert_eq!(r, r_again);
    let warm = p.fit(x.view(), &y).unwrap();
    for f in 0..folds.count {
        let train = folds.train_indices(f);
        let yt: Vec<bool> = train.iter().map(|&i| y[i]).collect();
        let model = p
            .fit_from(gather(x.view(), &train).view(), &yt, Some(&warm))
            .unwrap();
        for i in folds.test_indices(f) {
            assert_eq!(
                r.decisions[i],
                model.decision(x.row(i)),
                "fold {f} sample {i}"
            );
        }
    }
}
