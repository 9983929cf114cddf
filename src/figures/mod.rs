//! Figures: renderer-independent figure data ([`Figure`]) and its export to SVG, PNG and CSV.
//!
//! The engine builds a `Figure` from a result; the workbench draws it on screen and this
//! module writes it to files, so that a figure on paper shows the same numbers as the view.
//! Export draws with plotters and a font embedded in the binary (Ubuntu Light, from
//! `epaint_default_fonts`), so it works on machines without system fonts.
//!
//! ```
//! use tactile_workbench::figures::*;
//!
//! let fig = Figure::chart(
//!     "Accuracy as trials progress",
//!     Axis::new("Trials", ""),
//!     Axis::new("Accuracy", "%").including(0.0, 100.0),
//!     vec![
//!         Series::new("DS", vec![1.0, 2.0, 3.0], vec![60.0, 75.0, 90.0])
//!             .band(vec![55.0, 70.0, 86.0], vec![65.0, 80.0, 94.0]),
//!         Series::new("GS", vec![1.0, 2.0, 3.0], vec![50.0, 70.0, 85.0]),
//!     ],
//! )
//! .ref_line(Orientation::Vertical, 2.0, "threshold");
//! let svg = render_svg(&fig, &RenderOptions::default()).unwrap();
//! assert!(svg.contains("Accuracy (%)"));
//!
//! let confusion = Figure::heatmap(
//!     "Confusion matrix",
//!     AxisTitle::new("Predicted", ""),
//!     AxisTitle::new("True", ""),
//!     vec!["success".into(), "failure".into()],
//!     vec!["success".into(), "failure".into()],
//!     vec![vec![40.0, 2.0], vec![5.0, 30.0]],
//!     ColorScale::viridis("Grasps", "count"),
//! )
//! .annotated();
//! assert!(to_csv(&confusion).unwrap().contains("success,40,2"));
//! ```

mod canvas;
pub mod colormap;
mod csv;
mod export;
pub mod layout;
pub mod legibility;
pub mod model;
mod render;

use std::path::PathBuf;

pub use colormap::Rgb;
pub use colormap::{ColorMap, series_color};
pub use csv::{row as csv_row, to_csv};
pub use export::{
    Format, Index, IndexEntry, NotDrawn, RenderOptions, export_all, layout_of, render_pdf,
    render_png, render_svg, write_figure,
};
pub use layout::{AxisLabels, Bounds, FigureLayout, PlacedText};
pub use model::{
    Axis, AxisTitle, BarChart, BarGroup, Chart, ColorScale, ErrorDisplay, ErrorRange, Figure,
    FigureEntry, FigureKind, FigureSet, GridImage, Heatmap, ImageGrid, Orientation, RefLine, Scale,
    Series, SeriesStyle, pareto_front,
};
pub use render::{
    axis_limits, axis_ticks, bar_limits, chart_limits, fitted_axis_ticks, tick_label,
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
