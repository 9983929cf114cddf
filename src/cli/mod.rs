//! The headless command line: the same binary as the window, with subcommands.
//! Each subcommand lives in its own file with its `clap::Args` struct and a `run`.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "tactile-workbench",
    version,
    about = "Learn from robot touch: open the workbench, or run a headless command",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Session files to open in the workbench (with no subcommand).
    pub files: Vec<PathBuf>,
}

#[derive(Subcommand, Debug)]
pub enum Command {}

/// Run a subcommand. Returns the process exit code.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {}
}
