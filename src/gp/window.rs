//! The input window of the OIESGP: the last `tau` inputs, oldest first, zero padded at the
//! start of a sequence (never truncated, so that the kernel's recursion always runs tau
//! lags), and stamped so that a model can tell a window shifted by one input from a new one.

use serde::{Deserialize, Serialize};

use super::GpError;

/// Where a [`Window`] stands: its sequence (unique to the window and the sequence it
/// holds) and the inputs pushed since the sequence began. A model that observed stamp
/// (s, t) knows, without comparing the windows, that (s, t + 1) is that window shifted by
/// one input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stamp {
    sequence: u64,
    step: u64,
}

impl Stamp {
    /// A sequence no other window holds.
    fn fresh() -> Stamp {
        static SEQUENCES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        Stamp {
            sequence: SEQUENCES.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            step: 0,
        }
    }

    /// True if `self` is `earlier` with one more input pushed.
    pub fn follows(self, earlier: Stamp) -> bool {
        self.sequence == earlier.sequence && self.step == earlier.step + 1
    }
}

/// The last `tau` inputs, oldest first, zero padded at the start of a sequence.
///
/// Saved as its inputs; a loaded window starts a sequence of its own (as a clone does), so
/// a model that observed the original sees the first window pushed to it as a new one and
/// evaluates it in full, which gives the same values as the shift by one.
#[derive(Debug)]
pub struct Window {
    dim: usize,
    data: Vec<f64>,
    stamp: Stamp,
}

impl Clone for Window {
    /// A copy starts a sequence of its own: pushes to the copy and to the original would
    /// otherwise give different windows the same stamp.
    fn clone(&self) -> Window {
        Window {
            dim: self.dim,
            data: self.data.clone(),
            stamp: Stamp::fresh(),
        }
    }
}

impl Window {
    pub fn new(dim: usize, tau: usize) -> Window {
        Window {
            dim,
            data: vec![0.0; dim * tau],
            stamp: Stamp::fresh(),
        }
    }

    /// Back to all-zero padding (a new sequence starts).
    pub fn reset(&mut self) {
        self.data.fill(0.0);
        self.stamp = Stamp::fresh();
    }

    /// Shift in x as the newest lag. Extra entries of `x` are ignored, missing ones are 0.
    pub fn push(&mut self, x: &[f64]) {
        let n = self.data.len();
        self.data.copy_within(self.dim.., 0);
        let newest = &mut self.data[n - self.dim..];
        newest.fill(0.0);
        for (o, v) in newest.iter_mut().zip(x) {
            *o = *v;
        }
        self.stamp.step += 1;
    }

    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    pub fn stamp(&self) -> Stamp {
        self.stamp
    }

    /// The inputs per lag.
    pub fn dim(&self) -> usize {
        self.dim
    }
}

/// A [`Window`] as it is saved.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WindowState {
    dim: usize,
    /// tau lags of `dim` inputs, oldest first.
    #[serde(with = "super::floats")]
    inputs: Vec<f64>,
}

impl Serialize for Window {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        WindowState {
            dim: self.dim,
            inputs: self.data.clone(),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Window {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Window, D::Error> {
        let w = WindowState::deserialize(d)?;
        if w.dim == 0 {
            return Err(serde::de::Error::custom(GpError::state(
                "dim",
                "must be at least 1",
            )));
        }
        if w.inputs.is_empty() || !w.inputs.len().is_multiple_of(w.dim) {
            return Err(serde::de::Error::custom(GpError::state(
                "inputs",
                format!(
                    "{} values are not one or more lags of {} inputs",
                    w.inputs.len(),
                    w.dim
                ),
            )));
        }
        Ok(Window {
            dim: w.dim,
            data: w.inputs,
            stamp: Stamp::fresh(),
        })
    }
}

/// Every window of one sequence, each a slice of its zero-padded inputs (nothing is copied
/// per step), stamped as a [`Window`] fed the same inputs would be: an expert can go over
/// the whole sequence on its own, with its state hot in the cache, and observe exactly
/// what it would have observed step by step among the other experts.
#[derive(Debug)]
pub struct SequenceWindows {
    dim: usize,
    tau: usize,
    padded: Vec<f64>,
    sequence: u64,
}

impl SequenceWindows {
    /// The windows of `steps` (rows of `dim` inputs, one after the other).
    pub fn new(dim: usize, tau: usize, steps: &[f64]) -> SequenceWindows {
        let mut padded = vec![0.0; tau * dim];
        padded.extend_from_slice(&steps[..steps.len() / dim * dim]);
        SequenceWindows {
            dim,
            tau,
            padded,
            sequence: Stamp::fresh().sequence,
        }
    }

    /// Inputs in the sequence.
    pub fn len(&self) -> usize {
        self.padded.len() / self.dim - self.tau
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The window after the first `n` inputs (n = 0 ..= len: all padding at 0) and its
    /// stamp.
    pub fn after(&self, n: usize) -> (&[f64], Stamp) {
        let d = self.dim;
        (
            &self.padded[n * d..(n + self.tau) * d],
            Stamp {
                sequence: self.sequence,
                step: n as u64,
            },
        )
    }
}
