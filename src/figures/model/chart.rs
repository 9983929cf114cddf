//! Line and scatter charts: series with error ranges and point labels, reference lines,
//! and the Pareto front of a speed-against-accuracy chart.

use serde::{Deserialize, Serialize};

use crate::figures::FigureError;

use super::axis::{Axis, check_include};
use super::nan_serde::nan_as_null;
use crate::figures::colormap::Rgb;

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
    /// The series this one is drawn for (a Pareto front through some of its points): no
    /// legend entry of its own, its line joins that series' entry.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part_of: Option<String>,
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
            part_of: None,
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

    /// Drawn for the series named `owner`: see [`Series::part_of`].
    pub fn part_of(mut self, owner: impl Into<String>) -> Self {
        self.part_of = Some(owner.into());
        self
    }

    /// The legend entry this series is drawn under.
    pub fn legend_name(&self) -> &str {
        self.part_of.as_deref().unwrap_or(&self.name)
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

impl Chart {
    /// Series lengths agree with their points, error bounds and labels.
    pub(super) fn validate(&self) -> Result<(), FigureError> {
        let c = self;
        if c.series.is_empty() {
            return Err(FigureError::Invalid(
                "a chart needs at least one series".into(),
            ));
        }
        for s in &c.series {
            if s.x.len() != s.y.len() {
                return Err(FigureError::Invalid(format!(
                    "series {:?} has {} x values and {} y values",
                    s.name,
                    s.x.len(),
                    s.y.len()
                )));
            }
            if let Some(e) = &s.error
                && (e.lower.len() != s.y.len() || e.upper.len() != s.y.len())
            {
                return Err(FigureError::Invalid(format!(
                    "series {:?}: error bounds need one value per point",
                    s.name
                )));
            }
            if let Some(owner) = &s.part_of
                && !c
                    .series
                    .iter()
                    .any(|o| &o.name == owner && o.part_of.is_none())
            {
                return Err(FigureError::Invalid(format!(
                    "series {:?} is drawn for a series {owner:?} the chart does not have",
                    s.name
                )));
            }
            if !s.point_labels.is_empty() && s.point_labels.len() != s.x.len() {
                return Err(FigureError::Invalid(format!(
                    "series {:?}: {} point labels for {} points",
                    s.name,
                    s.point_labels.len(),
                    s.x.len()
                )));
            }
        }
        if c.ref_lines.iter().any(|r| !r.value.is_finite()) {
            return Err(FigureError::Invalid(
                "a reference line needs a finite value".into(),
            ));
        }
        check_include(&c.x)?;
        check_include(&c.y)?;
        if !c.y.categories.is_empty() {
            return Err(FigureError::Invalid(
                "only a chart's x axis can name categories".into(),
            ));
        }
        Ok(())
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
}
