//! Expected run times from measurements on this machine. Each kind of run has a model of its
//! cost (seconds per unit of work, measured once on the project's 2-core machine); the runs
//! that finish here correct it: a kind's factor is the running mean, in log scale, of
//! measured ÷ modelled time. While a run goes, its time left blends that expectation with what
//! the items finished so far say, and counts down between them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// After this many runs a new one weighs as much as the mean of the earlier ones it joins
/// (an exponential mean: the machine's load changes, old runs should fade).
const MEMORY: u32 = 4;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct Factor {
    /// Mean of ln(measured / modelled).
    log_ratio: f64,
    runs: u32,
}

/// What a run is expected to cost: the kind of run whose measured times correct its cost
/// model and the seconds the model puts it at.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub timing: String,
    pub modelled: f64,
}

impl Estimate {
    /// The expectation on this machine: the model corrected by the runs measured here.
    pub fn expected(&self, timings: &Timings) -> f64 {
        timings.expected(&self.timing, self.modelled)
    }
}

/// Measured corrections to the modelled run times, by kind of run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    factors: BTreeMap<String, Factor>,
}

impl Timings {
    /// The expected seconds of a run of `kind` that its model puts at `modelled` seconds.
    pub fn expected(&self, kind: &str, modelled: f64) -> f64 {
        match self.factors.get(kind) {
            Some(f) => modelled * f.log_ratio.exp(),
            None => modelled,
        }
    }

    /// A run of `kind` modelled at `modelled` seconds took `measured` seconds.
    pub fn record(&mut self, kind: &str, modelled: f64, measured: f64) {
        if !(modelled > 0.0 && measured > 0.0 && modelled.is_finite() && measured.is_finite()) {
            return;
        }
        let x = (measured / modelled).ln();
        let f = self.factors.entry(kind.to_string()).or_insert(Factor {
            log_ratio: 0.0,
            runs: 0,
        });
        f.runs = (f.runs + 1).min(MEMORY);
        f.log_ratio += (x - f.log_ratio) / f.runs as f64;
    }

    /// How many runs of `kind` were measured (at most the memory's length).
    pub fn runs(&self, kind: &str) -> u32 {
        self.factors.get(kind).map_or(0, |f| f.runs)
    }
}

/// The fraction done at which what the finished part says weighs as much as the
/// expectation. A cost model is right to within about 2× across sessions; the rate of the
/// part done is nearer once a few items have finished, so it takes over early: at a fifth
/// done it weighs 0.8.
const HALF_WEIGHT_AT: f64 = 0.05;

/// Seconds left of a run: `fraction` of it was done `at` seconds in, `now` seconds have
/// passed, and it was expected to take `expected` seconds in all (None: no expectation).
/// `first` is when the fraction first moved and to what: the rate is measured from there
/// once it moves again, since what came before (reading the session, preparing what every
/// item shares, the first item) may have reported nothing. The total is the expectation at first and what
/// the rate says as the fraction grows past `first` (weighted d / (d + HALF_WEIGHT_AT) for
/// a growth d); between two reports the time left counts down with the clock instead of
/// waiting for the next report. None while nothing says anything.
pub fn time_left(
    expected: Option<f64>,
    fraction: f64,
    at: f64,
    now: f64,
    first: Option<(f64, f64)>,
) -> Option<f64> {
    let f = fraction.clamp(0.0, 1.0);
    let (t1, f1) = first.unwrap_or((0.0, 0.0));
    let d = f - f1;
    // Until the fraction moves a second time, the plain rate since the start.
    let (observed, grown) = match (d > 1e-3, f > 1e-3) {
        (true, _) => (Some(t1 + (at - t1) / d * (1.0 - f1)), d),
        (false, true) => (Some(at / f), f),
        (false, false) => (None, 0.0),
    };
    let total = match (expected.filter(|e| *e > 0.0), observed) {
        (Some(e), Some(o)) => {
            let w = grown / (grown + HALF_WEIGHT_AT);
            (1.0 - w) * e + w * o
        }
        (Some(e), None) => e,
        (None, Some(o)) => o,
        (None, None) => return None,
    };
    Some((total - now).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kind_measured_slower_than_modelled_is_expected_slower() {
        let mut t = Timings::default();
        assert_eq!(t.expected("DU", 240.0), 240.0);
        // Modelled at 240 s, took 20 s: the next such run is expected at about 20 s.
        t.record("DU", 240.0, 20.0);
        assert!((t.expected("DU", 240.0) - 20.0).abs() < 1e-9);
        // A run twice the size is expected twice as long.
        assert!((t.expected("DU", 480.0) - 40.0).abs() < 1e-9);
        // Another kind is untouched.
        assert_eq!(t.expected("GU", 10.0), 10.0);
        // Two runs, ratios 1/12 and 1/3: the geometric mean, 1/6.
        t.record("DU", 60.0, 20.0);
        assert!((t.expected("DU", 60.0) - 10.0).abs() < 1e-9);
        t.record("DU", 0.0, 5.0);
        assert_eq!(t.runs("DU"), 2);
    }

    #[test]
    fn time_left_counts_down_between_reports_and_follows_the_items_done() {
        // Expected 100 s; nothing done yet: 100 s, then 90 s ten seconds in.
        assert_eq!(time_left(Some(100.0), 0.0, 0.0, 0.0, None), Some(100.0));
        assert_eq!(time_left(Some(100.0), 0.0, 0.0, 10.0, None), Some(90.0));
        // Half done at 20 s (the run goes faster than expected): the part done says 40 s
        // and weighs 0.5 / 0.55, so the total is 100/11 + 400/11 = 500/11 s; the time left
        // falls while no new item finishes.
        let a = time_left(Some(100.0), 0.5, 20.0, 20.0, None).unwrap();
        let b = time_left(Some(100.0), 0.5, 20.0, 25.0, None).unwrap();
        let total = 500.0 / 11.0;
        assert!(
            (a - (total - 20.0)).abs() < 1e-9 && (b - (total - 25.0)).abs() < 1e-9,
            "{a} {b}"
        );
        // A fifth done: an expectation 2× off moves the total by a fifth of it at most.
        let t = 10.0 + time_left(Some(100.0), 0.2, 10.0, 10.0, None).unwrap();
        assert!((t / 50.0 - 1.2).abs() < 1e-9, "{t}");
        // Ten silent seconds of preparation, then the fraction first moved to 0.1 at 12 s
        // and reached 0.3 at 16 s: 0.2 in 4 s, so the remaining 0.9 after the first move
        // takes 18 s; the total is 30 s, not 16 / 0.3 = 53 s.
        let first = Some((12.0, 0.1));
        assert_eq!(time_left(None, 0.3, 16.0, 16.0, first), Some(14.0));
        // The first move alone gives no rate from it yet: the plain rate since the start
        // (120 s, weighing 0.1 / 0.15) and the expectation.
        let left = time_left(Some(40.0), 0.1, 12.0, 12.0, first).unwrap();
        assert!((left - (40.0 / 3.0 + 80.0 - 12.0)).abs() < 1e-9, "{left}");
        // With no expectation, the items done alone: a quarter at 10 s, 30 s left.
        assert_eq!(time_left(None, 0.25, 10.0, 10.0, None), Some(30.0));
        assert_eq!(time_left(None, 0.0, 0.0, 3.0, None), None);
        // Never negative.
        assert_eq!(time_left(Some(1.0), 0.0, 0.0, 5.0, None), Some(0.0));
    }
}
