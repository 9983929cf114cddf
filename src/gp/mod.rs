//! The online infinite echo-state Gaussian process (OIESGP) of the second paper: a sparse
//! online GP (Csató & Opper) with a recursive ARD kernel over the input history and
//! stochastic natural-gradient hyperparameter adaptation.
//!
//! A model's state saves and loads with serde ([`Sogp`], [`Sngd`] and [`Window`] implement
//! `Serialize` and `Deserialize`): the file holds what the model has learnt (the BVs, their
//! targets, α, C, Q, the hyperparameters, the optimiser's window, the counters) and the
//! caches derived from it are rebuilt on load, bit for bit. Deserialising is the checked
//! constructor: a state whose lengths, dimensions, counts or values disagree is an
//! [`GpError::InvalidState`] naming the field, so an inconsistent model cannot be obtained.

mod bits;
pub(crate) mod floats;
mod inputs;
pub mod kernel;
pub mod normal;
mod pairs;
mod quotient;
pub mod sngd;
pub mod sogp;
mod wide;
pub mod window;

pub(crate) use inputs::shared::SharedInputs;
pub use kernel::{KernelParams, LagMajor, RecursiveArd};
pub use pairs::{MAX_PAIR_INPUTS, PairDistances};
pub use sngd::{Sngd, SngdParams};
pub use sogp::{Likelihood, Sogp, SogpParams};
pub use window::{SequenceWindows, Stamp, Window};

/// Errors of the GP engine: bad parameters name the parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    /// A saved state that no model could have reached (a damaged or crafted file).
    #[error("invalid state `{field}`: {reason}")]
    InvalidState { field: String, reason: String },
}

impl GpError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> GpError {
        GpError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }

    pub(crate) fn state(field: impl Into<String>, reason: impl Into<String>) -> GpError {
        GpError::InvalidState {
            field: field.into(),
            reason: reason.into(),
        }
    }

    /// The error as one of the state inside `prefix` (`models[2]` makes `alpha` into
    /// `models[2].alpha`).
    pub fn within(self, prefix: &str) -> GpError {
        match self {
            GpError::InvalidParameter { name, reason } => {
                GpError::state(format!("{prefix}.{name}"), reason)
            }
            GpError::InvalidState { field, reason } => {
                GpError::state(format!("{prefix}.{field}"), reason)
            }
        }
    }
}
