//! `render-figure`: draw a serialised [`Figure`] to a file, to check the figure layer from
//! the shell.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::figures::{Figure, RenderOptions, write_figure};

#[derive(Args, Debug)]
pub struct RenderFigureArgs {
    /// The figure, as JSON (the serde form of `figures::Figure`).
    pub figure: PathBuf,
    /// Output file; the extension (.svg, .png or .csv) picks the format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Width in pixels.
    #[arg(long, default_value_t = RenderOptions::default().width)]
    pub width: u32,
    /// Height in pixels.
    #[arg(long, default_value_t = RenderOptions::default().height)]
    pub height: u32,
    /// Resolution: text and lines scale with dpi / 96.
    #[arg(long, default_value_t = RenderOptions::default().dpi)]
    pub dpi: f64,
}

pub fn run(args: RenderFigureArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(Some(&args.output), &[&args.figure])?;
    let text = std::fs::read_to_string(&args.figure)
        .with_context(|| format!("cannot read {}", args.figure.display()))?;
    let figure: Figure = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a valid figure", args.figure.display()))?;
    let opts = RenderOptions {
        width: args.width,
        height: args.height,
        dpi: args.dpi,
    };
    write_figure(&figure, &args.output, &opts)?;
    println!("wrote {}", args.output.display());
    Ok(())
}
