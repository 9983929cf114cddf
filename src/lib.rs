//! Tactile Workbench: learning from robot touch.
//!
//! Data flows one way: `session` → `features` → models (`sparse`, `svm`, `gp`, `learners`,
//! `cluster`) → `experiments` → `figures` and the `app`. Engine modules never import the
//! app or egui; the `gui` feature (on by default) adds the window.

pub mod catalogue;
pub mod cli;
pub mod cluster;
pub mod compare;
pub mod error;
pub mod experiments;
pub mod features;
pub mod figures;
pub mod fsutil;
pub mod gp;
pub mod jobs;
pub mod learners;
pub mod linalg;
pub mod live;
pub mod models;
pub mod perturb;
pub mod project;
pub mod rng;
pub mod session;
pub mod sparse;
pub mod special;
pub mod svm;
pub mod sweep;
#[cfg(test)]
mod test_datasets;

#[cfg(feature = "gui")]
pub mod app;
