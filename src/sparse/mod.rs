//! Efficient sparse coding (Lee, Battle, Raina & Ng 2007): exact feature-sign search for
//! L1-penalised codes, a damped Newton solver for the epsilon-L1 codes, the Lagrange dual
//! for the dictionary, and batch dictionary learning alternating the two.
//!
//! # Objective convention (used everywhere in the project and in exported results)
//!
//! Patches are the rows `x_i` (dimension `n`) of a matrix `X` (N × n); the dictionary `D`
//! holds one basis vector ("atom") per row (K × n); codes are rows `a_i` (K). We use the
//! scikit-learn convention, per patch and averaged over patches:
//!
//! ```text
//! F(D, A) = (1/N) Σ_i [ 0.5 ||x_i − a_i D||² + penalty · Σ_j φ(a_ij) ]
//! subject to ||d_j||² ≤ c for every basis vector (c = 1 unless set)
//! ```
//!
//! with φ(a) = |a| (L1) or φ(a) = sqrt(a² + ε) (epsilon-L1, the paper's eq. 2). While
//! learning the dictionary the penalty is `beta`; when coding (reconstruction, eq. 3) it is
//! `gamma`. With this convention the all-zero code of a z-scored patch of n taxels costs
//! n/2 and the useful range of `beta`/`gamma` on z-scored data is roughly 0.1–5. The paper
//! writes its objectives without the factor 0.5 (eq. 2, eq. 3); a penalty written that way
//! is twice ours (β_paper = 2 β_ours), and its β = 950, γ = 1000 were on its sensors' raw
//! scale, so they do not transfer to standardised data.

mod dictionary;
mod dual;
mod eps_l1;
mod feature_sign;
mod init;

pub use dictionary::{
    CodePenalty, Dictionary, DictionaryFit, DictionaryParams, IterationRecord, encode, objective,
};
pub use dual::{DualStats, basis_step_dual};
pub use eps_l1::{EpsL1Newton, eps_l1_objective};
pub use feature_sign::{FeatureSign, FsStats, l1_objective, l1_optimality_violation};
pub use init::DictInit;

/// Errors of the sparse-coding engine: bad parameters or data, or a cancelled run, never a
/// panic (the numeric methods' shared error).
pub type SparseError = crate::error::MethodError;
