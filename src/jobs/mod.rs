//! Background work: progress, cancellation, errors, worker threads.

mod progress;
mod runner;

pub use progress::{Cancelled, Progress};
pub use runner::{Job, JobError, Outcome};
