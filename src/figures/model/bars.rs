//! Grouped bar charts.

use serde::{Deserialize, Serialize};

use crate::figures::FigureError;

use super::axis::{Axis, AxisTitle, Scale, check_include};
use super::nan_serde::{nan_as_null, opt_nan_as_null};
use crate::figures::colormap::Rgb;

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

impl BarChart {
    /// One value (and error) per category, a linear axis, sign colours for one group.
    pub(super) fn validate(&self) -> Result<(), FigureError> {
        let b = self;
        if b.categories.is_empty() || b.groups.is_empty() {
            return Err(FigureError::Invalid(
                "a bar chart needs categories and at least one group".into(),
            ));
        }
        if b.y.scale == Scale::Log {
            return Err(FigureError::Invalid(
                "bars start at 0 and cannot use a log axis".into(),
            ));
        }
        if b.sign_colors && b.groups.len() > 1 {
            return Err(FigureError::Invalid(
                "sign colours need a single group".into(),
            ));
        }
        for g in &b.groups {
            if g.values.len() != b.categories.len() {
                return Err(FigureError::Invalid(format!(
                    "group {:?} has {} values for {} categories",
                    g.name,
                    g.values.len(),
                    b.categories.len()
                )));
            }
            if g.error
                .as_ref()
                .is_some_and(|e| e.len() != b.categories.len())
            {
                return Err(FigureError::Invalid(format!(
                    "group {:?}: one error per category",
                    g.name
                )));
            }
        }
        check_include(&b.y)?;
        Ok(())
    }
}
