//! Progress reporting and cancellation shared by the engine and the background jobs.
//!
//! An engine function takes a `&Progress`, reports the fraction done with a short message,
//! and calls [`Progress::checkpoint`] between units of work so that a Cancel takes effect
//! within one unit (the views promise under a second).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

#[derive(Debug)]
struct Inner {
    fraction_bits: AtomicU64,
    cancelled: AtomicBool,
    message: Mutex<String>,
    started: Instant,
    /// Seconds since the start when the fraction last moved.
    moved_at_bits: AtomicU64,
    /// Seconds the whole run is expected to take (NaN: no expectation).
    expected_bits: AtomicU64,
}

/// A cheap, cloneable handle: the worker reports, the UI reads and may cancel.
#[derive(Debug, Clone)]
pub struct Progress {
    inner: Arc<Inner>,
}

impl Default for Progress {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress {
    pub fn new() -> Self {
        Progress {
            inner: Arc::new(Inner {
                fraction_bits: AtomicU64::new(0f64.to_bits()),
                cancelled: AtomicBool::new(false),
                message: Mutex::new(String::new()),
                started: Instant::now(),
                moved_at_bits: AtomicU64::new(0f64.to_bits()),
                expected_bits: AtomicU64::new(f64::NAN.to_bits()),
            }),
        }
    }

    /// Report `fraction` (clamped to 0..=1) done, with what is being done now.
    pub fn set(&self, fraction: f64, message: impl Into<String>) {
        self.set_fraction(fraction);
        if let Ok(mut m) = self.inner.message.lock() {
            *m = message.into();
        }
    }

    pub fn set_fraction(&self, fraction: f64) {
        let f = if fraction.is_finite() {
            fraction.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let before = self
            .inner
            .fraction_bits
            .swap(f.to_bits(), Ordering::Relaxed);
        if before != f.to_bits() {
            self.inner
                .moved_at_bits
                .store(self.elapsed_secs().to_bits(), Ordering::Relaxed);
        }
    }

    /// The whole run is expected to take `seconds` (from measurements of earlier runs).
    pub fn set_expected(&self, seconds: f64) {
        self.inner
            .expected_bits
            .store(seconds.to_bits(), Ordering::Relaxed);
    }

    pub fn fraction(&self) -> f64 {
        f64::from_bits(self.inner.fraction_bits.load(Ordering::Relaxed))
    }

    pub fn message(&self) -> String {
        self.inner
            .message
            .lock()
            .map(|m| m.clone())
            .unwrap_or_default()
    }

    pub fn cancel(&self) {
        self.inner.cancelled.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.inner.cancelled.load(Ordering::Relaxed)
    }

    /// `Err(Cancelled)` once cancel was asked: call between units of work and return early.
    pub fn checkpoint(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }

    pub fn elapsed_secs(&self) -> f64 {
        self.inner.started.elapsed().as_secs_f64()
    }

    /// Time left: the expected time blended with what the part done says, counting down
    /// between reports (see [`super::estimate::time_left`]); None before anything is known.
    pub fn eta_secs(&self) -> Option<f64> {
        let f = self.fraction();
        if f >= 1.0 {
            return None;
        }
        let expected = f64::from_bits(self.inner.expected_bits.load(Ordering::Relaxed));
        let at = f64::from_bits(self.inner.moved_at_bits.load(Ordering::Relaxed));
        super::estimate::time_left(
            expected.is_finite().then_some(expected),
            f,
            at,
            self.elapsed_secs(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_and_cancels_across_clones() {
        let p = Progress::new();
        let q = p.clone();
        q.set(0.25, "coding");
        assert_eq!(p.fraction(), 0.25);
        assert_eq!(p.message(), "coding");
        assert!(p.checkpoint().is_ok());
        p.cancel();
        assert_eq!(q.checkpoint(), Err(Cancelled));
        q.set_fraction(f64::NAN);
        assert_eq!(p.fraction(), 0.0);
    }
}
