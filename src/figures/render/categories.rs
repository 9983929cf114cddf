//! Category labels (bar categories, heatmap rows and columns): every one when there is
//! room, rotated when long, every k-th when crowded, and never fewer than three (smaller,
//! down to 60 % of the size, when three would not fit otherwise).

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::truncated;
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, TEXT};
use crate::figures::legibility::thin_categories;

/// Which category labels to draw: every `step`-th, rotated or not, at size `em`, and the
/// height taken.
#[derive(Clone, Copy)]
pub(super) struct CategoryLabels {
    pub(super) step: usize,
    pub(super) rotated: bool,
    pub(super) height: f64,
    pub(super) em: f64,
    /// Room one label needs along the axis at size `base_em`.
    needed: f64,
    base_em: f64,
    count: usize,
}

impl CategoryLabels {
    /// Labels along an axis where each needs `needed` (a line of text for row labels).
    pub(super) fn level(count: usize, needed: f64, em: f64) -> Self {
        CategoryLabels {
            step: 1,
            rotated: false,
            height: needed,
            em,
            needed,
            base_em: em,
            count,
        }
    }

    /// The same layout for the final slot width: only how many labels are skipped (and
    /// their size) changes, so that the height already reserved stays right.
    pub(super) fn for_slot(self, slot: f64) -> Self {
        let t = thin_categories(self.count, slot, self.needed);
        CategoryLabels {
            step: t.step,
            em: self.base_em * t.scale,
            ..self
        }
    }

    /// The labels drawn.
    pub(super) fn shown(&self, labels: &[String]) -> Vec<String> {
        labels.iter().step_by(self.step).cloned().collect()
    }
}

/// Labels under slots `slot` wide: level when they fit, else rotated (at most `max_h`
/// tall, cut with an ellipsis) when long, else thinned out (short names such as indices).
pub(super) fn category_labels<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    labels: &[String],
    slot: f64,
    em: f64,
    max_h: f64,
) -> Result<CategoryLabels, FigureError> {
    let mut widest: f64 = 0.0;
    for l in labels {
        widest = widest.max(c.text_size(l, em)?.0);
    }
    let line_h = c.px(em * 1.2);
    let gap = c.px(6.0);
    let rotated = widest + gap > slot && widest > c.px(em * 3.0);
    let layout = if rotated {
        CategoryLabels {
            rotated,
            height: widest.min(max_h),
            ..CategoryLabels::level(labels.len(), line_h, em)
        }
    } else {
        CategoryLabels {
            height: line_h,
            ..CategoryLabels::level(labels.len(), widest + gap, em)
        }
    };
    Ok(layout.for_slot(slot))
}

/// One label under its slot centred at `x`, from `top` down.
pub(super) fn draw_category_label<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    label: &str,
    x: f64,
    top: f64,
    layout: &CategoryLabels,
) -> Result<(), FigureError> {
    let em = layout.em;
    if layout.rotated {
        let label = truncated(c, label, em, layout.height)?;
        c.text(&label, (x, top), em, TEXT, HPos::Right, true)
    } else {
        c.text(
            label,
            (x, top + c.px(em * 0.6)),
            em,
            TEXT,
            HPos::Center,
            false,
        )
    }
}
