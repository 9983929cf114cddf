//! Background work: progress, cancellation, errors.

mod progress;

pub use progress::{Cancelled, Progress};
