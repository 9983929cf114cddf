//! The online infinite echo-state Gaussian process (OIESGP) of the second paper: a sparse
//! online GP (Csató & Opper) with a recursive ARD kernel over the input history and
//! stochastic natural-gradient hyperparameter adaptation.

mod inputs;
pub mod kernel;
pub mod normal;
pub mod sngd;
pub mod sogp;
mod wide;

pub use kernel::{KernelParams, LagMajor, RecursiveArd, SequenceWindows, Stamp, Window};
pub use sngd::{Sngd, SngdParams};
pub use sogp::{Likelihood, Sogp, SogpParams};

/// Errors of the GP engine: bad parameters name the parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
}

impl GpError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> GpError {
        GpError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}
