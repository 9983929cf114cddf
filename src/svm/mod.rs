//! Support vector machines and their evaluation: the linear SVM (dual coordinate descent
//! and primal Newton), the RBF-kernel SVM (SMO), cross-validation folds and the paper's
//! scores.

pub mod eval;
pub mod kernel_svm;
pub mod linear;

pub use eval::{
    Confusion, CvResult, FoldScore, Folds, cross_validate, gather, group_k_fold, mean_se,
    stratified_k_fold,
};
pub use linear::{ClassWeight, LinearSvm, LinearSvmParams, Loss, Solver, SvmWorkspace};

/// Errors of the SVM engine: bad parameters or data, or a cancelled run, never a panic (the
/// numeric methods' shared error).
pub type SvmError = crate::error::MethodError;
