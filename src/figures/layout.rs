//! What the renderer placed where: every text's box, the tick labels of every axis, the
//! legend's box and the data's marks, in device pixels. The export records it while it
//! draws, so that tests can check a figure's legibility (no overprinted text, enough ticks,
//! a legend off the data) from the layout instead of from pixels.

use serde::Serialize;

/// A rectangle in device pixels, y downwards.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    pub left: f64,
    pub top: f64,
    pub right: f64,
    pub bottom: f64,
}

impl Bounds {
    pub fn new(left: f64, top: f64, right: f64, bottom: f64) -> Self {
        Bounds {
            left: left.min(right),
            top: top.min(bottom),
            right: left.max(right),
            bottom: top.max(bottom),
        }
    }

    /// Do the two rectangles share an area (touching edges do not count)?
    pub fn overlaps(&self, o: &Bounds) -> bool {
        self.left < o.right && o.left < self.right && self.top < o.bottom && o.top < self.bottom
    }
}

/// One line of text as drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlacedText {
    pub text: String,
    pub bounds: Bounds,
}

/// The tick labels an axis (or a colour bar) shows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisLabels {
    /// The axis' title ("Accuracy (%)").
    pub title: String,
    /// A category axis: `categories` names, of which `labels` are drawn.
    pub categories: Option<usize>,
    pub labels: Vec<String>,
}

/// Everything the checks need about one rendered figure.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FigureLayout {
    pub width: f64,
    pub height: f64,
    pub texts: Vec<PlacedText>,
    pub axes: Vec<AxisLabels>,
    /// The legend's box, when a legend is drawn.
    pub legend: Option<Bounds>,
    /// Data marks: markers, line vertices and bars.
    pub data: Vec<Bounds>,
}

impl FigureLayout {
    /// Pairs of texts whose boxes overlap.
    pub fn overlapping_texts(&self) -> Vec<(&PlacedText, &PlacedText)> {
        let mut out = Vec::new();
        for (i, a) in self.texts.iter().enumerate() {
            for b in &self.texts[i + 1..] {
                if a.bounds.overlaps(&b.bounds) {
                    out.push((a, b));
                }
            }
        }
        out
    }

    /// Data marks under the legend.
    pub fn data_under_legend(&self) -> Vec<Bounds> {
        match self.legend {
            Some(legend) => self
                .data
                .iter()
                .filter(|d| d.overlaps(&legend))
                .copied()
                .collect(),
            None => Vec::new(),
        }
    }
}
