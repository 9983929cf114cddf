//! Figures: renderer-independent figure data ([`Figure`]) and its export to SVG, PNG and CSV.
//!
//! The engine builds a `Figure` from a result; the workbench draws it on screen and this
//! module writes it to files, so that a figure on paper shows the same numbers as the view.
//! Export draws with plotters and a font embedded in the binary (Ubuntu Light, from
//! `epaint_default_fonts`), so it works on machines without system fonts.

mod canvas;
pub mod colormap;
mod csv;
mod export;
pub mod model;
mod render;

use std::path::PathBuf;

pub use colormap::ColorMap;
pub use csv::to_csv;
pub use export::{
    Format, Index, IndexEntry, RenderOptions, export_all, render_png, render_svg, write_figure,
};
pub use model::{
    Axis, AxisTitle, BarChart, BarGroup, Chart, ColorScale, ErrorDisplay, ErrorRange, Figure,
    FigureEntry, FigureKind, FigureSet, GridImage, Heatmap, ImageGrid, Orientation, RefLine, Rgb,
    Scale, Series, SeriesStyle, pareto_front,
};

#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("invalid figure: {0}")]
    Invalid(String),
    #[error("invalid export options: {0}")]
    Options(String),
    #[error("drawing failed: {0}")]
    Render(String),
    #[error("cannot write {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}
