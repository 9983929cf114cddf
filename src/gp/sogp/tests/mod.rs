use super::gram::{GradBuffers, tri};
use super::*;

mod inputs;

/// Hyperparameter adaptation over a window of 4 observations, starting after
/// `start_after` updates and never stopping within a test.
fn adapting_after(start_after: usize) -> SngdParams {
    SngdParams {
        window: 4,
        start_after,
        stop_count: 1000,
        ..SngdParams::default()
    }
}

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
            adaptation: Some(adapting_after(8)),
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

/// A model that observed a whole sequence at once, then learns at its last window,
/// ends as one that observed the windows step by step: the window it learns is the
/// sequence's last, and with adaptation its gradient reads that window's K_t per lag.
#[test]
fn a_sequence_observed_at_once_learns_its_last_window() {
    let (dim, tau) = (2, 3);
    for adaptation in [None, Some(adapting_after(6))] {
        let p = SogpParams {
            capacity: 8,
            tau,
            adaptation,
            ..SogpParams::default()
        };
        learn_sequences_at_once_and_by_step(dim, tau, &p);
    }
}

fn learn_sequences_at_once_and_by_step(dim: usize, tau: usize, p: &SogpParams) {
    use crate::gp::{SequenceWindows, Window};
    let mut at_once = Sogp::new(dim, 1, p).unwrap();
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
        assert_eq!(
            at_once.kernel.params(),
            by_step.kernel.params(),
            "grasp {g}"
        );
    }
    assert_eq!(at_once.n_basis(), p.capacity);
    if p.adaptation.is_some() {
        assert!(at_once.hyper_updates() >= 5, "{}", at_once.hyper_updates());
    }
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

/// A model's input at step `t` (`dim` values) and its target (`n_out` values: ±1 for
/// probit), with sequences restarting every 9 steps.
fn stream(t: usize, dim: usize, n_out: usize, probit: bool) -> (Vec<f64>, Vec<f64>) {
    let f = t as f64;
    let x: Vec<f64> = (0..dim)
        .map(|k| (0.37 * f + 1.3 * k as f64).sin() + 0.1 * (0.05 * f).cos())
        .collect();
    let y = (0..n_out)
        .map(|d| {
            let v = (0.23 * f + d as f64).cos();
            if probit { v.signum() } else { v }
        })
        .collect();
    (x, y)
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// A model saved and loaded goes on as the one saved, bit for bit: saved after an update
/// (its evaluation left over from before it) and after an observation (an update may
/// follow without observing again), before adaptation starts, while adapting and after
/// adaptation has stopped, at the budget. Every prediction, the posterior and the caches
/// the next update reads are compared at every step, and both end in the same state.
#[test]
fn a_loaded_model_goes_on_as_the_saved_one_bit_for_bit() {
    let (dim, tau) = (2, 3);
    for (likelihood, n_out) in [(Likelihood::Probit, 1), (Likelihood::Regression, 2)] {
        for (stop_threshold, trained) in [(1e-4, 10), (1e-4, 160), (1e3, 160)] {
            let p = SogpParams {
                capacity: 7,
                tau,
                likelihood,
                adaptation: Some(SngdParams {
                    window: 4,
                    start_after: 30,
                    stop_threshold,
                    stop_count: 3,
                    ..SngdParams::default()
                }),
                ..SogpParams::default()
            };
            let probit = likelihood == Likelihood::Probit;
            let mut a = Sogp::new(dim, n_out, &p).unwrap();
            let mut window = Window::new(dim, tau);
            for t in 0..trained {
                if t % 9 == 0 {
                    window.reset();
                }
                let (x, y) = stream(t, dim, n_out, probit);
                window.push(&x);
                a.observe_window(&window);
                a.update(&y);
            }
            match (trained, stop_threshold) {
                (10, _) => assert!(!a.adapting() && !a.adaptation_finished()),
                (_, 1e3) => assert!(a.adaptation_finished()),
                _ => assert!(a.adapting() && a.hyper_updates() >= 10),
            }
            if trained > 10 {
                assert_eq!(a.n_basis(), p.capacity);
            }
            for observed_last in [false, true] {
                let mut a = a.clone();
                let (x, y) = stream(trained, dim, n_out, probit);
                if observed_last {
                    window.push(&x);
                    a.observe_window(&window);
                }
                let json = serde_json::to_string(&a).unwrap();
                let mut b: Sogp = serde_json::from_str(&json).unwrap();
                assert_eq!(serde_json::to_string(&b).unwrap(), json);
                if observed_last {
                    assert_eq!(bits(a.mean()), bits(b.mean()));
                    let (va, vb) = (a.predictive_variance(), b.predictive_variance());
                    assert_eq!(va.to_bits(), vb.to_bits());
                    a.update(&y);
                    b.update(&y);
                }
                let mut wb = window.clone();
                for t in trained + 1..trained + 200 {
                    if t % 9 == 0 {
                        window.reset();
                        wb.reset();
                    }
                    let (x, y) = stream(t, dim, n_out, probit);
                    window.push(&x);
                    wb.push(&x);
                    a.observe_window(&window);
                    // Now and then by the slice, as a caller without a window does.
                    if t % 5 == 0 {
                        b.observe(wb.as_slice());
                    } else {
                        b.observe_window(&wb);
                    }
                    let n = a.n;
                    assert_eq!(bits(a.mean()), bits(b.mean()), "step {t}");
                    let (va, vb) = (a.predictive_variance(), b.predictive_variance());
                    assert_eq!(va.to_bits(), vb.to_bits(), "step {t}");
                    assert_eq!(bits(&a.k[..n]), bits(&b.k[..n]), "step {t}");
                    // K_t per lag are kept only while adapting.
                    for lag in (0..tau).filter(|_| a.adapt.is_some()) {
                        let row = lag * a.basis.stride();
                        assert_eq!(bits(&a.lag_k[row..row + n]), bits(&b.lag_k[row..row + n]));
                    }
                    a.update(&y);
                    b.update(&y);
                    assert_eq!(bits(&a.alpha), bits(&b.alpha), "step {t}");
                }
                assert_eq!(
                    serde_json::to_string(&a).unwrap(),
                    serde_json::to_string(&b).unwrap()
                );
            }
        }
    }
}

/// A damaged model state is an error naming what is wrong, and nothing panics.
#[test]
fn a_damaged_model_state_is_an_error_naming_the_field() {
    let p = SogpParams {
        capacity: 5,
        tau: 2,
        adaptation: Some(adapting_after(10)),
        ..SogpParams::default()
    };
    let mut m = Sogp::new(2, 1, &p).unwrap();
    for t in 0..40 {
        let (x, y) = stream(t, 4, 1, true);
        m.observe(&x);
        m.update(&y);
    }
    assert!(m.adapting());
    let saved = serde_json::to_value(&m).unwrap();
    let error = |field: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = saved.clone();
        edit(&mut v);
        let e = serde_json::from_value::<Sogp>(v).unwrap_err().to_string();
        assert!(e.contains(field), "`{field}` not named in: {e}");
    };
    error("n_basis", &|v| v["n_basis"] = 6.into());
    error("c", &|v| v["c"].as_array_mut().unwrap().truncate(3));
    error("last_window", &|v| {
        v["last_window"].as_array_mut().unwrap().pop();
    });
    // Lengthscales for three inputs in a model of two.
    error("kernel.lengthscales", &|v| v["dim"] = 3.into());
    error("q[4]", &|v| v["q"][4] = "inf".into());
    error("tau", &|v| v["tau"] = 100_000.into());
    // Each within its limit, together far beyond any model.
    error("would take", &|v| {
        v["kernel"]["lengthscales"] = serde_json::json!(vec![1.0; 1000]);
        v["dim"] = 1000.into();
        v["tau"] = 1000.into();
        v["capacity"] = 4096.into();
    });
    error("sngd", &|v| v["adaptation"] = serde_json::Value::Null);
    error("sngd", &|v| v["adaptation_finished"] = true.into());
    error("sngd: invalid state `samples`", &|v| {
        v["sngd"]["samples"] = 4.into()
    });
    error("sngd.theta[4]", &|v| v["sngd"]["theta"][4] = 0.0.into());
    error("sngd: invalid state `lower[0]`", &|v| {
        v["sngd"]["lower"][0] = 1e3.into()
    });
    error("sngd: invalid state `calm`", &|v| {
        v["sngd"]["calm"] = 1000.into()
    });
    error("sngd.params", &|v| {
        v["sngd"]["params"]["lambda0"] = 2.0.into()
    });
    error("novelty_eps", &|v| v["novelty_eps"] = (-1.0).into());
    error("n_out", &|v| v["n_out"] = 0.into());
    error("unknown field `extra`", &|v| v["extra"] = 1.into());
    error("missing field `alpha`", &|v| {
        v.as_object_mut().unwrap().remove("alpha");
    });
}

/// A window saves its inputs; a damaged one is an error, never a window that panics on
/// its next input.
#[test]
fn a_window_saves_its_inputs_and_a_damaged_one_is_an_error() {
    let mut w = Window::new(2, 3);
    w.push(&[1.0, -0.0]);
    w.push(&[f64::NAN, 2.5]);
    let back: Window = serde_json::from_str(&serde_json::to_string(&w).unwrap()).unwrap();
    assert_eq!(bits(back.as_slice()), bits(w.as_slice()));
    assert_ne!(back.stamp(), w.stamp());
    for (bad, field) in [
        (r#"{"dim": 0, "inputs": []}"#, "dim"),
        (r#"{"dim": 2, "inputs": [1.0, 2.0, 3.0]}"#, "inputs"),
        (r#"{"dim": 2, "inputs": []}"#, "inputs"),
    ] {
        let e = serde_json::from_str::<Window>(bad).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
}

/// At the budget, an update stores the new BV only when the deletion keeps it, straight
/// into the slot it frees. It must leave what storing the BV first and then deleting
/// the least informative one leaves (a model with room for one more BV, then
/// [`Sogp::delete`] of the BV with the lowest |α_i|²/(Q_ii + C_ii), paper eq. 10): the
/// same posterior, BVs, Gram derivatives and observations, bit for bit, with and
/// without adaptation.
#[test]
fn at_the_budget_an_update_equals_storing_then_deleting_the_least_informative() {
    let (dim, tau, cap) = (2, 3, 6);
    for (likelihood, n_out) in [(Likelihood::Probit, 1), (Likelihood::Regression, 2)] {
        for adaptation in [false, true] {
            let params = |capacity| SogpParams {
                capacity,
                tau,
                likelihood,
                adaptation: adaptation.then_some(adapting_after(20)),
                ..SogpParams::default()
            };
            let probit = likelihood == Likelihood::Probit;
            let mut a = Sogp::new(dim, n_out, &params(cap)).unwrap();
            let mut b = Sogp::new(dim, n_out, &params(cap + 1)).unwrap();
            let mut window = Window::new(dim, tau);
            let (mut kept, mut dropped) = (0, 0);
            for t in 0..300 {
                if t % 9 == 0 {
                    window.reset();
                }
                let (x, y) = stream(t, dim, n_out, probit);
                window.push(&x);
                a.observe_window(&window);
                b.observe_window(&window);
                assert_eq!(bits(a.mean()), bits(b.mean()), "step {t}");
                let (va, vb) = (a.predictive_variance(), b.predictive_variance());
                assert_eq!(va.to_bits(), vb.to_bits(), "step {t}");
                a.update(&y);
                b.update(&y);
                let (n, s) = (b.n, b.stride);
                if n > cap {
                    let score = |i: usize| {
                        let a2: f64 = (0..n_out).map(|d| b.alpha[i * n_out + d].powi(2)).sum();
                        a2 / (b.q[i * s + i] + b.c[i * s + i]).max(1e-300)
                    };
                    let worst = (0..n).fold(0, |w, i| if score(i) < score(w) { i } else { w });
                    if worst == n - 1 {
                        dropped += 1
                    } else {
                        kept += 1
                    }
                    b.delete(worst);
                }
                let (n, sa) = (a.n, a.stride);
                assert_eq!(n, b.n, "step {t}");
                assert_eq!(bits(&a.alpha[..n * n_out]), bits(&b.alpha[..n * n_out]));
                for i in 0..n {
                    assert_eq!(bits(&a.c[i * sa..i * sa + n]), bits(&b.c[i * s..i * s + n]));
                    assert_eq!(bits(&a.q[i * sa..i * sa + n]), bits(&b.q[i * s..i * s + n]));
                }
                let (ba, bb) = (a.basis(), b.basis());
                assert_eq!(ba, bb, "step {t}");
                assert_eq!(a.kernel_params(), b.kernel_params(), "step {t}");
                if let (Some(da), Some(db)) = (a.adapt.as_ref(), b.adapt.as_ref()) {
                    let len = tri(n, 0) * da.buf.pk;
                    assert_eq!(bits(&da.buf.kb[..len]), bits(&db.buf.kb[..len]), "step {t}");
                }
            }
            assert!(a.adapting() == adaptation && (!adaptation || a.hyper_updates() > 10));
            // Both ways through the budget were taken, many times.
            assert!(kept > 20 && dropped > 20, "kept {kept}, dropped {dropped}");
        }
    }
}

/// The removal's quotients by reciprocal and FMAs ([`crate::gp::quotient`]) give the
/// division's C, Q and α to the last bit, for every BV of models at the budget, with and
/// without adaptation; and the reciprocal path is the one taken nearly always.
#[test]
fn the_removal_by_reciprocals_equals_the_removal_by_division() {
    use crate::gp::Window;
    use crate::gp::quotient::in_range;
    let (dim, tau, cap) = (3, 4, 8);
    let (mut removals, mut by_reciprocal) = (0, 0);
    for adaptation in [false, true] {
        let params = SogpParams {
            capacity: cap,
            tau,
            adaptation: adaptation.then_some(adapting_after(20)),
            ..SogpParams::default()
        };
        let mut gp = Sogp::new(dim, 1, &params).unwrap();
        let mut window = Window::new(dim, tau);
        for t in 0..200 {
            if t % 9 == 0 {
                window.reset();
            }
            let (x, y) = stream(t, dim, 1, true);
            window.push(&x);
            gp.observe_window(&window);
            gp.update(&y);
            let (n, s) = (gp.n, gp.stride);
            for i in 0..n {
                let qs = gp.q[i * s + i].max(1e-300);
                let den = (gp.q[i * s + i] + gp.c[i * s + i]).max(1e-300);
                let fast = in_range(qs)
                    && in_range(den)
                    && (0..n).all(|j| {
                        let q = gp.q[j * s + i];
                        in_range(q) && in_range(q + gp.c[j * s + i])
                    });
                let (mut a, mut b) = (gp.clone(), gp.clone());
                a.remove_portable(i, true);
                b.remove_portable(i, false);
                assert_eq!(bits(&a.alpha[..n]), bits(&b.alpha[..n]), "step {t}, BV {i}");
                for r in (0..n).filter(|&r| r != i) {
                    let row = |m: &[f64]| bits(&m[r * s..r * s + n]);
                    assert_eq!(row(&a.c), row(&b.c), "step {t}, BV {i}, row {r}");
                    assert_eq!(row(&a.q), row(&b.q), "step {t}, BV {i}, row {r}");
                }
                removals += 1;
                by_reciprocal += fast as usize;
            }
        }
    }
    assert!(
        by_reciprocal * 10 > removals * 9,
        "{by_reciprocal} of {removals} by reciprocal"
    );
}
