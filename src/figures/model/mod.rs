//! The figure data model: plain, serialisable data that says what a figure shows, not how a
//! renderer draws it. The export code (plotters) and the workbench views (egui_plot) draw
//! the same `Figure`.
//!
//! Missing values: a NaN (written `null` in JSON) is a missing value. Chart points with a
//! missing coordinate are skipped (the line breaks there) and the legend says how many; a
//! missing heatmap or image cell is drawn as background (for image grids: a cell without a
//! taxel). The CSV export writes them as `NaN`.

mod axis;
mod bars;
mod chart;
mod heatmap;
mod image;
mod nan_serde;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::FigureError;
pub use axis::{Axis, AxisTitle, Scale};
pub use bars::{BarChart, BarGroup};
pub use chart::{
    Chart, ErrorDisplay, ErrorRange, Orientation, RefLine, Series, SeriesStyle, pareto_front,
};
pub use heatmap::{ColorScale, Heatmap};
pub use image::{GridImage, ImageGrid};

/// One figure: a title, an optional subtitle (drawn under the title) and what it shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub title: String,
    #[serde(default)]
    pub subtitle: Option<String>,
    pub kind: FigureKind,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum FigureKind {
    Chart(Chart),
    Bars(BarChart),
    Heatmap(Heatmap),
    ImageGrid(ImageGrid),
}

impl Figure {
    pub fn new(title: impl Into<String>, kind: FigureKind) -> Self {
        Figure {
            title: title.into(),
            subtitle: None,
            kind,
        }
    }

    pub fn subtitle(mut self, subtitle: impl Into<String>) -> Self {
        self.subtitle = Some(subtitle.into());
        self
    }

    /// A line/scatter chart.
    pub fn chart(title: impl Into<String>, x: Axis, y: Axis, series: Vec<Series>) -> Self {
        Figure::new(
            title,
            FigureKind::Chart(Chart {
                x,
                y,
                series,
                ref_lines: Vec::new(),
            }),
        )
    }

    /// Grouped bars.
    pub fn bars(
        title: impl Into<String>,
        x: AxisTitle,
        y: Axis,
        categories: Vec<String>,
        groups: Vec<BarGroup>,
    ) -> Self {
        Figure::new(
            title,
            FigureKind::Bars(BarChart {
                x,
                y,
                categories,
                groups,
                sign_colors: false,
            }),
        )
    }

    /// A heatmap, `values[row][column]`; see [`Heatmap::from_array`] for an ndarray.
    pub fn heatmap(
        title: impl Into<String>,
        x: AxisTitle,
        y: AxisTitle,
        columns: Vec<String>,
        rows: Vec<String>,
        values: Vec<Vec<f64>>,
        colors: ColorScale,
    ) -> Self {
        Figure::new(
            title,
            FigureKind::Heatmap(Heatmap {
                x,
                y,
                columns,
                rows,
                values,
                colors,
                annotate: false,
                marked: Vec::new(),
            }),
        )
    }

    /// Small multiples on one colour scale, arranged near-square.
    pub fn image_grid(
        title: impl Into<String>,
        images: Vec<GridImage>,
        colors: ColorScale,
    ) -> Self {
        Figure::new(
            title,
            FigureKind::ImageGrid(ImageGrid {
                images,
                columns: 0,
                colors,
            }),
        )
    }

    /// Write each heatmap value in its cell (heatmaps only; other kinds are unchanged).
    pub fn annotated(mut self) -> Self {
        if let FigureKind::Heatmap(h) = &mut self.kind {
            h.annotate = true;
        }
        self
    }

    /// Outline a heatmap cell, e.g. the recommended model (heatmaps only).
    pub fn mark(mut self, row: usize, column: usize) -> Self {
        if let FigureKind::Heatmap(h) = &mut self.kind {
            h.marked.push([row, column]);
        }
        self
    }

    /// Colour bars by sign, for a differential (bar charts with one group only).
    pub fn sign_colored(mut self) -> Self {
        if let FigureKind::Bars(b) = &mut self.kind {
            b.sign_colors = true;
        }
        self
    }

    /// Add a reference line (charts only; other kinds are unchanged).
    pub fn ref_line(
        mut self,
        orientation: Orientation,
        value: f64,
        label: impl Into<String>,
    ) -> Self {
        if let FigureKind::Chart(chart) = &mut self.kind {
            chart.ref_lines.push(RefLine {
                orientation,
                value,
                label: label.into(),
            });
        }
        self
    }

    /// Check the figure can be drawn: something to draw, matching lengths, labels for
    /// every row and column. Missing (NaN) values are allowed.
    pub fn validate(&self) -> Result<(), FigureError> {
        let invalid = |msg: String| Err(FigureError::Invalid(format!("{}: {msg}", self.title)));
        // Every axis and colour bar says what it shows.
        let titles: Vec<&str> = match &self.kind {
            FigureKind::Chart(c) => vec![&c.x.title, &c.y.title],
            FigureKind::Bars(b) => vec![&b.x.title, &b.y.title],
            FigureKind::Heatmap(h) => vec![&h.x.title, &h.y.title, &h.colors.title],
            FigureKind::ImageGrid(g) => vec![&g.colors.title],
        };
        if titles.iter().any(|t| t.trim().is_empty()) {
            return invalid("every axis and colour bar needs a title".into());
        }
        let checked = match &self.kind {
            FigureKind::Chart(c) => c.validate(),
            FigureKind::Bars(b) => b.validate(),
            FigureKind::Heatmap(h) => h.validate(),
            FigureKind::ImageGrid(g) => g.validate(),
        };
        checked.or_else(|e| match e {
            FigureError::Invalid(msg) => invalid(msg),
            other => Err(other),
        })
    }
}

/// One figure of an "export all", with where it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureEntry {
    /// File stem of the exported files (letters, digits, `-` and `_` only).
    pub name: String,
    pub figure: Figure,
    /// The parameters that produced it (e.g. `num_bases` → `64`).
    #[serde(default)]
    pub parameters: BTreeMap<String, String>,
    pub session: String,
    /// When it was computed, as the caller writes it (ISO 8601 recommended).
    pub date: String,
}

/// Every figure of a project, for "export all".
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FigureSet {
    pub entries: Vec<FigureEntry>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_round_trips_through_json() {
        let fig = Figure::chart(
            "t",
            Axis::new("x", ""),
            Axis::new("y", ""),
            vec![Series::new("s", vec![1.0, 2.0], vec![f64::NAN, 3.0])],
        );
        let json = serde_json::to_string(&fig).unwrap();
        assert!(json.contains("null"));
        let back: Figure = serde_json::from_str(&json).unwrap();
        let FigureKind::Chart(c) = back.kind else {
            panic!("kind changed")
        };
        assert!(c.series[0].y[0].is_nan());
        assert_eq!(c.series[0].y[1], 3.0);
    }

    #[test]
    fn validation_rejects_bad_shapes() {
        let bad = Figure::chart(
            "t",
            Axis::new("x", ""),
            Axis::new("y", ""),
            vec![Series::new("s", vec![1.0, 2.0], vec![1.0])],
        );
        assert!(matches!(bad.validate(), Err(FigureError::Invalid(m)) if m.contains("\"s\"")));
        let empty = Figure::chart("t", Axis::new("x", ""), Axis::new("y", ""), vec![]);
        assert!(empty.validate().is_err());
        let untitled = Figure::chart(
            "t",
            Axis::new(" ", "s"),
            Axis::new("y", ""),
            vec![Series::new("s", vec![1.0], vec![1.0])],
        );
        assert!(matches!(untitled.validate(), Err(FigureError::Invalid(m)) if m.contains("title")));
        let heat = Figure::new(
            "h",
            FigureKind::Heatmap(Heatmap {
                x: AxisTitle::new("p", ""),
                y: AxisTitle::new("t", ""),
                columns: vec!["a".into(), "b".into()],
                rows: vec!["a".into()],
                values: vec![vec![1.0]],
                colors: ColorScale::viridis("count", ""),
                annotate: false,
                marked: vec![],
            }),
        );
        assert!(heat.validate().is_err());
    }
}
