//! `stability` (the first paper's pipeline on any session), `bench-stability` (its
//! speed on BTS3 palm-down) and `bench-held-out` (its methods on held-out sessions).
//!
//! The folder: `args` turns the command line into the pipeline's options, `report` prints
//! a run's summary, `bench` is `bench-stability` and `held_out` `bench-held-out`.

mod args;
mod bench;
mod held_out;
mod report;

use std::path::Path;

use anyhow::Context;
use serde::Serialize;

use super::progress::with_progress;
use crate::experiments::stability::{self, StabilityData};
use crate::session::{self, Session};
pub use args::{
    GridPreset, InitArg, LossArg, PenaltyArg, StabilityArgs, data_options, options_from, parse_cv,
};
pub use bench::{BenchStabilityArgs, run_bench};
pub use held_out::{BTS3V2_TEST, BTS3V2_TRAIN, BenchHeldOutArgs, bench_held_out};
use report::report;

/// Open a native session, or import the BTS3 CSV.
pub fn open(path: &Path) -> anyhow::Result<Session> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        session::import_bts3(path).with_context(|| format!("importing {}", path.display()))
    } else {
        session::load(path).with_context(|| format!("loading {}", path.display()))
    }
}

pub(crate) fn in_pool<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    match threads {
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()?
            .install(f)),
        None => Ok(f()),
    }
}

fn write_json(path: &Path, value: &impl Serialize) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    crate::fsutil::write_atomic(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

pub fn run(a: StabilityArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(a.json.as_deref(), &[&a.session])?;
    super::refuse_input_as_output(a.save_model.as_deref(), &[&a.session])?;
    let session = open(&a.session)?;
    let data = StabilityData::from_session(&session, &data_options(&a))?;
    let opts = options_from(&a, &data)?;
    let report = in_pool(a.threads, || {
        with_progress(a.quiet, |p| stability::run(&data, &opts, p))
    })??;
    print!("{}", self::report(&report));
    if let Some(path) = &a.json {
        write_json(path, &report)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &a.save_model {
        let file =
            crate::models::stability::StabilityFit::from_report(&session, &data, &opts, &report)
                .into_file(&session, &data);
        crate::models::save(&file, path)?;
        println!("wrote {} ({})", path.display(), file.provenance.summary());
    }
    Ok(())
}
