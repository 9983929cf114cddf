//! Heatmaps and the colour scale they share with image grids.

use serde::{Deserialize, Serialize};

use crate::figures::FigureError;

use super::axis::{AxisTitle, axis_text};
use super::nan_serde::matrix_nan_as_null;
use crate::figures::colormap::ColorMap;

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

pub(super) fn check_limits(colors: &ColorScale) -> Result<(), FigureError> {
    match colors.limits {
        Some([lo, hi]) if !(lo.is_finite() && hi.is_finite() && lo < hi) => Err(
            FigureError::Invalid("colour limits must be finite with low < high".into()),
        ),
        _ => Ok(()),
    }
}

impl Heatmap {
    /// A row and a column label per value, marked cells inside the matrix.
    pub(super) fn validate(&self) -> Result<(), FigureError> {
        let h = self;
        if h.rows.is_empty() || h.columns.is_empty() {
            return Err(FigureError::Invalid(
                "a heatmap needs at least one row and one column".into(),
            ));
        }
        if h.values.len() != h.rows.len() || h.values.iter().any(|r| r.len() != h.columns.len()) {
            return Err(FigureError::Invalid(format!(
                "the values must be {} rows of {} columns",
                h.rows.len(),
                h.columns.len()
            )));
        }
        if h.marked
            .iter()
            .any(|&[r, c]| r >= h.rows.len() || c >= h.columns.len())
        {
            return Err(FigureError::Invalid(
                "a marked cell lies outside the matrix".into(),
            ));
        }
        check_limits(&h.colors)?;
        Ok(())
    }
}
