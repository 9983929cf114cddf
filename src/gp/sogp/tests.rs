use super::gram::{GradBuffers, tri};
use super::*;

/// The training path keeps the Gram derivatives incrementally (new rows from the
/// observation's derivatives, swaps on deletion, compaction on rebuild) and reuses the
/// observation's per-lag kernel values; after every update, through deletions and
/// hyperparameter rebuilds, both must equal a fresh computation, and so must the
/// gradient (which tests/gp_sogp.rs checks against finite differences).
#[test]
fn cached_gradient_terms_equal_a_fresh_computation() {
    for likelihood in [Likelihood::Probit, Likelihood::Regression] {
        let p = SogpParams {
            capacity: 6,
            tau: 3,
            likelihood,
            adaptation: Some(SngdParams {
                window: 4,
                start_after: 8,
                stop_count: 1000,
                ..SngdParams::default()
            }),
            ..SogpParams::default()
        };
        let (dim, tau) = (2, 3);
        let mut gp = Sogp::new(dim, 1, &p).unwrap();
        let mut checked = 0;
        for t in 0..400 {
            let f = t as f64;
            let mut x = [0.0; 6];
            // Every fifth window starts with a padding lag.
            for (i, v) in x
                .iter_mut()
                .enumerate()
                .skip(if t % 5 == 0 { dim } else { 0 })
            {
                *v = (0.37 * f + 1.3 * i as f64).sin();
            }
            let y = if (0.11 * f).sin() > 0.0 { 1.0 } else { -1.0 };
            if let Some(ad) = gp.adapt.as_ref() {
                // The gradient the next update will take, from the cached terms.
                let mut g = gp.clone();
                g.observe(&x);
                g.y_tmp[0] = y;
                let (_, ds, _) = g.likelihood_terms().unwrap();
                let mut buf = ad.buf.clone();
                g.gradient(&mut buf, ds);
                let (_, fresh) = g.log_predictive_gradient(&x, &[y]);
                for (a, b) in buf.grad.iter().zip(&fresh) {
                    assert!(
                        (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                        "step {t}: {a} vs {b}"
                    );
                }
            }
            gp.observe(&x);
            gp.update(&[y]);
            if let Some(ad) = gp.adapt.as_ref() {
                let mut fresh = GradBuffers::new(dim, tau, gp.stride, gp.basis.stride());
                gp.fill_gram_derivatives(&mut fresh);
                let pk = fresh.pk;
                for i in 0..gp.n {
                    for j in 0..=i {
                        for q in 0..pk {
                            let at = tri(i, j) * pk + q;
                            assert_eq!(ad.buf.kb[at], fresh.kb[at], "step {t}, pair ({i}, {j})");
                        }
                    }
                }
                checked += 1;
            }
        }
        assert!(gp.seen() > 2 * p.capacity && gp.n_basis() == p.capacity);
        assert!(gp.hyper_updates() >= 20, "{}", gp.hyper_updates());
        assert!(checked > 300);
    }
}

/// The kernel vector and the per-lag K_t of an observation, looked up from the
/// distance rows of the distinct inputs, equal the direct evaluation of every pair bit
/// for bit: along sequences (shifted windows), at their starts (padding lags), on a
/// window observed twice, with inputs repeated across sequences, through deletions and
/// hyperparameter rebuilds.
#[test]
fn kernel_from_input_rows_equals_the_direct_evaluation() {
    use crate::gp::Window;
    let (dim, tau) = (3, 4);
    let p = SogpParams {
        capacity: 9,
        tau,
        adaptation: Some(SngdParams {
            window: 4,
            start_after: 12,
            stop_count: 1000,
            ..SngdParams::default()
        }),
        ..SogpParams::default()
    };
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    let mut window = Window::new(dim, tau);
    let mut checked = 0;
    for t in 0..900 {
        if t % 11 == 0 {
            window.reset();
        }
        // Inputs on a coarse grid, so that sequences share inputs.
        let x: Vec<f64> = (0..dim)
            .map(|k| ((0.37 * t as f64 + 1.3 * k as f64).sin() * 2.0).round() / 2.0)
            .collect();
        window.push(&x);
        for _ in 0..1 + usize::from(t % 7 == 0) {
            gp.observe(window.as_slice());
            let mut xs = vec![0.0; gp.wlen];
            gp.kernel.scale_into(window.as_slice(), &mut xs);
            // The BVs' lag-major store, built afresh.
            let mut basis = LagMajor::new(dim, tau, gp.stride);
            for i in 0..gp.n {
                basis.set(i, gp.bv(i));
            }
            let lanes = basis.stride();
            let (mut lag_k, mut k) = (vec![0.0; tau * lanes], vec![0.0; lanes]);
            gp.kernel.unit_many(&xs, &basis, gp.n, &mut lag_k, &mut k);
            let sf2 = gp.kernel.sigma_f2();
            for i in 0..gp.n {
                let direct = sf2 * gp.kernel.unit_scaled(&xs, gp.bv(i));
                assert_eq!(gp.k[i].to_bits(), direct.to_bits(), "step {t}, BV {i}");
                for lag in 0..tau {
                    let at = lag * lanes + i;
                    assert_eq!(gp.lag_k[at].to_bits(), lag_k[at].to_bits(), "step {t}");
                }
            }
            checked += gp.n;
        }
        gp.update(&[if (0.23 * t as f64).cos() > 0.0 {
            1.0
        } else {
            -1.0
        }]);
    }
    assert!(gp.n_basis() == p.capacity && gp.hyper_updates() >= 20);
    assert!(checked > 5000, "{checked}");
}

/// Observing a window by its stamp computes what comparing the windows computes, bit
/// for bit: along sequences, at a window observed twice, after steps the model sat out
/// (not a shift by one), after a reset, and from a copy of the window that went on with
/// other inputs (its stamp must not pass for the original's).
#[test]
fn stamped_windows_observe_what_compared_windows_do() {
    use crate::gp::Window;
    let (dim, tau) = (2, 3);
    let p = SogpParams {
        capacity: 6,
        tau,
        adaptation: Some(SngdParams {
            window: 4,
            start_after: 8,
            stop_count: 1000,
            ..SngdParams::default()
        }),
        ..SogpParams::default()
    };
    let mut by_slice = Sogp::new(dim, 1, &p).unwrap();
    let mut by_stamp = by_slice.clone();
    let mut window = Window::new(dim, tau);
    let mut copy = window.clone();
    let mut compared = 0;
    for t in 0..600 {
        let f = t as f64;
        if t % 13 == 0 {
            window.reset();
        }
        let x = [(0.37 * f).sin(), (0.11 * f).cos()];
        window.push(&x);
        copy.push(&[x[1], x[0]]);
        if t % 17 == 4 {
            copy = window.clone();
        }
        // The model sits out some steps.
        if t % 7 == 3 {
            continue;
        }
        let w = if t % 17 == 5 { &copy } else { &window };
        for _ in 0..1 + usize::from(t % 5 == 0) {
            by_slice.observe(w.as_slice());
            by_stamp.observe_window(w);
            let n = by_slice.n;
            assert_eq!(n, by_stamp.n);
            for (a, b) in by_slice.k[..n].iter().zip(&by_stamp.k[..n]) {
                assert_eq!(a.to_bits(), b.to_bits(), "step {t}");
            }
            assert_eq!(by_slice.mean[0].to_bits(), by_stamp.mean[0].to_bits());
            compared += n;
        }
        let y = if (0.23 * f).cos() > 0.0 { 1.0 } else { -1.0 };
        by_slice.update(&[y]);
        by_stamp.update(&[y]);
    }
    assert!(
        by_stamp.hyper_updates() >= 20 && compared > 2000,
        "{compared}"
    );
}

/// A model that observed a whole sequence at once, then learns at its last window,
/// ends as one that observed the windows step by step: the window it learns is the
/// sequence's last.
#[test]
fn a_sequence_observed_at_once_learns_its_last_window() {
    use crate::gp::{SequenceWindows, Window};
    let (dim, tau) = (2, 3);
    let p = SogpParams {
        capacity: 8,
        tau,
        ..SogpParams::default()
    };
    let mut at_once = Sogp::new(dim, 1, &p).unwrap();
    let mut by_step = at_once.clone();
    for g in 0..40 {
        let f = g as f64;
        let steps: Vec<f64> = (0..2 * (4 + g % 5))
            .map(|i| (0.37 * f + 0.9 * i as f64).sin())
            .collect();
        let y = if g % 3 == 0 { 1.0 } else { -1.0 };
        let mut seen = Vec::new();
        at_once.observe_sequence(&SequenceWindows::new(dim, tau, &steps), 1, |_, m| {
            seen.push(m.probability())
        });
        at_once.update(&[y]);
        let mut window = Window::new(dim, tau);
        for (o, q) in steps.chunks_exact(dim).zip(&seen) {
            window.push(o);
            by_step.observe_window(&window);
            assert_eq!(by_step.probability().to_bits(), q.to_bits(), "grasp {g}");
        }
        by_step.update(&[y]);
        assert_eq!(at_once.basis(), by_step.basis(), "grasp {g}");
        assert_eq!(at_once.alpha, by_step.alpha, "grasp {g}");
    }
    assert_eq!(at_once.n_basis(), p.capacity);
}

#[test]
fn a_drifted_inverse_is_detected_and_rebuilt() {
    let p = SogpParams {
        capacity: 8,
        tau: 2,
        adaptation: None,
        likelihood: Likelihood::Regression,
        ..SogpParams::default()
    };
    let mut gp = Sogp::new(1, 1, &p).unwrap();
    // Train until the next update is a drift check, with the budget full.
    for t in 0..DRIFT_CHECK_EVERY - 1 {
        let x = [(t as f64 * 0.37).sin(), (t as f64 * 0.11).cos()];
        gp.observe(&x);
        gp.update(&[x[1]]);
    }
    assert!(gp.inverse_drift() < DRIFT_TOL, "{}", gp.inverse_drift());
    assert_eq!(gp.inverse_rebuilds(), 0);
    // Force a drift: perturb Q symmetrically.
    let (n, s) = (gp.n, gp.stride);
    assert!(n >= 2);
    gp.q[s] += 1e-2;
    gp.q[1] += 1e-2;
    gp.q[0] *= 1.05;
    assert!(gp.inverse_drift() > DRIFT_TOL);
    gp.observe(&[0.3, -0.2]);
    gp.update(&[0.1]);
    assert_eq!(gp.inverse_rebuilds(), 1);
    assert!(gp.inverse_drift() < DRIFT_TOL, "{}", gp.inverse_drift());
    // Q is again the inverse of K_B within rounding.
    let k = Array2::from_shape_vec((gp.n, gp.n), gp.gram()).unwrap();
    let qk = gp.inverse_gram().dot(&k);
    for ((i, j), v) in qk.indexed_iter() {
        let want = if i == j { 1.0 } else { 0.0 };
        assert!((v - want).abs() < 1e-6, "QK[{i},{j}] = {v}");
    }
}
