//! Experiments: protocols that combine features, models and evaluation into results.

pub mod stability;
