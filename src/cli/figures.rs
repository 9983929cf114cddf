//! `render-figure`: draw a serialised [`Figure`] to a file, to check the figure layer from
//! the shell.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};

use crate::figures::{Figure, RenderOptions, write_figure};

/// Sizes for a paper, or the size given by --width, --height and --dpi.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Preset {
    /// A journal column: 3.5 in at 300 DPI (1050 × 700 px), 8–9 pt text.
    Column,
    /// A full page width: 7 in at 300 DPI (2100 × 1050 px), 8–9 pt text.
    Page,
}

impl Preset {
    pub fn options(self) -> RenderOptions {
        match self {
            Preset::Column => RenderOptions::column(),
            Preset::Page => RenderOptions::page(),
        }
    }
}

#[derive(Args, Debug)]
pub struct RenderFigureArgs {
    /// The figure, as JSON (the serde form of `figures::Figure`).
    pub figure: PathBuf,
    /// Output file; the extension (.svg, .png, .pdf or .csv) picks the format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// A size for a paper; replaces --width, --height and --dpi.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
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
    let reader = crate::fsutil::open_json(&args.figure, crate::fsutil::max_bytes::FIGURE, "figure")
        .with_context(|| format!("cannot read {}", args.figure.display()))?;
    let figure: Figure = serde_json::from_reader(reader)
        .with_context(|| format!("{} is not a valid figure", args.figure.display()))?;
    let opts = args.preset.map_or(
        RenderOptions {
            width: args.width,
            height: args.height,
            dpi: args.dpi,
        },
        Preset::options,
    );
    // Figures whose axes cannot be drawn (non-finite or overflowing ranges) are refused
    // by the renderer with the axis named.
    write_figure(&figure, &args.output, &opts)
        .with_context(|| format!("cannot render {}", args.figure.display()))?;
    println!("wrote {}", args.output.display());
    Ok(())
}
