//! The figure data model: plain, serialisable data that says what a figure shows, not how a
//! renderer draws it. The export code (plotters) and the workbench views (egui_plot) draw
//! the same `Figure`.
//!
//! Missing values: a NaN (written `null` in JSON) is a missing value. Chart points with a
//! missing coordinate are skipped (the line breaks there) and the legend says how many; a
//! missing heatmap or image cell is drawn as background (for image grids: a cell without a
//! taxel). The CSV export writes them as `NaN`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::FigureError;
use super::colormap::ColorMap;
use crate::session::Layout;

/// An sRGB colour, serialised as `[r, g, b]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rgb(pub u8, pub u8, pub u8);

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

/// A categorical axis: only a title and a unit (empty for a dimensionless quantity).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisTitle {
    pub title: String,
    #[serde(default)]
    pub unit: String,
}

impl AxisTitle {
    pub fn new(title: impl Into<String>, unit: impl Into<String>) -> Self {
        AxisTitle {
            title: title.into(),
            unit: unit.into(),
        }
    }

    /// "Title (unit)", or just the title for a dimensionless quantity.
    pub fn text(&self) -> String {
        axis_text(&self.title, &self.unit)
    }
}

fn axis_text(title: &str, unit: &str) -> String {
    if unit.is_empty() {
        title.to_string()
    } else {
        format!("{title} ({unit})")
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    #[default]
    Linear,
    /// Base-10 logarithmic; values ≤ 0 cannot be drawn and are skipped like missing ones.
    Log,
}

impl Scale {
    /// Can `v` be drawn on an axis of this scale? (Finite, and positive on a log axis.)
    /// Values that cannot are skipped and counted as missing.
    pub fn can_draw(self, v: f64) -> bool {
        v.is_finite() && (self == Scale::Linear || v > 0.0)
    }
}

/// A numeric axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    pub title: String,
    #[serde(default)]
    pub unit: String,
    #[serde(default)]
    pub scale: Scale,
    /// A range the axis must show in addition to the data (e.g. `[0, 1]` for an accuracy).
    /// Data is never clipped: the axis always covers every drawn value.
    #[serde(default)]
    pub include: Option<[f64; 2]>,
}

impl Axis {
    pub fn new(title: impl Into<String>, unit: impl Into<String>) -> Self {
        Axis {
            title: title.into(),
            unit: unit.into(),
            scale: Scale::Linear,
            include: None,
        }
    }

    pub fn log(mut self) -> Self {
        self.scale = Scale::Log;
        self
    }

    pub fn including(mut self, lo: f64, hi: f64) -> Self {
        self.include = Some([lo, hi]);
        self
    }

    pub fn text(&self) -> String {
        axis_text(&self.title, &self.unit)
    }
}

/// Line and scatter charts (accuracy curves, sweeps, speed against accuracy).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chart {
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    /// Vertical or horizontal reference lines (a threshold, chance level).
    #[serde(default)]
    pub ref_lines: Vec<RefLine>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SeriesStyle {
    #[default]
    Line,
    Markers,
    LineMarkers,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub name: String,
    #[serde(with = "nan_as_null")]
    pub x: Vec<f64>,
    #[serde(with = "nan_as_null")]
    pub y: Vec<f64>,
    #[serde(default)]
    pub style: SeriesStyle,
    #[serde(default)]
    pub error: Option<ErrorRange>,
    /// One label per point (empty strings for unlabelled points), or none at all.
    #[serde(default)]
    pub point_labels: Vec<String>,
    /// Colour; by default the next colour of a colour-blind-safe palette.
    #[serde(default)]
    pub color: Option<Rgb>,
}

impl Series {
    pub fn new(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series {
            name: name.into(),
            x,
            y,
            style: SeriesStyle::Line,
            error: None,
            point_labels: Vec::new(),
            color: None,
        }
    }

    pub fn style(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }

    /// Error band (shaded) from `lower` to `upper`, both absolute y values.
    pub fn band(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Self {
        self.error = Some(ErrorRange {
            display: ErrorDisplay::Band,
            lower,
            upper,
        });
        self
    }

    /// Error bars from `lower` to `upper`, both absolute y values.
    pub fn error_bars(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Self {
        self.error = Some(ErrorRange {
            display: ErrorDisplay::Bars,
            lower,
            upper,
        });
        self
    }

    pub fn labels(mut self, labels: Vec<String>) -> Self {
        self.point_labels = labels;
        self
    }

    pub fn color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorDisplay {
    Band,
    Bars,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorRange {
    pub display: ErrorDisplay,
    #[serde(with = "nan_as_null")]
    pub lower: Vec<f64>,
    #[serde(with = "nan_as_null")]
    pub upper: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Orientation {
    /// A vertical line at an x value.
    Vertical,
    /// A horizontal line at a y value.
    Horizontal,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefLine {
    pub orientation: Orientation,
    pub value: f64,
    #[serde(default)]
    pub label: String,
}

/// Grouped bars: one bar per group for each category (e.g. usage of each basis per label).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BarChart {
    pub x: AxisTitle,
    /// Must be linear: bars start at 0.
    pub y: Axis,
    pub categories: Vec<String>,
    pub groups: Vec<BarGroup>,
    /// Colour each bar by its sign (blue negative, red positive), for a differential.
    /// Only with a single group, whose identity would otherwise be lost.
    #[serde(default)]
    pub sign_colors: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BarGroup {
    pub name: String,
    #[serde(with = "nan_as_null")]
    pub values: Vec<f64>,
    /// Symmetric error half-widths, one per category.
    #[serde(default, with = "opt_nan_as_null")]
    pub error: Option<Vec<f64>>,
    #[serde(default)]
    pub color: Option<Rgb>,
}

impl BarGroup {
    pub fn new(name: impl Into<String>, values: Vec<f64>) -> Self {
        BarGroup {
            name: name.into(),
            values,
            error: None,
            color: None,
        }
    }

    pub fn errors(mut self, half_widths: Vec<f64>) -> Self {
        self.error = Some(half_widths);
        self
    }
}

/// How values map to colours, and the colour bar that explains it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorScale {
    pub map: ColorMap,
    /// Colour bar title and unit.
    pub title: String,
    #[serde(default)]
    pub unit: String,
    /// Fixed limits; by default the data's range (made symmetric for the diverging map).
    #[serde(default)]
    pub limits: Option<[f64; 2]>,
}

impl ColorScale {
    pub fn viridis(title: impl Into<String>, unit: impl Into<String>) -> Self {
        ColorScale {
            map: ColorMap::Viridis,
            title: title.into(),
            unit: unit.into(),
            limits: None,
        }
    }

    pub fn diverging(title: impl Into<String>, unit: impl Into<String>) -> Self {
        ColorScale {
            map: ColorMap::Diverging,
            title: title.into(),
            unit: unit.into(),
            limits: None,
        }
    }

    pub fn text(&self) -> String {
        axis_text(&self.title, &self.unit)
    }

    /// The colour limits for these values.
    pub fn resolve(&self, values: impl IntoIterator<Item = f64>) -> (f64, f64) {
        self.map
            .limits(values, self.limits.map(|[lo, hi]| (lo, hi)))
    }
}

/// A matrix of values with row and column labels (confusion matrices, grid-search maps).
/// Row 0 is drawn at the top.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Heatmap {
    pub x: AxisTitle,
    pub y: AxisTitle,
    pub columns: Vec<String>,
    pub rows: Vec<String>,
    /// `values[row][column]`.
    #[serde(with = "matrix_nan_as_null")]
    pub values: Vec<Vec<f64>>,
    pub colors: ColorScale,
    /// Write each value in its cell (when the cells are large enough for the text).
    #[serde(default)]
    pub annotate: bool,
    /// Cells to outline, as `[row, column]` (e.g. the recommended model of a grid search).
    #[serde(default)]
    pub marked: Vec<[usize; 2]>,
}

impl Heatmap {
    /// A heatmap of `values` (`values[row][column]`), from an ndarray matrix.
    pub fn from_array(
        x: AxisTitle,
        y: AxisTitle,
        columns: Vec<String>,
        rows: Vec<String>,
        values: ndarray::ArrayView2<'_, f64>,
        colors: ColorScale,
    ) -> Self {
        Heatmap {
            x,
            y,
            columns,
            rows,
            values: values.outer_iter().map(|r| r.to_vec()).collect(),
            colors,
            annotate: false,
            marked: Vec::new(),
        }
    }
}

/// Small multiples: images of equal shape (basis images, patches) on one colour scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageGrid {
    pub images: Vec<GridImage>,
    /// Images per row of the grid; 0 picks a near-square arrangement.
    #[serde(default)]
    pub columns: usize,
    pub colors: ColorScale,
}

/// One image; `values[0]` is the top row as drawn. A missing value is a cell without a
/// taxel, drawn as background.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridImage {
    #[serde(default)]
    pub caption: String,
    #[serde(with = "matrix_nan_as_null")]
    pub values: Vec<Vec<f64>>,
}

impl GridImage {
    /// Arrange one value per taxel as the sensor's image: the layout's row 0 (the sensor's
    /// base) is drawn at the bottom, cells without a taxel are missing.
    pub fn from_layout(
        caption: impl Into<String>,
        taxel_values: &[f64],
        layout: &Layout,
    ) -> Result<Self, FigureError> {
        let (rows, cols) = layout.grid_shape().ok_or_else(|| {
            FigureError::Invalid("a point layout has no grid to draw an image on".into())
        })?;
        if taxel_values.len() != layout.taxel_count() {
            return Err(FigureError::Invalid(format!(
                "{} values for a layout of {} taxels",
                taxel_values.len(),
                layout.taxel_count()
            )));
        }
        let mut values = vec![vec![f64::NAN; cols]; rows];
        for (i, &v) in taxel_values.iter().enumerate() {
            match layout.grid_cell(i) {
                Some((r, c)) if r < rows && c < cols => values[rows - 1 - r][c] = v,
                _ => {
                    return Err(FigureError::Invalid(format!(
                        "taxel {i} lies outside its {rows}×{cols} grid"
                    )));
                }
            }
        }
        Ok(GridImage {
            caption: caption.into(),
            values,
        })
    }
}

/// The non-dominated points for "less x is better, more y is better" (training time
/// against accuracy), as indices sorted by increasing x. Points with a non-finite
/// coordinate are ignored.
pub fn pareto_front(x: &[f64], y: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..x.len().min(y.len()))
        .filter(|&i| x[i].is_finite() && y[i].is_finite())
        .collect();
    // Ties in x: the best y first, so that the others are dominated.
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]).then(y[b].total_cmp(&y[a])));
    let mut front = Vec::new();
    let mut best = f64::NEG_INFINITY;
    for i in order {
        if y[i] > best {
            best = y[i];
            front.push(i);
        }
    }
    front
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

    /// A chart of labelled points with their Pareto front (less x and more y is better),
    /// e.g. training time (log axis) against accuracy, one point per model.
    pub fn pareto(
        title: impl Into<String>,
        x: Axis,
        y: Axis,
        points: Series,
        front_name: impl Into<String>,
    ) -> Self {
        let front = pareto_front(&points.x, &points.y);
        let front = Series::new(
            front_name,
            front.iter().map(|&i| points.x[i]).collect(),
            front.iter().map(|&i| points.y[i]).collect(),
        )
        // A neutral line, so that the coloured points stand out.
        .color(Rgb(0x55, 0x55, 0x55));
        Figure::chart(title, x, y, vec![front, points.style(SeriesStyle::Markers)])
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
        match &self.kind {
            FigureKind::Chart(c) => {
                if c.series.is_empty() {
                    return invalid("a chart needs at least one series".into());
                }
                for s in &c.series {
                    if s.x.len() != s.y.len() {
                        return invalid(format!(
                            "series {:?} has {} x values and {} y values",
                            s.name,
                            s.x.len(),
                            s.y.len()
                        ));
                    }
                    if let Some(e) = &s.error
                        && (e.lower.len() != s.y.len() || e.upper.len() != s.y.len())
                    {
                        return invalid(format!(
                            "series {:?}: error bounds need one value per point",
                            s.name
                        ));
                    }
                    if !s.point_labels.is_empty() && s.point_labels.len() != s.x.len() {
                        return invalid(format!(
                            "series {:?}: {} point labels for {} points",
                            s.name,
                            s.point_labels.len(),
                            s.x.len()
                        ));
                    }
                }
                if c.ref_lines.iter().any(|r| !r.value.is_finite()) {
                    return invalid("a reference line needs a finite value".into());
                }
                check_include(&c.x).or_else(invalid)?;
                check_include(&c.y).or_else(invalid)?;
            }
            FigureKind::Bars(b) => {
                if b.categories.is_empty() || b.groups.is_empty() {
                    return invalid("a bar chart needs categories and at least one group".into());
                }
                if b.y.scale == Scale::Log {
                    return invalid("bars start at 0 and cannot use a log axis".into());
                }
                if b.sign_colors && b.groups.len() > 1 {
                    return invalid("sign colours need a single group".into());
                }
                for g in &b.groups {
                    if g.values.len() != b.categories.len() {
                        return invalid(format!(
                            "group {:?} has {} values for {} categories",
                            g.name,
                            g.values.len(),
                            b.categories.len()
                        ));
                    }
                    if g.error
                        .as_ref()
                        .is_some_and(|e| e.len() != b.categories.len())
                    {
                        return invalid(format!("group {:?}: one error per category", g.name));
                    }
                }
                check_include(&b.y).or_else(invalid)?;
            }
            FigureKind::Heatmap(h) => {
                if h.rows.is_empty() || h.columns.is_empty() {
                    return invalid("a heatmap needs at least one row and one column".into());
                }
                if h.values.len() != h.rows.len()
                    || h.values.iter().any(|r| r.len() != h.columns.len())
                {
                    return invalid(format!(
                        "the values must be {} rows of {} columns",
                        h.rows.len(),
                        h.columns.len()
                    ));
                }
                if h.marked
                    .iter()
                    .any(|&[r, c]| r >= h.rows.len() || c >= h.columns.len())
                {
                    return invalid("a marked cell lies outside the matrix".into());
                }
                check_limits(&h.colors).or_else(invalid)?;
            }
            FigureKind::ImageGrid(g) => {
                let Some(first) = g.images.first() else {
                    return invalid("an image grid needs at least one image".into());
                };
                let shape = (first.values.len(), first.values.first().map_or(0, Vec::len));
                if shape.0 == 0 || shape.1 == 0 {
                    return invalid("images need at least one row and one column".into());
                }
                for (i, im) in g.images.iter().enumerate() {
                    if im.values.len() != shape.0 || im.values.iter().any(|r| r.len() != shape.1) {
                        return invalid(format!(
                            "image {i} is not {}×{} like the first image",
                            shape.0, shape.1
                        ));
                    }
                }
                check_limits(&g.colors).or_else(invalid)?;
            }
        }
        Ok(())
    }
}

fn check_include(axis: &Axis) -> Result<(), String> {
    match axis.include {
        Some([lo, hi]) if !(lo.is_finite() && hi.is_finite() && lo <= hi) => Err(format!(
            "axis {:?}: the included range must be finite and ordered",
            axis.title
        )),
        Some([lo, _]) if axis.scale == Scale::Log && lo <= 0.0 => Err(format!(
            "axis {:?}: a log axis cannot include values ≤ 0",
            axis.title
        )),
        _ => Ok(()),
    }
}

fn check_limits(colors: &ColorScale) -> Result<(), String> {
    match colors.limits {
        Some([lo, hi]) if !(lo.is_finite() && hi.is_finite() && lo < hi) => {
            Err("colour limits must be finite with low < high".into())
        }
        _ => Ok(()),
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

/// serde_json writes NaN as `null`; read `null` back as NaN so that figures round-trip.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        v.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let v: Vec<Option<f64>> = Vec::deserialize(d)?;
        Ok(v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
    }
}

mod opt_nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<Vec<f64>>, s: S) -> Result<S::Ok, S::Error> {
        v.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<f64>>, D::Error> {
        let v: Option<Vec<Option<f64>>> = Option::deserialize(d)?;
        Ok(v.map(|v| v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect()))
    }
}

mod matrix_nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &[Vec<f64>], s: S) -> Result<S::Ok, S::Error> {
        v.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vec<f64>>, D::Error> {
        let v: Vec<Vec<Option<f64>>> = Vec::deserialize(d)?;
        Ok(v.into_iter()
            .map(|r| r.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_non_dominated_points() {
        let x = [1.0, 2.0, 3.0, 0.5, 2.0, f64::NAN];
        let y = [0.7, 0.6, 0.9, 0.5, 0.8, 1.0];
        // 0.5→0.5, 1→0.7, 2→0.8 (beats 2→0.6), 3→0.9; NaN ignored.
        assert_eq!(pareto_front(&x, &y), vec![3, 0, 4, 2]);
    }

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

    #[test]
    fn image_from_sparse_layout_puts_base_at_bottom() {
        let layout = Layout::SparseGrid {
            rows: 2,
            cols: 3,
            cells: vec![[0, 0], [1, 2]],
        };
        let im = GridImage::from_layout("b1", &[1.0, 2.0], &layout).unwrap();
        assert_eq!(im.values[1][0], 1.0);
        assert_eq!(im.values[0][2], 2.0);
        assert!(im.values[0][0].is_nan());
        assert!(GridImage::from_layout("b", &[1.0], &layout).is_err());
    }
}
