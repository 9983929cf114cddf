use ndarray::Array2;
use tactile_workbench::gp::{SngdParams, Window};
use tactile_workbench::learners::{Ds, DsParams, Gs, GsParams, SequenceClassifier, lengthscales};
use tactile_workbench::rng::Rng;

/// Three classes of 2-D sequences: noisy ramps with class-specific slopes and offsets.
fn sequence(class: usize, rng: &mut Rng) -> Array2<f64> {
    let t_len = 12 + rng.below(5);
    Array2::from_shape_fn((t_len, 2), |(t, d)| {
        let x = t as f64 / t_len as f64;
        let slope = [0.2, 0.6, 0.9][class];
        let offset = [0.1, 0.3, 0.0][class];
        let v = if d == 0 {
            offset + slope * x
        } else {
            0.5 - 0.4 * slope * x
        };
        v + 0.02 * rng.normal()
    })
}

fn run(learner: &mut dyn SequenceClassifier, seed: u64) -> (f64, Vec<Vec<f64>>) {
    let mut rng = Rng::new(seed);
    for _ in 0..3 {
        learner.add_class().unwrap();
    }
    for _ in 0..6 {
        for c in 0..3 {
            let s = sequence(c, &mut rng);
            learner.train_sequence(s.view(), c);
        }
    }
    let mut correct = 0;
    let mut first = Vec::new();
    for i in 0..30 {
        let c = i % 3;
        let s = sequence(c, &mut rng);
        let dist = learner.predict_sequence(s.view());
        assert_eq!(dist.dim(), (s.nrows(), 3));
        for row in dist.rows() {
            assert!(row.iter().all(|p| p.is_finite() && *p >= 0.0));
            assert!((row.sum() - 1.0).abs() < 1e-9);
        }
        if i == 0 {
            first = dist.rows().into_iter().map(|r| r.to_vec()).collect();
        }
        correct += usize::from(learner.decide(dist.view()) == c);
    }
    (correct as f64 / 30.0, first)
}

/// ln N(o | mean, var·I), eq. 30 written out as a sum of 1-D normal log-densities.
fn gaussian(_: usize, o: &[f64], mean: &[f64], var: f64) -> f64 {
    o.iter()
        .zip(mean)
        .map(|(x, m)| {
            -0.5 * (2.0 * std::f64::consts::PI * var).ln() - (x - m).powi(2) / (2.0 * var)
        })
        .sum()
}

fn small(mut p: tactile_workbench::gp::SogpParams) -> tactile_workbench::gp::SogpParams {
    p.tau = 4;
    p.capacity = 20;
    p.adaptation = Some(SngdParams {
        start_after: 40,
        ..Default::default()
    });
    p
}

#[test]
fn ds_learns_three_classes_deterministically() {
    let mut p = DsParams::default();
    p.gp = small(p.gp);
    let (acc, first) = run(&mut Ds::new(2, &p).unwrap(), 1);
    assert!(acc >= 0.9, "DS accuracy {acc}");
    let (acc2, first2) = run(&mut Ds::new(2, &p).unwrap(), 1);
    assert_eq!((acc, first), (acc2, first2), "same seed, same numbers");
}

#[test]
fn gs_learns_three_classes_and_its_filter_sharpens() {
    let mut p = GsParams::default();
    p.gp = small(p.gp);
    let mut gs = Gs::new(2, &p).unwrap();
    let (acc, first) = run(&mut gs, 2);
    assert!(acc >= 0.9, "GS accuracy {acc}");
    // The Bayes filter accumulates evidence: the true class (0) gains over the grasp.
    assert!(first.last().unwrap()[0] > first[0][0], "{first:?}");
    assert!(gs.models().iter().all(|m| m.n_basis() <= 20));
    // Eq. 29 from a uniform prior: the posterior after step t is the normalised product of
    // the steps' likelihoods (eq. 30: independent Gaussians of the noisy predictive
    // variance), so it sharpens as steps agree; a filter that forgot its past would not.
    let mut rng = Rng::new(9);
    for c in 0..3 {
        let s = sequence(c, &mut rng);
        let post = gs.predict_sequence(s.view());
        let t_len = s.nrows();
        for t in [1, t_len / 2, t_len] {
            let summed =
                gs.summed_log_likelihoods(s.slice(ndarray::s![..t, ..]), &[0, 1, 2], gaussian);
            let top = summed.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let z: f64 = summed.iter().map(|l| (l - top).exp()).sum();
            for (j, l) in summed.iter().enumerate() {
                let want = (l - top).exp() / z;
                assert!(
                    (post[[t - 1, j]] - want).abs() < 1e-9,
                    "class {c}, step {t}, expert {j}: {} against {want}",
                    post[[t - 1, j]]
                );
            }
        }
    }
}

#[test]
fn untrained_learners_give_uniform_distributions() {
    let mut ds = Ds::new(2, &DsParams::default()).unwrap();
    let mut gs = Gs::new(2, &GsParams::default()).unwrap();
    let s = Array2::from_elem((5, 2), 0.3);
    for l in [&mut ds as &mut dyn SequenceClassifier, &mut gs] {
        for _ in 0..4 {
            l.add_class().unwrap();
        }
        let dist = l.predict_sequence(s.view());
        assert!(dist.iter().all(|p| (p - 0.25).abs() < 1e-12));
    }
}

#[test]
fn wrong_likelihood_is_a_parameter_error() {
    let mut p = DsParams::default();
    p.gp.likelihood = tactile_workbench::gp::Likelihood::Regression;
    let e = Ds::new(2, &p).unwrap_err().to_string();
    assert!(e.contains("likelihood"), "{e}");
    let mut p = GsParams::default();
    p.gp.capacity = 0;
    assert!(Gs::new(2, &p).unwrap_err().to_string().contains("capacity"));
    // One input dimension, so that a probit expert (one output) would build: GS itself
    // must refuse the likelihood.
    let mut p = GsParams::default();
    p.gp.likelihood = tactile_workbench::gp::Likelihood::Probit;
    let e = Gs::new(1, &p).unwrap_err().to_string();
    assert!(e.contains("gp.likelihood"), "{e}");
}

/// The step interface (what `bench-recognition` times) gives the distributions of the
/// sequence methods, and training step by step leaves the learner where training by
/// sequence does, bit for bit.
#[test]
fn steps_one_at_a_time_equal_the_sequence_methods() {
    let (mut ds, mut gs) = (DsParams::default(), GsParams::default());
    ds.gp = small(ds.gp);
    gs.gp = small(gs.gp);
    let learners: [Box<dyn SequenceClassifier>; 2] = [
        Box::new(Ds::new(2, &ds).unwrap()),
        Box::new(Gs::new(2, &gs).unwrap()),
    ];
    for mut by_seq in learners {
        for _ in 0..3 {
            by_seq.add_class().unwrap();
        }
        let mut rng = Rng::new(5);
        let seqs: Vec<(usize, Array2<f64>)> = (0..24)
            .map(|i| (i % 3, sequence(i % 3, &mut rng)))
            .collect();
        let mut by_step = clone_of(&*by_seq, &ds, &gs);
        for (c, s) in &seqs {
            let want = by_seq.predict_sequence(s.view());
            by_step.start_sequence();
            for (o, row) in s.rows().into_iter().zip(want.rows()) {
                let mut dist = vec![0.0; 3];
                by_step.predict_step(o.as_slice().unwrap(), &mut dist);
                let got: Vec<u64> = dist.iter().map(|p| p.to_bits()).collect();
                let want: Vec<u64> = row.iter().map(|p| p.to_bits()).collect();
                assert_eq!(got, want);
            }
            by_seq.train_sequence(s.view(), *c);
            by_step.start_sequence();
            for o in s.rows() {
                by_step.train_step(o.as_slice().unwrap(), *c);
            }
        }
        for (a, b) in by_seq.models().iter().zip(by_step.models()) {
            assert_eq!(a.basis(), b.basis());
            assert_eq!(a.kernel_params(), b.kernel_params());
        }
    }
}

/// A fresh learner of the same kind with the same number of (untrained) classes.
fn clone_of(
    l: &dyn SequenceClassifier,
    ds: &DsParams,
    gs: &GsParams,
) -> Box<dyn SequenceClassifier> {
    let mut c: Box<dyn SequenceClassifier> = match l.models()[0].n_out() {
        1 => Box::new(Ds::new(2, ds).unwrap()),
        _ => Box::new(Gs::new(2, gs).unwrap()),
    };
    for _ in 0..l.n_classes() {
        c.add_class().unwrap();
    }
    c
}

/// A sequence predicted expert by expert (`predict_sequence`) gives, bit for bit, what the
/// step-by-step interface gives, every expert observing each step in turn; and training
/// in between (adaptation on) keeps them equal.
#[test]
fn whole_sequence_prediction_equals_the_steps() {
    for gs in [false, true] {
        let mut rng = Rng::new(4);
        let mut learner: Box<dyn SequenceClassifier> = if gs {
            let mut p = GsParams::default();
            p.gp = small(p.gp);
            Box::new(Gs::new(2, &p).unwrap())
        } else {
            let mut p = DsParams::default();
            p.gp = small(p.gp);
            Box::new(Ds::new(2, &p).unwrap())
        };
        for _ in 0..3 {
            learner.add_class().unwrap();
        }
        for i in 0..24 {
            let c = i % 3;
            let s = sequence(c, &mut rng);
            let whole = learner.predict_sequence(s.view());
            learner.start_sequence();
            let mut dist = [0.0; 3];
            for (t, o) in s.rows().into_iter().enumerate() {
                learner.predict_step(o.as_slice().unwrap(), &mut dist);
                for (a, b) in whole.row(t).iter().zip(&dist) {
                    assert_eq!(a.to_bits(), b.to_bits(), "sequence {i}, step {t}");
                }
            }
            learner.train_sequence(s.view(), c);
        }
    }
}

/// `q` is eq. 24's q_c = Φ(μ_c/σ_c) of every expert at the last step taken one at a time,
/// and the step's distribution is q normalised (eq. 26).
#[test]
fn ds_q_is_every_experts_probit_at_the_last_step() {
    let mut p = DsParams::default();
    p.gp = small(p.gp);
    let mut ds = Ds::new(2, &p).unwrap();
    for _ in 0..3 {
        ds.add_class().unwrap();
    }
    let mut rng = Rng::new(6);
    for i in 0..6 {
        let s = sequence(i % 3, &mut rng);
        ds.train_sequence(s.view(), i % 3);
    }
    let s = sequence(1, &mut rng);
    ds.start_sequence();
    let mut dist = [0.0; 3];
    for o in s.rows() {
        ds.predict_step(o.as_slice().unwrap(), &mut dist);
    }
    let want: Vec<f64> = ds.models().iter().map(|m| m.probability()).collect();
    assert_eq!(ds.q(), want);
    assert!(want.iter().all(|&q| q > 0.0 && q < 1.0), "{want:?}");
    let sum: f64 = want.iter().sum();
    for (p, q) in dist.iter().zip(&want) {
        assert!((p - q / sum).abs() < 1e-15, "{dist:?} against {want:?}");
    }
}

/// `lengthscales` has a row per expert and a column per input dimension, each row the
/// expert's (adapted) lengthscales.
#[test]
fn lengthscales_are_one_row_per_expert_and_one_column_per_input() {
    let (mut ds, mut gs) = (DsParams::default(), GsParams::default());
    ds.gp = small(ds.gp);
    gs.gp = small(gs.gp);
    let learners: [Box<dyn SequenceClassifier>; 2] = [
        Box::new(Ds::new(2, &ds).unwrap()),
        Box::new(Gs::new(2, &gs).unwrap()),
    ];
    for mut l in learners {
        run(&mut *l, 3);
        let ls = lengthscales(&*l);
        assert_eq!(ls.dim(), (3, 2));
        for (row, m) in ls.rows().into_iter().zip(l.models()) {
            assert_eq!(row.to_vec(), m.kernel_params().lengthscales.to_vec());
        }
    }
}

/// GS trained on three classes of `sequence`.
fn trained_gs(seed: u64) -> Gs {
    let mut p = GsParams::default();
    p.gp = small(p.gp);
    let mut gs = Gs::new(2, &p).unwrap();
    for _ in 0..3 {
        gs.add_class().unwrap();
    }
    let mut rng = Rng::new(seed);
    for i in 0..9 {
        let s = sequence(i % 3, &mut rng);
        gs.train_sequence(s.view(), i % 3);
    }
    gs
}

/// An expert's predictions are one row of means and one predictive variance per step, each
/// the expert's prediction from the window of the steps before it (the module's rule, the
/// first window all padding), taken here one window at a time; an empty sequence, or one
/// whose width is not the learner's, gives none.
#[test]
fn expert_predictions_are_one_per_step_from_the_window_before_it() {
    let mut gs = trained_gs(7);
    let s = sequence(2, &mut Rng::new(17));
    let (means, vars) = gs.expert_predictions(1, s.view());
    assert_eq!(means.dim(), (s.nrows(), 2));
    assert_eq!(vars.len(), s.nrows());
    let mut expert = gs.models()[1].clone();
    let mut window = Window::new(2, expert.kernel().tau());
    for (t, o) in s.rows().into_iter().enumerate() {
        expert.observe_window(&window);
        for (got, want) in means.row(t).iter().zip(expert.mean()) {
            assert!(
                (got - want).abs() < 1e-12,
                "step {t}: mean {got} against {want}"
            );
        }
        let want = expert.predictive_variance();
        assert!(
            (vars[t] - want).abs() < 1e-12,
            "step {t}: variance {} against {want}",
            vars[t]
        );
        window.push(o.as_slice().unwrap());
    }
    for none in [Array2::zeros((0, 2)), Array2::zeros((4, 3))] {
        let (means, vars) = gs.expert_predictions(1, none.view());
        assert_eq!((means.nrows(), vars.len()), (0, 0));
    }
}

/// A step so far from every expert that each gives it likelihood 0 (inputs of 1e200: ln p
/// = −∞) carries no evidence. The filter (eq. 29) keeps the posterior of the step before
/// instead of forming 0/0, and the summed log-likelihoods are those of the steps before.
#[test]
fn gs_skips_a_step_that_no_expert_explains() {
    let mut gs = trained_gs(8);
    let mut s = sequence(1, &mut Rng::new(18));
    let t_len = s.nrows();
    s.row_mut(t_len - 1).fill(1e200);
    let post = gs.predict_sequence(s.view());
    for (got, want) in post.row(t_len - 1).iter().zip(post.row(t_len - 2)) {
        assert!((got - want).abs() < 1e-12, "{got} against {want}");
    }
    assert!((post.row(t_len - 1).sum() - 1.0).abs() < 1e-12);
    let all = gs.summed_log_likelihoods(s.view(), &[0, 1, 2], gaussian);
    let before =
        gs.summed_log_likelihoods(s.slice(ndarray::s![..t_len - 1, ..]), &[0, 1, 2], gaussian);
    for (got, want) in all.iter().zip(&before) {
        assert!(
            want.is_finite() && (got - want).abs() < 1e-9 * want.abs(),
            "{got} against {want}"
        );
    }
}
