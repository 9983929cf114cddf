use clap::Parser;
use tactile_workbench::cli::{self, Cli};

fn main() -> std::process::ExitCode {
    let started = std::time::Instant::now();
    let args = Cli::parse();
    let result = match args.command {
        Some(command) => cli::run(command),
        None => open_window(
            args.files,
            args.view,
            args.measure_startup,
            args.measure_frames,
            started,
        ),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", cli::error_line(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(feature = "gui")]
fn open_window(
    files: Vec<std::path::PathBuf>,
    view: Option<cli::View>,
    measure_startup: bool,
    measure_frames: Option<f64>,
    started: std::time::Instant,
) -> anyhow::Result<()> {
    use tactile_workbench::app::Measure;
    let measure = match (measure_frames, measure_startup) {
        (Some(seconds), _) => Some(Measure::Frames { seconds }),
        (None, true) => Some(Measure::Startup(started)),
        (None, false) => None,
    };
    tactile_workbench::app::run(files, view, measure)
}

#[cfg(not(feature = "gui"))]
fn open_window(
    _files: Vec<std::path::PathBuf>,
    _view: Option<cli::View>,
    _measure_startup: bool,
    _measure_frames: Option<f64>,
    _started: std::time::Instant,
) -> anyhow::Result<()> {
    anyhow::bail!("this build has no window (built without the `gui` feature); see --help")
}
