//! Background work: progress, cancellation, errors, worker threads, expected run times.

pub mod estimate;
mod progress;
mod runner;

pub use progress::{Cancelled, Progress};
pub use runner::{Job, JobError, Outcome};
