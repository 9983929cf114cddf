//! The distinct-input tables: kernel values read from their distance rows equal the
//! direct evaluation, a model's own table grows as it fills, windows observed by their
//! stamps, and models sharing one learner's table.

use super::super::*;
use super::{adapting_after, bits};

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
        adaptation: Some(adapting_after(12)),
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
            checked += assert_rows_give_the_direct_kernel(&gp, &window, t);
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

/// The kernel vector and (while adapting, when they are kept) K_t per lag of `gp`'s last
/// observation (of `window`, at step `t`) equal the direct evaluation, bit for bit; returns
/// the BVs checked.
fn assert_rows_give_the_direct_kernel(gp: &Sogp, window: &crate::gp::Window, t: usize) -> usize {
    let (dim, tau) = (gp.kernel.dim(), gp.kernel.tau());
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
        for lag in (0..tau).filter(|_| gp.adapt.is_some()) {
            let at = lag * lanes + i;
            assert_eq!(gp.lag_k[at].to_bits(), lag_k[at].to_bits(), "step {t}");
        }
    }
    gp.n
}

/// A model's own table starts with fewer input slots than its BVs can hold and grows as
/// they fill: BVs of windows that share no input (a BV every tau steps) hold more
/// distinct inputs than it starts with, and every kernel value stays the direct one.
#[test]
fn an_own_table_grows_as_the_bvs_hold_more_inputs() {
    use crate::gp::Window;
    use crate::gp::inputs::own_table_start;
    let (dim, tau) = (3, 4);
    let p = SogpParams {
        capacity: 40,
        tau,
        adaptation: Some(adapting_after(12)),
        ..SogpParams::default()
    };
    let mut gp = Sogp::new(dim, 1, &p).unwrap();
    let mut window = Window::new(dim, tau);
    let mut rng = crate::rng::Rng::new(7);
    let (mut checked, mut most) = (0, 0);
    for t in 0..400 {
        let x: Vec<f64> = (0..dim).map(|_| rng.range(-4.0, 4.0)).collect();
        window.push(&x);
        gp.observe(window.as_slice());
        checked += assert_rows_give_the_direct_kernel(&gp, &window, t);
        if t % tau == tau - 1 {
            gp.update(&[if rng.bernoulli(0.5) { 1.0 } else { -1.0 }]);
            most = most.max(gp.distinct_inputs());
        }
    }
    assert!(
        most > own_table_start(p.capacity, tau),
        "{most} distinct inputs"
    );
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
        adaptation: Some(adapting_after(8)),
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

/// Models that share one table of distinct inputs give what models with their own give,
/// bit for bit, however the learner interleaves them: each observing windows of its own
/// sequence (the shared rows move between sequences), updated twice without observing
/// again (the second update evaluates at a window the shared rows have left), joining
/// while the others are midway, and deleting BVs at the budget. Inputs lie on a coarse
/// grid, so that the models' BVs share them.
#[test]
fn models_sharing_one_input_table_equal_models_with_their_own() {
    use crate::gp::{SharedInputs, Window};
    let (dim, tau) = (2, 3);
    let p = SogpParams {
        capacity: 7,
        tau,
        adaptation: None,
        ..SogpParams::default()
    };
    let mut own: Vec<Sogp> = (0..3).map(|_| Sogp::new(dim, 1, &p).unwrap()).collect();
    let mut shared_models = own.clone();
    let mut shared = SharedInputs::new(own[0].kernel());
    let mut windows: Vec<Window> = (0..3).map(|_| Window::new(dim, tau)).collect();
    let mut joined = 0;
    let mut checked = 0;
    for t in 0..600 {
        // Model 2 joins after 100 steps, with BVs and an observation of its own.
        let wanted = if t < 100 { 2 } else { 3 };
        while joined < wanted {
            assert!(shared_models[joined].join(&mut shared));
            joined += 1;
        }
        // Three steps of a model's sequence at a time; model 0 is midway at the join.
        let j = (t / 3) % 3;
        if t % 13 == 0 {
            windows[j].reset();
        }
        let x: Vec<f64> = (0..dim)
            .map(|k| ((0.61 * t as f64 + 1.7 * k as f64).sin() * 2.0).round() / 2.0)
            .collect();
        windows[j].push(&x);
        own[j].observe_window(&windows[j]);
        shared_models[j].observe_in(&mut shared, windows[j].as_slice(), windows[j].stamp());
        let y = [if (0.29 * t as f64).cos() > 0.0 {
            1.0
        } else {
            -1.0
        }];
        // Every fourth step another model is updated again, without observing.
        let again = (t % 4 == 0).then_some((j + 1) % 3);
        for i in std::iter::once(j).chain(again) {
            let (a, b) = (&mut own[i], &mut shared_models[i]);
            assert_eq!(bits(a.mean()), bits(b.mean()), "step {t}");
            assert_eq!(a.latent_variance().to_bits(), b.latent_variance().to_bits());
            a.update(&y);
            b.update_in(&mut shared, &y);
            checked += 1;
        }
    }
    assert!(
        shared_models
            .iter()
            .all(|m| m.shares_inputs() && m.n_basis() == 7)
    );
    let held = shared.distinct();
    let summed: usize = shared_models.iter().map(Sogp::distinct_inputs).sum();
    assert!(held < summed, "{held} {summed}");
    for (a, b) in own.iter().zip(&shared_models) {
        assert_eq!(bits(&a.c), bits(&b.c));
        assert_eq!(bits(&a.alpha), bits(&b.alpha));
    }
    assert!(checked > 700, "{checked}");
}
