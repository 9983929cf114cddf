//! A model's saved state: what it has learnt (the BVs' raw windows and targets, α, C and Q
//! over the BVs, the hyperparameters and the optimiser's state), its counters and the window
//! it observed last. Everything else is rebuilt on load from these, as the model itself
//! builds it: the scaled BVs and their lag-major copy (the windows divided by the
//! lengthscales), the distinct inputs and their distance rows, the Gram derivatives of the
//! gradient (a fresh computation equals the incrementally kept one bit for bit, which
//! `cached_gradient_terms_equal_a_fresh_computation` checks after every update), and the
//! evaluation at the last observed window.
//!
//! Not kept: scratch written before it is read within a call (the deletion's columns, the
//! rebuild's Gram, the targets being learnt, the optimiser's products), the slots in
//! which the distinct inputs happen to lie (their distances do not depend on them), the
//! stamps of observed windows (a loaded model evaluates the next window in full, which
//! gives the values the shift by one gives), and the evaluation left over from before the
//! last update: a loaded model holds the posterior at its last observed window under its
//! current state (what [`Sogp::update`] evaluates again before learning anyway), where the
//! saved one may still report the posterior from before that update through
//! [`Sogp::mean`] and the variances until it observes a window.

use serde::{Deserialize, Serialize};

use super::super::floats::{self, first_non_finite};
use super::super::kernel::{KernelParams, RecursiveArd};
use super::super::sngd::{Sngd, SngdParams};
use super::adapt::Adaptation;
use super::gram::GradBuffers;
use super::{GpError, Likelihood, Sogp, SogpParams};

/// The largest BV budget and number of lags a loaded model may have: the command line's
/// limits (`cli::bounds`). A file's budget and lags size buffers that its own contents do
/// not (a damaged budget of 10¹² would otherwise be an allocation that aborts).
const MAX_LOADED_CAPACITY: usize = 4096;
const MAX_LOADED_TAU: usize = 1000;
/// The most f64 values the buffers of a loaded model may take (4 GiB), for budgets and lags
/// each within their limits but together beyond any model trained here.
const MAX_LOADED_FLOATS: f64 = (1u64 << 29) as f64;

/// A [`Sogp`] as it is saved.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SogpState {
    dim: usize,
    tau: usize,
    capacity: usize,
    novelty_eps: f64,
    likelihood: Likelihood,
    n_out: usize,
    /// The current (adapted) hyperparameters.
    kernel: KernelParams,
    adaptation: Option<SngdParams>,
    /// Training points seen.
    seen: usize,
    inverse_rebuilds: usize,
    /// BVs held.
    n_basis: usize,
    /// The BVs' raw windows (n_basis × tau·dim, row-major, oldest lag first).
    #[serde(with = "floats")]
    basis_windows: Vec<f64>,
    /// Their targets (n_basis × n_out).
    #[serde(with = "floats")]
    basis_targets: Vec<f64>,
    /// α (n_basis × n_out), C and Q = K_B⁻¹ (n_basis × n_basis).
    #[serde(with = "floats")]
    alpha: Vec<f64>,
    #[serde(with = "floats")]
    c: Vec<f64>,
    #[serde(with = "floats")]
    q: Vec<f64>,
    /// The window observed last (tau·dim): the one an update learns.
    #[serde(with = "floats")]
    last_window: Vec<f64>,
    /// The optimiser while adapting.
    #[serde(deserialize_with = "deserialize_sngd")]
    sngd: Option<Sngd>,
    adaptation_finished: bool,
}

impl Serialize for Sogp {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.state().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Sogp {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Sogp, D::Error> {
        Sogp::from_state(SogpState::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

/// The optimiser's state, its errors named within `sngd`.
fn deserialize_sngd<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Sngd>, D::Error> {
    // (serde_json takes the position back out of the end of the message.)
    Option::<Sngd>::deserialize(d).map_err(|e| serde::de::Error::custom(format!("sngd: {e}")))
}

/// f64 values the buffers of a model of this size take (a bound, within a few percent).
fn footprint(dim: usize, tau: usize, capacity: usize, n_out: usize) -> f64 {
    let (d, t, s, o) = (dim as f64, tau as f64, capacity as f64 + 1.0, n_out as f64);
    let lanes = s + 8.0;
    let input_slots = s * t + 8.0;
    // BV windows (raw and scaled), C, Q and the rebuild's Gram, targets and α.
    let posterior = 2.0 * s * t * d + 3.0 * s * s + 2.0 * s * o;
    // The lag-major BVs, the distinct inputs and their distance rows, the per-lag kernel.
    let kernel = (t * d + t) * lanes + input_slots * (2.0 * d + 2.0 + t) + 3.0 * t * lanes;
    // The Gram derivatives of the gradient.
    let gradient = s * (s + 1.0) / 2.0 * (d + 2.0) + 2.0 * lanes * (d + 2.0);
    posterior + kernel + gradient
}

fn check_len(name: &str, v: &[f64], len: usize) -> Result<(), GpError> {
    if v.len() != len {
        return Err(GpError::state(
            name,
            format!("{} values, expected {len}", v.len()),
        ));
    }
    Ok(())
}

fn check_finite(name: &str, v: &[f64]) -> Result<(), GpError> {
    match first_non_finite(v) {
        Some((i, x)) => Err(GpError::state(
            format!("{name}[{i}]"),
            format!("{x} is not finite"),
        )),
        None => Ok(()),
    }
}

impl Sogp {
    fn state(&self) -> SogpState {
        let (n, s, w, no) = (self.n, self.stride, self.wlen, self.n_out);
        let square = |m: &[f64]| -> Vec<f64> {
            (0..n)
                .flat_map(|i| m[i * s..i * s + n].iter().copied())
                .collect()
        };
        SogpState {
            dim: self.kernel.dim(),
            tau: self.kernel.tau(),
            capacity: self.cap,
            novelty_eps: self.eps,
            likelihood: self.likelihood,
            n_out: no,
            kernel: self.kernel.params().clone(),
            adaptation: self.adaptation_params.clone(),
            seen: self.seen,
            inverse_rebuilds: self.inverse_rebuilds,
            n_basis: n,
            basis_windows: self.bv_raw[..n * w].to_vec(),
            basis_targets: self.bv_y[..n * no].to_vec(),
            alpha: self.alpha[..n * no].to_vec(),
            c: square(&self.c),
            q: square(&self.q),
            last_window: self.x_raw.clone(),
            sngd: self.adapt.as_ref().map(|a| a.sngd.clone()),
            adaptation_finished: self.adaptation_finished,
        }
    }

    /// Checks, before anything is allocated for it, that a model of `dim` inputs, `tau`
    /// lags, a budget of `capacity` BVs and `n_out` outputs, as a saved state gives them, is
    /// within the limits of a loaded model (errors name `dim`, `tau` or `capacity`).
    pub(crate) fn check_loadable_size(
        dim: usize,
        tau: usize,
        capacity: usize,
        n_out: usize,
    ) -> Result<(), GpError> {
        if capacity > MAX_LOADED_CAPACITY {
            return Err(GpError::state(
                "capacity",
                format!("{capacity} is above the limit of {MAX_LOADED_CAPACITY}"),
            ));
        }
        if tau > MAX_LOADED_TAU {
            return Err(GpError::state(
                "tau",
                format!("{tau} is above the limit of {MAX_LOADED_TAU}"),
            ));
        }
        let size = footprint(dim, tau, capacity, n_out);
        if size > MAX_LOADED_FLOATS {
            return Err(GpError::state(
                "dim",
                format!(
                    "a model of {dim} inputs, {tau} lags, {capacity} BVs and {n_out} outputs \
                     would take {:.1} GiB",
                    size * 8.0 / f64::from(1u32 << 30)
                ),
            ));
        }
        Ok(())
    }

    /// The model a saved state describes, every field checked against the others.
    fn from_state(st: SogpState) -> Result<Sogp, GpError> {
        for (name, v) in [("dim", st.dim), ("tau", st.tau), ("n_out", st.n_out)] {
            if v == 0 {
                return Err(GpError::state(name, "must be at least 1"));
            }
        }
        if st.likelihood == Likelihood::Probit && st.n_out != 1 {
            return Err(GpError::state(
                "n_out",
                format!("{} outputs in a probit model", st.n_out),
            ));
        }
        if let Some(a) = &st.adaptation {
            a.validate().map_err(|e| e.within("adaptation"))?;
        }
        // Every lengthscale is in the file, so that this bounds dim by the file's size.
        st.kernel.validate(st.dim).map_err(|e| e.within("kernel"))?;
        Sogp::check_loadable_size(st.dim, st.tau, st.capacity, st.n_out)?;
        // The lengths first: nothing is allocated for a state that does not hold together.
        let (n, no, w) = (st.n_basis, st.n_out, st.tau * st.dim);
        if n > st.capacity {
            return Err(GpError::state(
                "n_basis",
                format!("{n} BVs above the budget of {}", st.capacity),
            ));
        }
        if n > st.seen {
            return Err(GpError::state(
                "seen",
                format!("{} training points cannot have made {n} BVs", st.seen),
            ));
        }
        for (name, v, len) in [
            ("basis_windows", &st.basis_windows, n * w),
            ("basis_targets", &st.basis_targets, n * no),
            ("alpha", &st.alpha, n * no),
            ("c", &st.c, n * n),
            ("q", &st.q, n * n),
        ] {
            check_len(name, v, len)?;
            check_finite(name, v)?;
        }
        check_len("last_window", &st.last_window, w)?;
        if st.likelihood == Likelihood::Probit
            && let Some(i) = st.basis_targets.iter().position(|y| y.abs() != 1.0)
        {
            return Err(GpError::state(
                format!("basis_targets[{i}]"),
                format!("{} is not a probit label ±1", st.basis_targets[i]),
            ));
        }
        check_adaptation(&st)?;
        let params = SogpParams {
            capacity: st.capacity,
            tau: st.tau,
            novelty_eps: st.novelty_eps,
            lengthscale: st.kernel.lengthscales[0],
            sigma_rho: st.kernel.sigma_rho,
            sigma_f: st.kernel.sigma_f,
            sigma_n: st.kernel.sigma_n,
            likelihood: st.likelihood,
            adaptation: st.adaptation.clone(),
        };
        // Checks the budget, novelty threshold and outputs (named as in the state).
        let mut m = Sogp::new(st.dim, st.n_out, &params).map_err(|e| match e {
            GpError::InvalidParameter { name, reason } => GpError::state(name, reason),
            e => e,
        })?;
        let s = m.stride;
        m.kernel = RecursiveArd::new(st.dim, st.tau, st.kernel).map_err(|e| e.within("kernel"))?;
        m.n = n;
        m.seen = st.seen;
        m.inverse_rebuilds = st.inverse_rebuilds;
        m.adaptation_finished = st.adaptation_finished;
        m.bv_raw[..n * w].copy_from_slice(&st.basis_windows);
        m.bv_y[..n * no].copy_from_slice(&st.basis_targets);
        m.alpha[..n * no].copy_from_slice(&st.alpha);
        for i in 0..n {
            m.c[i * s..i * s + n].copy_from_slice(&st.c[i * n..(i + 1) * n]);
            m.q[i * s..i * s + n].copy_from_slice(&st.q[i * n..(i + 1) * n]);
        }
        let inv_rho = 1.0 / m.kernel.params().sigma_rho;
        for i in 0..n {
            let (raw, scaled) = (
                &m.bv_raw[i * w..(i + 1) * w],
                &mut m.bv_scaled[i * w..(i + 1) * w],
            );
            m.kernel.scale_into(raw, scaled);
            m.inputs.add_bv(i, raw, scaled, inv_rho);
        }
        m.sync_basis();
        if let Some(sngd) = st.sngd {
            let mut buf = GradBuffers::new(st.dim, st.tau, s, m.basis.stride());
            m.fill_gram_derivatives(&mut buf);
            m.adapt = Some(Box::new(Adaptation { sngd, buf }));
        }
        m.x_raw = st.last_window;
        m.refresh();
        Ok(m)
    }
}

/// The adaptation state against the counters and parameters: the optimiser runs from
/// `start_after` training points until it stops, on theta of this kernel.
fn check_adaptation(st: &SogpState) -> Result<(), GpError> {
    let Some(p) = &st.adaptation else {
        if st.sngd.is_some() || st.adaptation_finished {
            return Err(GpError::state(
                "sngd",
                "adaptation state without adaptation",
            ));
        }
        return Ok(());
    };
    let Some(sngd) = &st.sngd else {
        if !st.adaptation_finished && st.seen >= p.start_after {
            return Err(GpError::state(
                "sngd",
                format!(
                    "missing after {} training points (adaptation starts after {})",
                    st.seen, p.start_after
                ),
            ));
        }
        return Ok(());
    };
    if st.adaptation_finished || sngd.stopped() {
        return Err(GpError::state("sngd", "present after adaptation finished"));
    }
    if st.seen < p.start_after {
        return Err(GpError::state(
            "sngd",
            format!(
                "present after {} training points (adaptation starts after {})",
                st.seen, p.start_after
            ),
        ));
    }
    if sngd.params() != p {
        return Err(GpError::state("sngd.params", "differ from `adaptation`"));
    }
    let theta = sngd.theta();
    let expected = KernelParams::theta_len(st.dim);
    if theta.len() != expected {
        return Err(GpError::state(
            "sngd.theta",
            format!("{} values for {expected} hyperparameters", theta.len()),
        ));
    }
    // The kernel is the optimiser's theta (or, before its first step, theta is the
    // kernel's), up to the rounding of exp and ln.
    if let Some((i, (a, b))) = theta
        .iter()
        .zip(st.kernel.theta())
        .enumerate()
        .find(|(_, (a, b))| (*a - b).abs() > 1e-9 * (1.0 + b.abs()))
    {
        return Err(GpError::state(
            format!("sngd.theta[{i}]"),
            format!("{a} disagrees with the kernel's {b}"),
        ));
    }
    Ok(())
}
