use ndarray::Array2;
use tactile_workbench::gp::{KernelParams, Likelihood, RecursiveArd, Sogp, SogpParams, Window};
use tactile_workbench::linalg::Cholesky;
use tactile_workbench::rng::Rng;

fn regression(capacity: usize, tau: usize) -> SogpParams {
    SogpParams {
        capacity,
        tau,
        novelty_eps: 0.0,
        lengthscale: 0.8,
        sigma_rho: 1.01,
        sigma_f: 1.2,
        sigma_n: 0.3,
        likelihood: Likelihood::Regression,
        adaptation: None,
    }
}

/// Windows of a random input sequence and a smooth target of the newest two lags.
fn data(n: usize, dim: usize, tau: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<f64>) {
    let mut rng = Rng::new(seed);
    let mut w = Window::new(dim, tau);
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let x: Vec<f64> = (0..dim).map(|_| rng.normal()).collect();
        w.push(&x);
        let s = w.as_slice();
        let m = s.len();
        ys.push((s[m - 1]).sin() + 0.5 * s[m - dim - 1] + 0.05 * rng.normal());
        xs.push(s.to_vec());
    }
    (xs, ys)
}

#[test]
fn budget_at_least_n_gives_the_exact_gp_posterior() {
    let (dim, tau, n) = (2, 3, 25);
    let p = regression(40, tau);
    let (xs, ys) = data(n, dim, tau, 3);
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    for (x, y) in xs.iter().zip(&ys) {
        gp.observe(x);
        gp.update(&[*y]);
    }
    assert_eq!(gp.n_basis(), n);
    let k = RecursiveArd::new(dim, tau, p.kernel_params(dim)).unwrap();
    let sn2 = p.sigma_n * p.sigma_n;
    let gram = Array2::from_shape_fn((n, n), |(i, j)| {
        k.eval(&xs[i], &xs[j]) + if i == j { sn2 } else { 0.0 }
    });
    let chol = Cholesky::new(gram.view()).unwrap();
    let alpha = chol.solve(ndarray::ArrayView1::from(&ys)).unwrap();
    let (tests, _) = data(10, dim, tau, 99);
    for t in &tests {
        let kv = ndarray::Array1::from_iter(xs.iter().map(|x| k.eval(x, t)));
        let mean = kv.dot(&alpha);
        let var = k.eval(t, t) - kv.dot(&chol.solve(kv.view()).unwrap());
        gp.observe(t);
        assert!(
            (gp.mean()[0] - mean).abs() < 1e-8,
            "{} vs {mean}",
            gp.mean()[0]
        );
        assert!((gp.latent_variance() - var).abs() < 1e-8);
        assert!((gp.predictive_variance() - var - sn2).abs() < 1e-8);
    }
}

fn assert_q_inverts_gram(gp: &Sogp, dim: usize, tau: usize) {
    let (bv, _) = gp.basis();
    let k = RecursiveArd::new(dim, tau, gp.kernel_params().clone()).unwrap();
    let n = bv.nrows();
    let gram = Array2::from_shape_fn((n, n), |(i, j)| {
        k.eval(bv.row(i).as_slice().unwrap(), bv.row(j).as_slice().unwrap())
    });
    let prod = gram.dot(&gp.inverse_gram());
    for i in 0..n {
        for j in 0..n {
            let e = if i == j { 1.0 } else { 0.0 };
            assert!(
                (prod[[i, j]] - e).abs() < 1e-6,
                "K Q at {i},{j}: {}",
                prod[[i, j]]
            );
        }
    }
}

#[test]
fn budget_deletion_keeps_q_the_inverse_gram_and_predicts_well() {
    let (dim, tau) = (1, 2);
    let mut p = regression(12, tau);
    p.novelty_eps = 1e-5;
    p.sigma_n = 0.1;
    let (xs, ys) = data(300, dim, tau, 5);
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    for (x, y) in xs.iter().zip(&ys) {
        gp.observe(x);
        gp.update(&[*y]);
        assert!(gp.n_basis() <= 12);
    }
    assert_eq!(gp.n_basis(), 12);
    assert_q_inverts_gram(&gp, dim, tau);
    let (tests, truth) = data(200, dim, tau, 11);
    let mut se = 0.0;
    let mut base = 0.0;
    let mean_y = truth.iter().sum::<f64>() / truth.len() as f64;
    for (t, y) in tests.iter().zip(&truth) {
        gp.observe(t);
        se += (gp.mean()[0] - y).powi(2);
        base += (mean_y - y).powi(2);
    }
    assert!(
        se < 0.2 * base,
        "12 BVs should explain most variance: {se} vs {base}"
    );
}

#[test]
fn deleting_a_near_duplicate_bv_barely_changes_the_posterior() {
    let (dim, tau) = (1, 1);
    let p = regression(10, tau);
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    let xs = [-2.0, -1.0, 0.0, 1.0, 1.02, 2.0];
    for x in xs {
        gp.observe(&[x]);
        gp.update(&[x.sin()]);
    }
    let probe: Vec<f64> = (0..20).map(|i| -2.5 + 0.25 * i as f64).collect();
    let before: Vec<(f64, f64)> = probe
        .iter()
        .map(|x| {
            gp.observe(&[*x]);
            (gp.mean()[0], gp.latent_variance())
        })
        .collect();
    gp.delete(4);
    assert_eq!(gp.n_basis(), 5);
    assert_q_inverts_gram(&gp, dim, tau);
    for (x, (m, v)) in probe.iter().zip(before) {
        gp.observe(&[*x]);
        assert!(
            (gp.mean()[0] - m).abs() < 2e-3,
            "mean at {x}: {} vs {m}",
            gp.mean()[0]
        );
        assert!(
            (gp.latent_variance() - v).abs() < 0.05 * v,
            "var at {x}: {} vs {v}",
            gp.latent_variance()
        );
    }
    // Deleting an informative BV does lose information there.
    gp.observe(&[-2.0]);
    let v = gp.latent_variance();
    gp.delete(0);
    gp.observe(&[-2.0]);
    assert!(
        gp.latent_variance() > v + 0.05,
        "{} vs {v}",
        gp.latent_variance()
    );
}

#[test]
fn regression_hyper_gradient_matches_finite_differences() {
    let (dim, tau, n) = (2, 3, 15);
    let p = regression(30, tau);
    let (xs, ys) = data(n + 1, dim, tau, 21);
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    for (x, y) in xs.iter().zip(&ys).take(n) {
        gp.observe(x);
        gp.update(&[*y]);
    }
    let (x, y) = (&xs[n], [ys[n]]);
    let (_, grad) = gp.log_predictive_gradient(x, &y);
    let theta = gp.kernel_params().theta();
    let h = 1e-5;
    for j in 0..theta.len() {
        let at = |delta: f64| {
            let mut t = theta.clone();
            t[j] += delta;
            let mut g = gp.clone();
            g.set_kernel_params(KernelParams::from_theta(&t));
            assert_eq!(g.n_basis(), n);
            g.log_predictive_gradient(x, &y).0
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        assert!(
            (fd - grad[j]).abs() < 1e-5 * (1.0 + fd.abs()),
            "theta[{j}]: analytic {} vs finite difference {fd}",
            grad[j]
        );
    }
}

#[test]
fn probit_model_separates_two_regions_and_stays_finite() {
    let (dim, tau) = (2, 1);
    let p = SogpParams {
        tau,
        capacity: 20,
        likelihood: Likelihood::Probit,
        adaptation: None,
        ..SogpParams::default()
    };
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    let mut rng = Rng::new(4);
    for _ in 0..200 {
        let x = [rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)];
        let y = if x[0] + x[1] > 0.0 { 1.0 } else { -1.0 };
        gp.observe(&x);
        gp.update(&[y]);
    }
    // Far-away confident mistakes must not produce NaN (the ratio N/Φ stays finite).
    for _ in 0..20 {
        gp.observe(&[2.5, 2.5]);
        gp.update(&[-1.0]);
        gp.observe(&[2.5, 2.5]);
        gp.update(&[1.0]);
    }
    let mut correct = 0;
    for _ in 0..200 {
        let x = [rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)];
        gp.observe(&x);
        let q = gp.probability();
        assert!(q.is_finite() && (0.0..=1.0).contains(&q));
        correct += usize::from((q > 0.5) == (x[0] + x[1] > 0.0));
    }
    assert!(correct > 180, "{correct}/200");
    assert!(gp.n_basis() <= 20);
}

/// Squared error of `gp`'s mean on held-out windows (no training on them).
fn held_out_error(gp: &mut Sogp, tests: &[Vec<f64>], truth: &[f64]) -> f64 {
    tests
        .iter()
        .zip(truth)
        .map(|(t, y)| {
            gp.observe(t);
            (gp.mean()[0] - y).powi(2)
        })
        .sum()
}

/// A lengthscale of 0.05 is far too short for a smooth target of unit-scale inputs: the
/// fixed model barely generalises. Adapting the hyperparameters must lengthen it over more
/// than one step and predict held-out data better than the same model without adaptation.
#[test]
fn adaptation_runs_keeps_bounds_and_improves_a_misspecified_lengthscale() {
    let (dim, tau) = (1, 2);
    let sngd = tactile_workbench::gp::SngdParams {
        start_after: 30,
        ..Default::default()
    };
    let mut p = regression(25, tau);
    p.novelty_eps = 1e-5;
    p.lengthscale = 0.05;
    p.sigma_n = 0.1;
    let (xs, ys) = data(900, dim, tau, 8);
    let (tests, truth) = data(200, dim, tau, 12);
    let mut fixed = Sogp::new(dim, 1, &p).unwrap();
    p.adaptation = Some(sngd);
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    for (x, y) in xs.iter().zip(&ys) {
        for m in [&mut gp, &mut fixed] {
            m.observe(x);
            m.update(&[*y]);
            assert!(m.mean()[0].is_finite());
        }
    }
    let l = gp.kernel_params().lengthscales[0];
    assert!(gp.hyper_updates() > 1, "{} updates", gp.hyper_updates());
    assert!(l > 0.06, "lengthscale should grow from 0.05, got {l}");
    assert!(gp.kernel_params().sigma_rho >= 0.5 && gp.kernel_params().sigma_rho <= 1.1);
    let adapted = held_out_error(&mut gp, &tests, &truth);
    let unadapted = held_out_error(&mut fixed, &tests, &truth);
    assert!(
        adapted < unadapted,
        "held-out squared error {adapted} adapted against {unadapted} fixed"
    );
}

#[test]
fn bad_parameters_are_errors() {
    let p = SogpParams {
        capacity: 0,
        ..SogpParams::default()
    };
    assert!(
        Sogp::new(3, 1, &p)
            .unwrap_err()
            .to_string()
            .contains("capacity")
    );
    let p = SogpParams::default();
    assert!(
        Sogp::new(3, 2, &p)
            .unwrap_err()
            .to_string()
            .contains("n_out")
    );
    let p = SogpParams {
        sigma_n: f64::NAN,
        ..SogpParams::default()
    };
    assert!(
        Sogp::new(3, 1, &p)
            .unwrap_err()
            .to_string()
            .contains("sigma_n")
    );
}
