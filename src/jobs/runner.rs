//! Running engine work on a worker thread: the UI keeps a `Job` handle, reads its progress
//! each frame, may cancel it, and takes the result when it is done. A job that fails or
//! panics ends with an error message; nothing else is disturbed.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Instant;

use super::{Cancelled, Progress};

/// How a job ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome<T> {
    Done(T),
    Cancelled,
    Failed(String),
}

/// Errors a job body returns: cancellation, or any other error as text.
#[derive(Debug, Clone, PartialEq)]
pub enum JobError {
    Cancelled,
    Failed(String),
}

impl From<Cancelled> for JobError {
    fn from(_: Cancelled) -> Self {
        JobError::Cancelled
    }
}

impl JobError {
    pub fn failed(e: impl std::fmt::Display) -> Self {
        JobError::Failed(e.to_string())
    }
}

pub struct Job<T> {
    pub title: String,
    pub progress: Progress,
    started: Instant,
    rx: Receiver<Outcome<T>>,
    outcome: Option<Outcome<T>>,
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

impl<T: Send + 'static> Job<T> {
    /// Start `work` on a new thread. `wake` is called when the job ends (the UI passes a
    /// repaint request so the result shows without input).
    pub fn spawn(
        title: impl Into<String>,
        wake: impl Fn() + Send + 'static,
        work: impl FnOnce(&Progress) -> Result<T, JobError> + Send + 'static,
    ) -> Self {
        let progress = Progress::new();
        let (tx, rx) = channel();
        let p = progress.clone();
        let title = title.into();
        std::thread::Builder::new()
            .name(format!("job: {title}"))
            .spawn(move || {
                let outcome = match catch_unwind(AssertUnwindSafe(|| work(&p))) {
                    Ok(Ok(v)) => Outcome::Done(v),
                    Ok(Err(JobError::Cancelled)) => Outcome::Cancelled,
                    Ok(Err(JobError::Failed(m))) => Outcome::Failed(m),
                    Err(payload) => Outcome::Failed(format!(
                        "internal error (the job crashed): {}",
                        panic_message(payload.as_ref())
                    )),
                };
                let _ = tx.send(outcome);
                wake();
            })
            // If no thread can be started the closure (and its sender) is dropped, and
            // `poll` reports the job as failed.
            .ok();
        Job {
            title,
            progress,
            started: Instant::now(),
            rx,
            outcome: None,
        }
    }

    /// The outcome once the job has ended (None while it runs).
    pub fn poll(&mut self) -> Option<&Outcome<T>> {
        if self.outcome.is_none() {
            match self.rx.try_recv() {
                Ok(o) => self.outcome = Some(o),
                Err(TryRecvError::Disconnected) => {
                    self.outcome = Some(Outcome::Failed(
                        "the worker thread ended without a result".into(),
                    ))
                }
                Err(TryRecvError::Empty) => {}
            }
        }
        self.outcome.as_ref()
    }

    pub fn is_running(&mut self) -> bool {
        self.poll().is_none()
    }

    /// Take the outcome, leaving the job finished.
    pub fn take(&mut self) -> Option<Outcome<T>> {
        self.poll();
        self.outcome.take()
    }

    pub fn cancel(&self) {
        self.progress.cancel();
    }

    pub fn elapsed_secs(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Block until the job ends (for the CLI and tests; never on the UI thread).
    pub fn wait(mut self) -> Outcome<T> {
        if let Some(o) = self.outcome.take() {
            return o;
        }
        self.rx
            .recv()
            .unwrap_or_else(|_| Outcome::Failed("the worker thread ended without a result".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_job_reports_progress_and_returns() {
        let job = Job::spawn(
            "sum",
            || {},
            |p| {
                p.set(0.5, "half way");
                Ok(21 * 2)
            },
        );
        assert_eq!(job.wait(), Outcome::Done(42));
    }

    #[test]
    fn a_panicking_job_fails_with_its_message() {
        let job: Job<()> = Job::spawn("boom", || {}, |_| panic!("index out of range"));
        match job.wait() {
            Outcome::Failed(m) => assert!(m.contains("index out of range"), "{m}"),
            other => panic!("expected failure, got {other:?}"),
        }
    }

    #[test]
    fn an_error_is_reported_and_cancel_stops_at_the_next_checkpoint() {
        let job: Job<()> = Job::spawn(
            "bad",
            || {},
            |_| Err(JobError::failed("beta must be positive")),
        );
        assert_eq!(job.wait(), Outcome::Failed("beta must be positive".into()));

        // Work that only a cancel ends (the minute is a guard against a hang, not a timing).
        let job: Job<u64> = Job::spawn(
            "long",
            || {},
            |p| {
                let t = Instant::now();
                let mut units = 0u64;
                while t.elapsed() < Duration::from_secs(60) {
                    p.checkpoint()?;
                    units += 1;
                    p.set(0.5, units.to_string());
                    std::thread::sleep(Duration::from_millis(1));
                }
                Ok(units)
            },
        );
        while job.progress.message().is_empty() {
            std::thread::sleep(Duration::from_millis(1));
        }
        job.cancel();
        let progress = job.progress.clone();
        assert_eq!(job.wait(), Outcome::Cancelled);
        // The worker has stopped: its count of units no longer advances.
        let stopped = progress.message();
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(progress.message(), stopped);
    }
}
