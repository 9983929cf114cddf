//! The error the numeric methods share: a parameter out of range, data the method cannot
//! use, or a cancelled run. The sparse coder ([`crate::sparse::SparseError`]), the linear
//! SVM ([`crate::svm::SvmError`]) and the stability pipeline
//! ([`crate::experiments::stability::StabilityError`]) all refuse work for these three
//! reasons, so they name this one type (the first two as aliases of it).
//!
//! The convention of every engine error: a variant that wraps a lower layer's error keeps
//! it as its `source()` (`#[from]` / `#[source]`, never its text), and shows it in its own
//! message too, because the window shows one line; the command line prints the chain
//! without repeating a cause already in the message. `Result<_, String>` is for the window
//! and the command line only (`tests/typed_errors.rs` counts).

use crate::jobs::Cancelled;

/// Why a numeric method refused or stopped its work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MethodError {
    #[error("invalid parameter: {0}")]
    Param(String),
    #[error("invalid data: {0}")]
    Data(String),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for MethodError {
    fn from(_: Cancelled) -> Self {
        MethodError::Cancelled
    }
}
