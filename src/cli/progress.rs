//! Progress of a long command on stderr, read from the engine's [`Progress`]: on a
//! terminal a bar with the time left (indicatif); otherwise one line every few seconds, for
//! batch logs (Slurm writes them to files); nothing with `--quiet`.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::jobs::Progress;

/// Seconds between two lines when stderr is not a terminal.
const LINE_SECS: u64 = 5;
/// Steps of the bar (the fraction is drawn in thousandths).
const STEPS: u64 = 1000;

fn clock(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    if s >= 3600 {
        format!("{}h{:02}m{:02}s", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}m{:02}s", s / 60, s % 60)
    }
}

/// One log line: share done, time spent, time left and what is being done.
fn line(p: &Progress) -> String {
    let left = p
        .eta_secs()
        .map_or_else(|| "?".into(), |s| format!("about {}", clock(s)));
    format!(
        "[{:>5.1} %] {} elapsed, {left} left: {}",
        100.0 * p.fraction(),
        clock(p.elapsed_secs()),
        p.message()
    )
}

fn watch_bar(p: &Progress, done: &AtomicBool) {
    let bar = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {percent:>3}% {eta_precise} left  {wide_msg}",
        )
        .expect("a valid template")
        .progress_chars("=> "),
    );
    while !done.load(Ordering::Relaxed) {
        bar.set_position((p.fraction() * STEPS as f64) as u64);
        bar.set_message(p.message());
        std::thread::sleep(Duration::from_millis(100));
    }
    bar.finish_and_clear();
}

fn watch_lines(p: &Progress, done: &AtomicBool) {
    let mut last = Instant::now();
    while !done.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(100));
        if last.elapsed() >= Duration::from_secs(LINE_SECS) {
            eprintln!("{}", line(p));
            last = Instant::now();
        }
    }
}

/// Run `f` with a fresh [`Progress`], showing it on stderr unless `quiet`.
pub fn with_progress<T>(quiet: bool, f: impl FnOnce(&Progress) -> T) -> T {
    let progress = Progress::new();
    if quiet {
        return f(&progress);
    }
    let done = Arc::new(AtomicBool::new(false));
    let terminal = std::io::stderr().is_terminal();
    let watcher = {
        let (p, done) = (progress.clone(), done.clone());
        std::thread::spawn(move || {
            if terminal {
                watch_bar(&p, &done)
            } else {
                watch_lines(&p, &done)
            }
        })
    };
    let out = f(&progress);
    done.store(true, Ordering::Relaxed);
    let _ = watcher.join();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_line_names_share_time_left_and_message() {
        let p = Progress::new();
        p.set(0.25, "grid search: 3/12");
        let l = line(&p);
        assert!(l.starts_with("[ 25.0 %] 0m00s elapsed, about "), "{l}");
        assert!(l.ends_with("left: grid search: 3/12"), "{l}");
        assert_eq!(clock(3725.0), "1h02m05s");
        assert_eq!(clock(65.0), "1m05s");
    }
}
