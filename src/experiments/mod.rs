//! Experiments: the papers' protocols run end to end, and what they leave behind.

pub mod baselines_report;
pub mod report;
