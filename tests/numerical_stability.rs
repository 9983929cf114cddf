//! Numerical stability where the methods are pushed to their edges (issue 6): degenerate
//! inputs must give finite, defined values, never NaN.

use ndarray::{Array2, array};
use tactile_workbench::cluster::scores::{ClusterScores, mutual_info, scores};
use tactile_workbench::gp::kernel::LENGTHSCALE_BOUNDS;
use tactile_workbench::gp::{Likelihood, Sogp, SogpParams, Window};
use tactile_workbench::jobs::Progress;
use tactile_workbench::learners::evt::evt_novelty;
use tactile_workbench::learners::{
    Ds, DsParams, Du, DuParams, Gs, GsParams, Gu, GuParams, NoveltyLearner, SequenceClassifier,
};
use tactile_workbench::rng::Rng;
use tactile_workbench::sparse::{
    CodePenalty, DictionaryFit, DictionaryParams, FeatureSign, l1_optimality_violation,
};
use tactile_workbench::svm::kernel_svm::{KernelSvmParams, cross_validate};

// ---------------------------------------------------------------- sparse online GP

fn gp_params(likelihood: Likelihood, capacity: usize, lengthscale: f64) -> SogpParams {
    SogpParams {
        capacity,
        tau: 2,
        lengthscale,
        likelihood,
        adaptation: None,
        ..SogpParams::default()
    }
}

/// Train on `inputs` (one row per step) with a target of the sign/value of the first input
/// and assert after every step that the mean and the predictive variance are finite, the
/// variance positive and, for probit, the probability in [0, 1]. Returns the model.
fn train_checked(p: &SogpParams, dim: usize, inputs: &[Vec<f64>]) -> Sogp {
    let mut gp = Sogp::new(dim, 1, p).unwrap();
    let mut w = Window::new(dim, p.tau);
    for (t, x) in inputs.iter().enumerate() {
        w.push(x);
        gp.observe(w.as_slice());
        let y = if t % 2 == 0 { 1.0 } else { -1.0 };
        gp.update(&[y]);
        gp.observe(w.as_slice());
        let (m, v) = (gp.mean()[0], gp.predictive_variance());
        assert!(m.is_finite(), "step {t}: mean {m}");
        assert!(v.is_finite() && v > 0.0, "step {t}: variance {v}");
        if p.likelihood == Likelihood::Probit {
            let q = gp.probability();
            assert!((0.0..=1.0).contains(&q), "step {t}: probability {q}");
        }
        assert!(gp.n_basis() <= p.capacity);
    }
    assert!(gp.inverse_gram().iter().all(|q| q.is_finite()));
    gp
}

const LIKELIHOODS: [Likelihood; 2] = [Likelihood::Regression, Likelihood::Probit];

#[test]
fn sogp_duplicate_and_constant_inputs_keep_one_basis_vector() {
    for lik in LIKELIHOODS {
        let p = gp_params(lik, 10, 1.0);
        // The same window over and over: after the first, nothing is novel.
        let same = vec![vec![0.7, -0.3]; 200];
        let gp = train_checked(&p, 2, &same);
        assert_eq!(
            gp.n_basis(),
            2,
            "{lik:?}: the start-up window and the steady one"
        );
        let zeros = vec![vec![0.0; 3]; 200];
        let gp = train_checked(&p, 3, &zeros);
        assert_eq!(gp.n_basis(), 1, "{lik:?}: an all-zero stream is one window");
        assert!(gp.inverse_drift() < 1e-9);
    }
}

#[test]
fn sogp_inputs_a_million_apart() {
    for lik in LIKELIHOODS {
        let p = gp_params(lik, 8, 1.0);
        let far: Vec<Vec<f64>> = (0..60).map(|t| vec![1e6 * (t % 7) as f64]).collect();
        let mut gp = train_checked(&p, 1, &far);
        // Far windows share nothing: each is a BV up to the budget and Q stays diagonal.
        assert_eq!(gp.n_basis(), 8);
        assert!(gp.inverse_drift() < 1e-9);
        // A query far from every BV falls back to the prior variance.
        gp.observe(&[5e12, 5e12]);
        let sf2 = p.sigma_f * p.sigma_f;
        assert!((gp.latent_variance() - sf2).abs() < 1e-9);
    }
}

#[test]
fn sogp_lengthscales_at_their_bounds() {
    let mut rng = Rng::new(4);
    let xs: Vec<Vec<f64>> = (0..300).map(|_| vec![rng.normal(), rng.normal()]).collect();
    for lik in LIKELIHOODS {
        for l in [LENGTHSCALE_BOUNDS.0, LENGTHSCALE_BOUNDS.1] {
            let gp = train_checked(&gp_params(lik, 20, l), 2, &xs);
            // Tiny lengthscales make every window novel (K_B ≈ I); huge ones make every
            // window the same point (one BV after the start-up window).
            if l < 1.0 {
                assert_eq!(gp.n_basis(), 20, "{lik:?} l = {l}");
            } else {
                assert!(gp.n_basis() <= 2, "{lik:?} l = {l}: {}", gp.n_basis());
            }
            assert!(gp.inverse_drift() < 1e-6, "{lik:?} l = {l}");
        }
    }
}

#[test]
fn sogp_budget_of_one() {
    let mut rng = Rng::new(8);
    let xs: Vec<Vec<f64>> = (0..500).map(|_| vec![rng.normal()]).collect();
    for lik in LIKELIHOODS {
        let gp = train_checked(&gp_params(lik, 1, 1.0), 1, &xs);
        assert_eq!(gp.n_basis(), 1);
        let q = gp.inverse_gram()[[0, 0]];
        let sf2 = 1.0;
        assert!((q * sf2 - 1.0).abs() < 1e-9, "Q = 1/k* for one BV, got {q}");
    }
}

/// 10 000 updates at the budget (every step a deletion): the inverse stays the inverse,
/// the drift check has run, and no value goes non-finite.
#[test]
fn sogp_ten_thousand_updates() {
    let mut rng = Rng::new(21);
    let xs: Vec<Vec<f64>> = (0..10_000)
        .map(|t| vec![(t as f64 * 0.05).sin() + 0.1 * rng.normal()])
        .collect();
    for lik in LIKELIHOODS {
        let gp = train_checked(&gp_params(lik, 15, 0.5), 1, &xs);
        assert_eq!(gp.seen(), 10_000);
        assert!(
            gp.inverse_drift() < 1e-6,
            "{lik:?}: drift {}",
            gp.inverse_drift()
        );
    }
}

// ---------------------------------------------------------------- learners

fn small_gp(p: &mut SogpParams) {
    p.capacity = 10;
    p.tau = 3;
    if let Some(a) = p.adaptation.as_mut() {
        a.start_after = 5;
    }
}

fn assert_distribution(d: &Array2<f64>, what: &str) {
    for row in d.rows() {
        assert!(
            row.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{what}: {row}"
        );
        assert!((row.sum() - 1.0).abs() < 1e-9, "{what}: {row}");
    }
}

fn supervised() -> Vec<(&'static str, Box<dyn SequenceClassifier>)> {
    let mut ds = DsParams::default();
    small_gp(&mut ds.gp);
    let mut gs = GsParams::default();
    small_gp(&mut gs.gp);
    vec![
        ("DS", Box::new(Ds::new(2, &ds).unwrap())),
        ("GS", Box::new(Gs::new(2, &gs).unwrap())),
    ]
}

#[test]
fn supervised_learners_on_degenerate_sequences() {
    let zeros = Array2::<f64>::zeros((20, 2));
    let one_step = array![[0.4, -0.2]];
    let empty = Array2::<f64>::zeros((0, 2));
    for (name, mut l) in supervised() {
        let (a, b) = (l.add_class().unwrap(), l.add_class().unwrap());
        // Identical grasps labelled with different classes, all-zero and one-step ones.
        for _ in 0..3 {
            l.train_sequence(zeros.view(), a);
            l.train_sequence(zeros.view(), b);
            l.train_sequence(one_step.view(), a);
            l.train_sequence(one_step.view(), b);
        }
        for m in l.models() {
            let k = m.kernel_params();
            assert!(k.lengthscales.iter().all(|v| v.is_finite() && *v > 0.0));
            assert!(k.sigma_f.is_finite() && k.sigma_n.is_finite());
        }
        for seq in [&zeros, &one_step] {
            let d = l.predict_sequence(seq.view());
            assert_eq!(d.nrows(), seq.nrows());
            assert_distribution(&d, name);
            // GS's experts saw the same data, so they tie; DS's do not (each update of one
            // expert pushes the other down, so the order of training matters).
            let last = d.row(d.nrows() - 1);
            if name == "GS" {
                assert!((last[0] - last[1]).abs() < 1e-9, "{name}: {last}");
            }
            assert!(l.decide(d.view()) < 2);
        }
        let d = l.predict_sequence(empty.view());
        assert_eq!(d.nrows(), 0);
    }
}

/// Inputs so large that every expert's Gaussian log-likelihood is −∞ (GS used to return
/// NaN: −∞ − (−∞) in the normalisation).
#[test]
fn learners_on_huge_inputs_stay_nan_free() {
    for big in [1e6, 1e200, f64::MAX] {
        let seq =
            Array2::from_shape_fn((10, 2), |(t, j)| if (t + j) % 2 == 0 { big } else { -big });
        for (name, mut l) in supervised() {
            l.add_class().unwrap();
            l.add_class().unwrap();
            l.train_sequence(seq.view(), 0);
            let d = l.predict_sequence(seq.view());
            assert_distribution(&d, &format!("{name} at {big}"));
        }
        let mut dp = DuParams::default();
        small_gp(&mut dp.ds.gp);
        let mut gp = GuParams::default();
        small_gp(&mut gp.gs.gp);
        let (mut du, mut gu) = (Du::new(2, &dp).unwrap(), Gu::new(2, &gp).unwrap());
        for _ in 0..3 {
            for a in [du.learn(seq.view()).unwrap(), gu.learn(seq.view()).unwrap()] {
                assert!((0.0..=1.0).contains(&a.novelty), "{big}: {a:?}");
            }
        }
    }
}

#[test]
fn unsupervised_learners_on_degenerate_sequences() {
    let zeros = Array2::<f64>::zeros((20, 2));
    let one_step = array![[0.4, -0.2]];
    let mut dp = DuParams::default();
    small_gp(&mut dp.ds.gp);
    let mut gp = GuParams::default();
    small_gp(&mut gp.gs.gp);
    let mut du = Du::new(2, &dp).unwrap();
    let mut gu = Gu::new(2, &gp).unwrap();
    for seq in [&zeros, &zeros, &one_step, &one_step, &zeros] {
        for a in [du.learn(seq.view()).unwrap(), gu.learn(seq.view()).unwrap()] {
            assert!((0.0..=1.0).contains(&a.novelty), "{a:?}");
        }
    }
    // The same grasp again is never a new cluster.
    let before = (du.n_clusters(), gu.n_clusters());
    let a = du.learn(zeros.view()).unwrap();
    assert!(!a.created, "DU: {a:?}");
    let a = gu.learn(zeros.view()).unwrap();
    assert!(!a.created, "GU: {a:?}");
    assert_eq!(before, (du.n_clusters(), gu.n_clusters()));
    for c in 0..gu.n_clusters() {
        for seq in [&zeros, &one_step] {
            let nu = gu.novelty(c, seq.view());
            assert!((0.0..=1.0).contains(&nu), "GU novelty {nu}");
        }
    }
    assert!(du.assign(one_step.view()) < du.n_clusters());
    assert!(gu.assign(one_step.view()) < gu.n_clusters());
}

// ---------------------------------------------------------------- EVT novelty

#[test]
fn evt_novelty_of_extreme_residuals_and_variances() {
    let residuals = [0.0, 1e-300, 1.0, 1e150, 1e300, -1e300, f64::MAX];
    let variances = [1e-300, 0.0, -0.0, -1.0, -1e300, 1.0, 1e300, f64::INFINITY];
    for m in [2, 10, 1_000_000] {
        for &r in &residuals {
            for &v in &variances {
                for n in [1, 3] {
                    let nu = evt_novelty(&vec![r; n], &vec![v; n], m);
                    assert!((0.0..=1.0).contains(&nu), "r {r} v {v} m {m}: {nu}");
                }
            }
        }
        // The limits: a zero residual is not novel, a huge one is, a negative variance
        // counts as no spread.
        assert!(evt_novelty(&[0.0], &[1.0], m) < 0.5);
        assert_eq!(evt_novelty(&[1e300], &[1.0], m), 1.0);
        assert_eq!(evt_novelty(&[1.0], &[-1.0], m), 1.0);
    }
}

// ---------------------------------------------------------------- clustering scores

#[test]
fn cluster_scores_one_cluster_singletons_and_unused_ids() {
    let truth = [0, 0, 0, 1, 1, 2];
    let finite = |s: ClusterScores| {
        assert!(s.purity.is_finite() && s.ari.is_finite() && s.nmi.is_finite());
        s
    };
    // One sample, and one class predicted as singletons.
    let s = finite(scores(&[3], &[7]));
    assert_eq!((s.purity, s.ari, s.nmi), (1.0, 1.0, 1.0));
    let s = finite(scores(&[0; 5], &[0, 1, 2, 3, 4]));
    assert_eq!((s.purity, s.ari, s.nmi), (1.0, 0.0, 0.0));
    // Both one cluster.
    let s = finite(scores(&[4; 6], &[9; 6]));
    assert_eq!((s.purity, s.ari, s.nmi), (1.0, 1.0, 1.0));
    assert_eq!(mutual_info(&[4; 6], &[9; 6]), 0.0);
    // Empty clusters: a k = 10 clustering that used only ids 0, 5 and usize::MAX scores
    // the same as the contiguous one.
    let sparse_ids = [0, 0, 0, 5, 5, usize::MAX];
    let dense = [0, 0, 0, 1, 1, 2];
    assert_eq!(finite(scores(&truth, &sparse_ids)), scores(&truth, &dense));
    let s = scores(&truth, &dense);
    assert_eq!((s.purity, s.ari, s.nmi), (1.0, 1.0, 1.0));
}

// ---------------------------------------------------------------- kernel SVM

fn svm() -> KernelSvmParams {
    KernelSvmParams {
        gamma: 0.5,
        ..KernelSvmParams::default()
    }
}

#[test]
fn svm_one_class_training_predicts_that_class() {
    let x = array![[0.0, 1.0], [1.0, 2.0], [2.0, 0.5]];
    let model = svm().fit(x.view(), &[3, 3, 3]).unwrap();
    // The fallback is visible in the model: one class and no machine.
    assert_eq!(model.classes, vec![3]);
    assert!(model.machines.is_empty());
    assert_eq!(model.predict(array![[9.0, -9.0]].view()).unwrap(), vec![3]);
    // A class with one sample leaves a one-class training fold in 5-fold CV.
    let x = array![[0.0], [0.1], [0.2], [0.3], [5.0]];
    let cv = cross_validate(&svm(), x.view(), &[0, 0, 0, 0, 1], 5, 1).unwrap();
    assert!(cv.accuracy.is_finite() && (0.0..=1.0).contains(&cv.accuracy));
    assert!((cv.accuracy - 0.8).abs() < 1e-12, "{cv:?}");
    // The fold that holds the only sample of class 1 is reported.
    assert_eq!(cv.one_class_folds.len(), 1, "{cv:?}");
    assert_eq!(cv.fold_accuracy[cv.one_class_folds[0]], 0.0);
}

#[test]
fn svm_constant_features() {
    // A constant column (z-score sd 0) next to an informative one, then all constant.
    let x = array![[1.0, 0.0], [1.0, 0.2], [1.0, 3.0], [1.0, 3.2]];
    let y = [0, 0, 1, 1];
    let model = svm().fit(x.view(), &y).unwrap();
    assert_eq!(model.predict(x.view()).unwrap(), y.to_vec());
    assert!(model.machines.iter().all(|m| m.rho.is_finite()));
    let flat = array![[2.0, 2.0], [2.0, 2.0], [2.0, 2.0], [2.0, 2.0]];
    let model = svm().fit(flat.view(), &y).unwrap();
    let m = &model.machines[0];
    assert!(m.rho.is_finite() && m.coef.iter().all(|c| c.is_finite()));
    // Indistinguishable samples: every prediction is one class, the lower id on a tie.
    let pred = model.predict(flat.view()).unwrap();
    assert!(pred.iter().all(|&p| p == pred[0]));
}

#[test]
fn svm_perfectly_separable_data() {
    let mut rng = Rng::new(2);
    let n = 40;
    let x = Array2::from_shape_fn((n, 2), |(i, _)| {
        (if i < n / 2 { -3.0 } else { 3.0 }) + 0.3 * rng.normal()
    });
    let y: Vec<usize> = (0..n).map(|i| usize::from(i >= n / 2)).collect();
    for c in [1.0, 1e6] {
        let p = KernelSvmParams { c, ..svm() };
        let model = p.fit(x.view(), &y).unwrap();
        assert!(model.converged());
        assert_eq!(model.predict(x.view()).unwrap(), y);
        let m = &model.machines[0];
        assert!(m.rho.is_finite() && m.coef.iter().all(|v| v.is_finite()));
        let cv = cross_validate(&p, x.view(), &y, 5, 3).unwrap();
        assert_eq!(cv.accuracy, 1.0);
        assert!(cv.one_class_folds.is_empty());
    }
}

// ---- Sparse coding and dictionary learning at the extremes -----------------------------

/// Patches spanned by a few random directions (so small penalties reconstruct them).
fn patches(n: usize, dim: usize, seed: u64) -> Array2<f64> {
    let mut rng = Rng::new(seed);
    let dirs: Vec<Vec<f64>> = (0..3)
        .map(|_| (0..dim).map(|_| rng.normal()).collect())
        .collect();
    Array2::from_shape_fn((n, dim), |(i, t)| {
        (0..3)
            .map(|j| dirs[j][t] * ((i * 7 + j * 3) % 5) as f64)
            .sum()
    })
}

fn dictionary_params(num_bases: usize, beta: f64, penalty: CodePenalty) -> DictionaryParams {
    DictionaryParams {
        num_bases,
        beta,
        penalty,
        max_iter: 30,
        ..Default::default()
    }
}

/// Learn under both penalties and check every number the fit returns is finite, the norm
/// bound holds, and the codes reconstruct no worse than the zero code.
fn fit_checked(x: &Array2<f64>, num_bases: usize, beta: f64, what: &str) -> Vec<DictionaryFit> {
    [CodePenalty::L1, CodePenalty::EpsilonL1 { epsilon: 0.01 }]
        .into_iter()
        .map(|penalty| {
            let fit = dictionary_params(num_bases, beta, penalty)
                .fit(x.view(), &Progress::new())
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            let d = &fit.dictionary;
            assert!(d.atoms.iter().all(|v| v.is_finite()), "{what}: atoms");
            assert!(fit.codes.iter().all(|v| v.is_finite()), "{what}: codes");
            assert!(fit.objective.is_finite() && fit.objective >= 0.0, "{what}");
            assert!(fit.learning_objective.is_finite(), "{what}");
            for row in d.atoms.rows() {
                assert!(row.dot(&row) <= d.norm_bound * (1.0 + 1e-9), "{what}: norm");
            }
            let zero_code =
                x.rows().into_iter().map(|r| 0.5 * r.dot(&r)).sum::<f64>() / x.nrows() as f64;
            assert!(
                fit.objective <= zero_code * (1.0 + 1e-9) + 1e-12,
                "{what}: F {} above the zero code's {zero_code}",
                fit.objective
            );
            fit
        })
        .collect()
}

#[test]
fn dictionary_learning_on_all_zero_and_partly_zero_patches() {
    let zeros = Array2::<f64>::zeros((20, 12));
    for fit in fit_checked(&zeros, 5, 1.0, "all-zero patches") {
        assert!(fit.codes.iter().all(|&v| v == 0.0));
        assert_eq!(fit.objective, 0.0);
    }
    let mut mixed = patches(30, 12, 3);
    for i in (0..30).step_by(3) {
        mixed.row_mut(i).fill(0.0);
    }
    for fit in fit_checked(&mixed, 6, 0.1, "partly zero patches") {
        for i in (0..30).step_by(3) {
            assert!(
                fit.codes.row(i).iter().all(|&v| v == 0.0),
                "a zero patch's code"
            );
        }
    }
}

#[test]
fn dictionary_learning_on_duplicate_patches_and_more_bases_than_patches() {
    let one = patches(1, 10, 5);
    let dup = Array2::from_shape_fn((25, 10), |(_, t)| one[[0, t]]);
    for fit in fit_checked(&dup, 4, 1e-3, "duplicate patches") {
        // Identical patches get identical codes.
        for i in 1..25 {
            assert_eq!(fit.codes.row(i), fit.codes.row(0));
        }
    }
    let few = patches(6, 8, 7);
    for fit in fit_checked(&few, 50, 1e-3, "K = 50 > 6 patches") {
        assert_eq!(fit.dictionary.num_bases(), 50);
        let r = few.row(0).to_owned() - fit.dictionary.reconstruct(fit.codes.row(0));
        assert!(
            r.dot(&r) < 1e-2 * few.row(0).dot(&few.row(0)),
            "reconstruction"
        );
    }
}

#[test]
fn extreme_beta_and_gamma_stay_finite() {
    let x = patches(40, 12, 9);
    for beta in [1e-6, 1e6] {
        let fits = fit_checked(&x, 8, beta, &format!("beta {beta}"));
        if beta == 1e6 {
            // A penalty far above every |D x| codes everything as zero.
            assert!(fits[0].codes.iter().all(|&v| v == 0.0));
        }
        let d = &fits[0].dictionary;
        for gamma in [0.0, 1e-6, 1e6] {
            let codes = d.encode(x.view(), gamma).unwrap();
            assert!(codes.iter().all(|v| v.is_finite()), "gamma {gamma}");
            if gamma == 1e6 {
                assert!(codes.iter().all(|&v| v == 0.0), "gamma {gamma}");
            }
        }
    }
    // Duplicate bases make the Gram matrix singular: feature-sign still solves exactly.
    let mut fs = FeatureSign::new(3);
    let g = [1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    for gamma in [1e-6, 1.0, 1e6] {
        let mut a = [0.0; 3];
        fs.solve(&g, &[2.0, 2.0, -1.0], gamma, &mut a);
        assert!(a.iter().all(|v| v.is_finite()), "gamma {gamma}: {a:?}");
        assert!(
            l1_optimality_violation(&g, &[2.0, 2.0, -1.0], gamma, &a) < 1e-9 * gamma.max(1.0),
            "gamma {gamma}: {a:?}"
        );
    }
}

#[test]
fn normalisers_scale_values_near_the_float_limit() {
    use tactile_workbench::features::{Normalisation, Normaliser};
    let data = array![
        [1e300, -1.7e308, 1.0],
        [-1e300, 1.7e308, 1.0],
        [3e300, 0.0, 1.0]
    ];
    for kind in [Normalisation::ZScore, Normalisation::MinMax] {
        let n = Normaliser::fit(kind, data.view()).unwrap();
        let out = n.transform(data.view()).unwrap();
        assert!(out.iter().all(|v| v.is_finite()), "{kind:?}: {out}");
        // The two huge columns are not mistaken for constants; the constant one maps to 0.
        for c in 0..2 {
            let col = out.column(c);
            let spread =
                col.fold(f64::MIN, |a, &b| a.max(b)) - col.fold(f64::MAX, |a, &b| a.min(b));
            assert!(spread > 0.99, "{kind:?} column {c}: {col}");
        }
        assert!(out.column(2).iter().all(|&v| v == 0.0));
    }
    let n = Normaliser::fit(Normalisation::MinMax, data.view()).unwrap();
    let out = n.transform(data.view()).unwrap();
    assert!((out[[1, 1]] - 1.0).abs() < 1e-12 && out[[0, 1]].abs() < 1e-12);
}
