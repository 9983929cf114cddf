//! The linear SVM: it separates separable data; on a fixed data set its weights agree with
//! references computed another way (a primal Newton solver for the squared hinge, a
//! projected-gradient dual solver for the hinge) and its duality gap closes; class
//! weights, standardisation on the training data only, and errors.

use ndarray::{Array1, Array2};
use tactile_workbench::rng::Rng;
use tactile_workbench::svm::{
    ClassWeight, LinearSvmParams, Loss, Solver, SvmError, SvmWorkspace, gather,
};

/// Two Gaussian clouds in `d` dimensions, `gap` apart along the first axis, with
/// correlated, differently scaled features.
fn clouds(n: usize, d: usize, gap: f64, seed: u64) -> (Array2<f64>, Vec<bool>) {
    let mut rng = Rng::new(seed);
    let mut x = Array2::<f64>::zeros((n, d));
    let mut y = Vec::with_capacity(n);
    for i in 0..n {
        let pos = rng.bernoulli(0.35);
        y.push(pos);
        let shared = rng.normal();
        for j in 0..d {
            x[[i, j]] = (rng.normal() + 0.5 * shared) * (1.0 + j as f64) + 3.0;
        }
        x[[i, 0]] += if pos { gap } else { -gap };
    }
    (x, y)
}

fn accuracy(p: &LinearSvmParams, x: &Array2<f64>, y: &[bool]) -> f64 {
    let m = p.fit(x.view(), y).unwrap();
    let pred = m.predict_all(x.view());
    pred.iter().zip(y).filter(|(a, b)| a == b).count() as f64 / y.len() as f64
}

#[test]
fn separable_data_is_separated() {
    let (x, y) = clouds(200, 4, 8.0, 1);
    for loss in [Loss::Hinge, Loss::SquaredHinge] {
        for solver in [Solver::Auto, Solver::DualCoordinateDescent] {
            for class_weight in [ClassWeight::Uniform, ClassWeight::Balanced] {
                let p = LinearSvmParams {
                    loss,
                    solver,
                    class_weight,
                    c: 10.0,
                    ..Default::default()
                };
                assert_eq!(
                    accuracy(&p, &x, &y),
                    1.0,
                    "{loss:?} {solver:?} {class_weight:?}"
                );
            }
        }
    }
}

/// Weights of the raw-space decision function (weights then intercept).
fn decision(p: &LinearSvmParams, x: &Array2<f64>, y: &[bool]) -> Array1<f64> {
    let m = p.fit(x.view(), y).unwrap();
    assert!(m.converged, "{p:?} did not converge in {} epochs", m.epochs);
    let mut v = m.weights.to_vec();
    v.push(m.intercept);
    Array1::from(v)
}

fn rel_diff(a: &Array1<f64>, b: &Array1<f64>) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    (a - b).iter().fold(0.0f64, |m, v| m.max(v.abs())) / scale
}

#[test]
fn squared_hinge_dual_cd_agrees_with_the_primal_newton_solver() {
    let (x, y) = clouds(150, 5, 1.0, 2);
    for (c, cw) in [
        (1.0, ClassWeight::Balanced),
        (0.1, ClassWeight::Uniform),
        (
            10.0,
            ClassWeight::Custom {
                negative: 1.0,
                positive: 3.0,
            },
        ),
    ] {
        let base = LinearSvmParams {
            loss: Loss::SquaredHinge,
            c,
            class_weight: cw,
            max_epochs: 200_000,
            ..Default::default()
        };
        let newton = decision(
            &LinearSvmParams {
                solver: Solver::PrimalNewton,
                tol: 1e-6,
                ..base.clone()
            },
            &x,
            &y,
        );
        let dcd = decision(
            &LinearSvmParams {
                solver: Solver::DualCoordinateDescent,
                tol: 1e-7,
                ..base.clone()
            },
            &x,
            &y,
        );
        let d = rel_diff(&dcd, &newton);
        assert!(
            d < 1e-4,
            "C = {c}: dual CD and primal Newton weights differ by {d:e} (relative)"
        );
        let a1 = accuracy(
            &LinearSvmParams {
                solver: Solver::PrimalNewton,
                ..base.clone()
            },
            &x,
            &y,
        );
        let a2 = accuracy(
            &LinearSvmParams {
                solver: Solver::DualCoordinateDescent,
                tol: 1e-7,
                ..base
            },
            &x,
            &y,
        );
        assert_eq!(a1, a2);
    }
}

/// Projected gradient on the hinge dual over the augmented, standardised data:
/// min 0.5 αᵀQα − Σα, 0 ≤ α_i ≤ C_i, run to convergence; returns w.
fn hinge_dual_projected_gradient(x: &Array2<f64>, y: &[bool], costs: (f64, f64)) -> Array1<f64> {
    let (n, d) = x.dim();
    // Standardise like the SVM (population sd) and append the bias feature 1.
    let mut z = Array2::<f64>::ones((n, d + 1));
    for j in 0..d {
        let col = x.column(j);
        let mean = col.mean().unwrap();
        let sd = (col.mapv(|v| (v - mean) * (v - mean)).mean().unwrap()).sqrt();
        for i in 0..n {
            z[[i, j]] = (x[[i, j]] - mean) / sd;
        }
    }
    let ys: Vec<f64> = y.iter().map(|&v| if v { 1.0 } else { -1.0 }).collect();
    let upper: Vec<f64> = y
        .iter()
        .map(|&v| if v { costs.1 } else { costs.0 })
        .collect();
    let mut q = z.dot(&z.t());
    for i in 0..n {
        for j in 0..n {
            q[[i, j]] *= ys[i] * ys[j];
        }
    }
    let l = q.diag().sum();
    let mut alpha = Array1::<f64>::zeros(n);
    for _ in 0..2_000_000 {
        let grad = q.dot(&alpha) - 1.0;
        let mut change = 0.0f64;
        for i in 0..n {
            let new = (alpha[i] - grad[i] / l).clamp(0.0, upper[i]);
            change = change.max((new - alpha[i]).abs());
            alpha[i] = new;
        }
        if change < 1e-15 {
            break;
        }
    }
    let mut w = Array1::<f64>::zeros(d + 1);
    for i in 0..n {
        w.scaled_add(alpha[i] * ys[i], &z.row(i));
    }
    w
}

#[test]
fn hinge_dual_cd_agrees_with_a_projected_gradient_reference_and_closes_the_gap() {
    let (x, y) = clouds(80, 3, 1.0, 3);
    let p = LinearSvmParams {
        loss: Loss::Hinge,
        c: 1.0,
        class_weight: ClassWeight::Balanced,
        tol: 1e-8,
        max_epochs: 1_000_000,
        ..Default::default()
    };
    let m = p.fit(x.view(), &y).unwrap();
    assert!(m.converged);
    let gap = (m.primal_objective - m.dual_objective) / m.primal_objective;
    assert!((0.0..1e-6).contains(&gap), "duality gap {gap:e}");
    let reference = hinge_dual_projected_gradient(&x, &y, p.class_costs(&y));
    let d = rel_diff(&m.weights_standardized, &reference);
    assert!(
        d < 1e-4,
        "dual CD and projected gradient differ by {d:e} (relative)"
    );
}

#[test]
fn duality_gap_closes_for_every_solver_on_correlated_features() {
    let (x, y) = clouds(300, 8, 0.7, 4);
    for (loss, solver) in [
        (Loss::SquaredHinge, Solver::PrimalNewton),
        (Loss::SquaredHinge, Solver::DualCoordinateDescent),
        (Loss::Hinge, Solver::DualCoordinateDescent),
    ] {
        let p = LinearSvmParams {
            loss,
            solver,
            tol: 1e-6,
            max_epochs: 1_000_000,
            ..Default::default()
        };
        let m = p.fit(x.view(), &y).unwrap();
        let gap = (m.primal_objective - m.dual_objective) / m.primal_objective;
        assert!(gap.abs() < 1e-4, "{loss:?} {solver:?}: gap {gap:e}");
    }
}

#[test]
fn balanced_class_weights_match_the_definition() {
    let y = [true, false, false, false];
    let p = LinearSvmParams {
        c: 2.0,
        class_weight: ClassWeight::Balanced,
        ..Default::default()
    };
    // weight = N / (2 N_class): positives 4 / 2 = 2, negatives 4 / 6.
    let (neg, pos) = p.class_costs(&y);
    assert!((pos - 4.0).abs() < 1e-12 && (neg - 4.0 / 3.0).abs() < 1e-12);
    let p = LinearSvmParams {
        c: 2.0,
        class_weight: ClassWeight::Custom {
            negative: 0.5,
            positive: 3.0,
        },
        ..Default::default()
    };
    assert_eq!(p.class_costs(&y), (1.0, 6.0));
    // A heavier positive weight moves predictions towards the positive class.
    let (x, y) = clouds(300, 3, 0.3, 5);
    let count = |w: f64| {
        let p = LinearSvmParams {
            class_weight: ClassWeight::Custom {
                negative: 1.0,
                positive: w,
            },
            ..Default::default()
        };
        p.fit(x.view(), &y)
            .unwrap()
            .predict_all(x.view())
            .iter()
            .filter(|v| **v)
            .count()
    };
    assert!(count(5.0) > count(0.2));
}

#[test]
fn standardisation_is_fitted_on_the_training_data_and_reused() {
    let (x, y) = clouds(100, 3, 2.0, 6);
    let m = LinearSvmParams::default().fit(x.view(), &y).unwrap();
    let sc = m.scaler.as_ref().unwrap();
    for j in 0..3 {
        assert!((sc.mean[j] - x.column(j).mean().unwrap()).abs() < 1e-12);
    }
    // The raw-space decision function equals the standardised one.
    for i in 0..10 {
        let row = x.row(i);
        let mut z = [0.0; 4];
        for j in 0..3 {
            z[j] = (row[j] - sc.mean[j]) / sc.sd[j];
        }
        z[3] = 1.0;
        let v: f64 = z
            .iter()
            .zip(m.weights_standardized.iter())
            .map(|(a, b)| a * b)
            .sum();
        assert!((v - m.decision(row)).abs() < 1e-9);
    }
}

#[test]
fn bad_input_is_an_error() {
    let (x, y) = clouds(20, 2, 2.0, 7);
    let p = LinearSvmParams::default();
    assert!(matches!(
        p.fit(x.view(), &[true; 20]),
        Err(SvmError::Data(_))
    ));
    assert!(matches!(p.fit(x.view(), &y[..10]), Err(SvmError::Data(_))));
    let mut nan = x.clone();
    nan[[1, 1]] = f64::INFINITY;
    assert!(matches!(p.fit(nan.view(), &y), Err(SvmError::Data(_))));
    for bad in [
        LinearSvmParams {
            c: 0.0,
            ..Default::default()
        },
        LinearSvmParams {
            bias: -1.0,
            ..Default::default()
        },
        LinearSvmParams {
            tol: 0.0,
            ..Default::default()
        },
        LinearSvmParams {
            max_epochs: 0,
            ..Default::default()
        },
        LinearSvmParams {
            class_weight: ClassWeight::Custom {
                negative: 0.0,
                positive: 1.0,
            },
            ..Default::default()
        },
        LinearSvmParams {
            loss: Loss::Hinge,
            solver: Solver::PrimalNewton,
            ..Default::default()
        },
    ] {
        assert!(
            matches!(bad.fit(x.view(), &y), Err(SvmError::Param(_))),
            "{bad:?}"
        );
    }
}

/// A workspace carries only capacity from one fit to the next: fitting rows of one problem
/// through a workspace that has served a larger and a smaller problem (and the warm start
/// of cross validation) gives, to the bit, the model of a fresh fit of the gathered rows.
#[test]
fn a_reused_workspace_fits_as_a_fresh_one() {
    let p = LinearSvmParams {
        loss: Loss::SquaredHinge,
        ..Default::default()
    };
    let (big_x, big_y) = clouds(300, 12, 0.8, 5);
    let (small_x, small_y) = clouds(90, 3, 0.6, 6);
    let (x, y) = clouds(200, 7, 0.7, 7);
    let rows: Vec<usize> = (0..200).filter(|i| i % 5 != 2).rev().collect();
    let yr: Vec<bool> = rows.iter().map(|&i| y[i]).collect();
    let warm = p.fit(x.view(), &y).unwrap();
    let fresh = p
        .fit_from(gather(x.view(), &rows).view(), &yr, Some(&warm))
        .unwrap();
    assert!(fresh.converged && fresh.epochs > 0);
    let mut ws = SvmWorkspace::default();
    let all = |n: usize| (0..n).collect::<Vec<_>>();
    for (bx, by) in [(&big_x, &big_y), (&small_x, &small_y), (&big_x, &big_y)] {
        p.fit_rows(bx.view(), &all(bx.nrows()), by, None, &mut ws)
            .unwrap();
        let reused = p
            .fit_rows(x.view(), &rows, &yr, Some(&warm), &mut ws)
            .unwrap();
        assert_eq!(reused, fresh);
    }
    // Without standardisation and from zero, too.
    let raw = LinearSvmParams {
        standardize: false,
        ..p.clone()
    };
    let fresh = raw.fit(gather(x.view(), &rows).view(), &yr).unwrap();
    raw.fit_rows(big_x.view(), &all(300), &big_y, None, &mut ws)
        .unwrap();
    assert_eq!(
        raw.fit_rows(x.view(), &rows, &yr, None, &mut ws).unwrap(),
        fresh
    );
    // A row outside the data is an error, not a panic.
    assert!(
        p.fit_rows(x.view(), &[0, 200], &[true, false], None, &mut ws)
            .is_err()
    );
    // A non-finite value is named by its place among the rows fitted.
    let mut bad = x.clone();
    bad[[7, 2]] = f64::NAN;
    let err = p
        .fit_rows(
            bad.view(),
            &[3, 0, 7, 9],
            &[true, false, true, false],
            None,
            &mut ws,
        )
        .unwrap_err();
    assert!(err.to_string().contains("sample 2 feature 2"), "{err}");
}
