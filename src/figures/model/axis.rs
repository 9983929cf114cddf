//! Axes: numeric (linear or log, with a range to include) and categorical titles.

use serde::{Deserialize, Serialize};

use crate::figures::FigureError;

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

pub(super) fn axis_text(title: &str, unit: &str) -> String {
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
    /// The names of positions 1, 2, … along the axis: a category axis whose slots hold
    /// points (a strip of points per group). Empty for a numeric axis.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub categories: Vec<String>,
}

impl Axis {
    pub fn new(title: impl Into<String>, unit: impl Into<String>) -> Self {
        Axis {
            title: title.into(),
            unit: unit.into(),
            scale: Scale::Linear,
            include: None,
            categories: Vec::new(),
        }
    }

    /// A category axis: `names` at positions 1, 2, …, each with its slot from half a
    /// position before to half after.
    pub fn categories(mut self, names: Vec<String>) -> Self {
        self.include = Some([0.5, names.len() as f64 + 0.5]);
        self.categories = names;
        self
    }

    /// The category whose slot holds `v` (position `i + 1` ± ½), if any.
    pub fn category_at(&self, v: f64) -> Option<&str> {
        let i = (v.is_finite() && v >= 0.5).then(|| (v - 0.5).floor() as usize)?;
        self.categories.get(i).map(String::as_str)
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

pub(super) fn check_include(axis: &Axis) -> Result<(), FigureError> {
    if !axis.categories.is_empty() && axis.scale == Scale::Log {
        return Err(FigureError::Invalid(format!(
            "axis {:?}: a category axis cannot be logarithmic",
            axis.title
        )));
    }
    match axis.include {
        Some([lo, hi]) if !(lo.is_finite() && hi.is_finite() && lo <= hi) => {
            Err(FigureError::Invalid(format!(
                "axis {:?}: the included range must be finite and ordered",
                axis.title
            )))
        }
        Some([lo, _]) if axis.scale == Scale::Log && lo <= 0.0 => {
            Err(FigureError::Invalid(format!(
                "axis {:?}: a log axis cannot include values ≤ 0",
                axis.title
            )))
        }
        _ => Ok(()),
    }
}
