//! Progress reporting and cancellation shared by the engine and the background jobs.
//!
//! An engine function takes a `&Progress`, reports the fraction done with a short message,
//! and calls [`Progress::checkpoint`] between units of work so that a Cancel takes effect
//! within one unit (the views promise under a second). Work split into items of unequal
//! cost hands each item a [part](Progress::parts) weighted by its expected cost, so that
//! the fraction done follows the time spent, items in flight included.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
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
    /// When the fraction first moved from 0, and to what (None: not yet).
    first_move: OnceLock<(f64, f64)>,
}

/// A cheap, cloneable handle: the worker reports, the UI reads and may cancel.
#[derive(Debug, Clone)]
pub struct Progress {
    inner: Arc<Inner>,
    /// For a part: the whole it moves, by its weight.
    whole: Option<Arc<Part>>,
}

/// How a part moves the whole: its share of it.
#[derive(Debug)]
struct Part {
    whole: Progress,
    weight: f64,
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
                first_move: OnceLock::new(),
            }),
            whole: None,
        }
    }

    /// Parts of what is left of this run, one per weight, each worth its weight's share of
    /// it: a part's fraction moves this one by that share. A cancel of the whole reaches
    /// every part; a part's message becomes the whole's.
    pub fn parts(&self, weights: &[f64]) -> Vec<Progress> {
        let clean = |w: f64| if w.is_finite() && w > 0.0 { w } else { 0.0 };
        let total: f64 = weights.iter().map(|&w| clean(w)).sum();
        let left = 1.0 - self.fraction();
        weights
            .iter()
            .map(|&w| {
                let weight = match total > 0.0 {
                    true => left * clean(w) / total,
                    false => left / weights.len() as f64,
                };
                let mut part = Progress::new();
                part.whole = Some(Arc::new(Part {
                    whole: self.clone(),
                    weight,
                }));
                part
            })
            .collect()
    }

    /// Report `fraction` (clamped to 0..=1) done, with what is being done now.
    pub fn set(&self, fraction: f64, message: impl Into<String>) {
        self.set_fraction(fraction);
        self.set_message(message.into());
    }

    fn set_message(&self, message: String) {
        if let Some(p) = &self.whole {
            p.whole.set_message(message.clone());
        }
        if let Ok(mut m) = self.inner.message.lock() {
            *m = message;
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
            self.moved(f);
            if let Some(p) = &self.whole {
                p.whole
                    .add_fraction(p.weight * (f - f64::from_bits(before)));
            }
        }
    }

    /// Move the fraction by `delta` (a part's share of its change), atomically: parts
    /// report from several threads at once.
    fn add_fraction(&self, delta: f64) {
        let mut current = self.inner.fraction_bits.load(Ordering::Relaxed);
        loop {
            let f = (f64::from_bits(current) + delta).clamp(0.0, 1.0);
            match self.inner.fraction_bits.compare_exchange_weak(
                current,
                f.to_bits(),
                Ordering::Relaxed,
                Ordering::Relaxed,
            ) {
                Ok(_) => {
                    self.moved(f);
                    break;
                }
                Err(now) => current = now,
            }
        }
        if let Some(p) = &self.whole {
            p.whole.add_fraction(p.weight * delta);
        }
    }

    /// The fraction moved to `f` now.
    fn moved(&self, f: f64) {
        let now = self.elapsed_secs();
        self.inner
            .moved_at_bits
            .store(now.to_bits(), Ordering::Relaxed);
        if f > 0.0 && self.inner.first_move.get().is_none() {
            // Two parts moving at once: the first to set it is the first move.
            let _ = self.inner.first_move.set((now, f));
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
            || self.whole.as_ref().is_some_and(|p| p.whole.is_cancelled())
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
        let first = self.inner.first_move.get().copied();
        super::estimate::time_left(
            expected.is_finite().then_some(expected),
            f,
            at,
            self.elapsed_secs(),
            first,
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

    #[test]
    fn parts_move_the_whole_by_their_weights_and_hear_its_cancel() {
        let whole = Progress::new();
        whole.set_fraction(0.2);
        // What is left (0.8) split 3 : 1.
        let parts = whole.parts(&[3.0, 1.0]);
        parts[0].set(0.5, "first half-way");
        assert!((whole.fraction() - (0.2 + 0.8 * 0.75 * 0.5)).abs() < 1e-12);
        assert_eq!(whole.message(), "first half-way");
        parts[1].set_fraction(1.0);
        parts[0].set_fraction(1.0);
        assert!((whole.fraction() - 1.0).abs() < 1e-12);
        // Moving back moves the whole back; a part of a part moves both.
        parts[1].set_fraction(0.0);
        assert!((whole.fraction() - 0.8).abs() < 1e-12);
        let sub = parts[1].parts(&[1.0, 1.0]);
        sub[0].set_fraction(1.0);
        assert!((parts[1].fraction() - 0.5).abs() < 1e-12);
        assert!((whole.fraction() - 0.9).abs() < 1e-12);
        assert!(sub[1].checkpoint().is_ok());
        whole.cancel();
        assert_eq!(sub[1].checkpoint(), Err(Cancelled));
    }
}
