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

use std::fmt;
use std::ops::Deref;
use std::sync::Arc;

use crate::jobs::Cancelled;

/// A lower error kept as the `#[source]` of an error when it cannot be held as it is: an
/// error of the same type (a model file's error holding its field's), or one that is not
/// `Clone` and `PartialEq` (a JSON parser's) inside an error that is (the method layers'
/// errors are compared in tests). Shared, equal when it says the same, shown as the error it
/// keeps; and, as it derefs to that error, the `source()` of the error that holds it is the
/// kept error itself (a `Box<E>` would hand on only `E`'s own source).
#[derive(Debug)]
pub struct Kept<E: ?Sized>(Arc<E>);

impl<E> Kept<E> {
    pub fn new(e: E) -> Kept<E> {
        Kept(Arc::new(e))
    }
}

impl Kept<dyn std::error::Error + Send + Sync> {
    /// Any error, kept as it is (a session file's I/O or JSON error).
    pub fn any(e: impl std::error::Error + Send + Sync + 'static) -> Self {
        Kept(Arc::new(e))
    }
}

impl<E: ?Sized> Deref for Kept<E> {
    type Target = E;
    fn deref(&self) -> &E {
        &self.0
    }
}

impl<E: ?Sized> Clone for Kept<E> {
    fn clone(&self) -> Self {
        Kept(Arc::clone(&self.0))
    }
}

impl<E: fmt::Display + ?Sized> PartialEq for Kept<E> {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || self.0.to_string() == other.0.to_string()
    }
}

impl<E: fmt::Display + ?Sized> fmt::Display for Kept<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// Why a numeric method refused or stopped its work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MethodError {
    #[error("invalid parameter: {0}")]
    Param(String),
    #[error("invalid data: {0}")]
    Data(String),
    /// Data that does not take the shape the method gives it (ndarray's error kept).
    #[error("invalid data: {0}")]
    Shape(#[from] ndarray::ShapeError),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for MethodError {
    fn from(_: Cancelled) -> Self {
        MethodError::Cancelled
    }
}
