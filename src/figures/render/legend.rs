//! Legends: entries with swatches in the series' colours. A legend goes in the plot's
//! corner that holds no data when one does, else beside the plot when the plot keeps most
//! of the width, else under it in columns; it never covers data.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::{LEGEND_EM, Rect, segment_hits, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, GRID, MUTED, Marker, TEXT, WHITE};
use crate::figures::colormap::Rgb;
use crate::figures::layout::Bounds;

/// A legend entry: what its swatch shows.
pub(super) struct LegendEntry {
    pub(super) name: String,
    pub(super) color: Rgb,
    pub(super) line: bool,
    pub(super) marker: Option<Marker>,
    pub(super) band: bool,
    pub(super) bar: bool,
}

impl LegendEntry {
    /// An entry without a swatch ("+3 more").
    fn note(name: String) -> Self {
        LegendEntry {
            name,
            color: MUTED,
            line: false,
            marker: None,
            band: false,
            bar: false,
        }
    }
}

/// What the data occupies in pixels, for placing the legend and labels around it.
#[derive(Default)]
pub(super) struct Obstacles {
    pub(super) marks: Vec<Rect>,
    pub(super) segments: Vec<((f64, f64), (f64, f64))>,
}

impl Obstacles {
    pub(super) fn hit(&self, r: &Rect) -> usize {
        self.marks.iter().filter(|m| m.overlaps(r)).count()
            + self
                .segments
                .iter()
                .filter(|(a, b)| segment_hits(r, *a, *b))
                .count()
    }
}

/// Where the legend ended up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Placement {
    /// Inside the plot, at this top-left corner.
    Inside(f64, f64),
    /// At the right of the plot, from the plot's top.
    Right,
    /// Under the plot, centred.
    Below,
}

pub(super) struct Legend {
    pub(super) entries: Vec<LegendEntry>,
    /// Widest entry, swatch included.
    entry_w: f64,
    row: f64,
    columns: usize,
    gap: f64,
}

impl Legend {
    /// A one-column legend whose names are shortened to fit `max_w`.
    pub(super) fn new<DB: DrawingBackend>(
        c: &Canvas<'_, DB>,
        mut entries: Vec<LegendEntry>,
        max_w: f64,
    ) -> Result<Self, FigureError> {
        let swatch = c.px(30.0);
        for e in entries.iter_mut() {
            e.name = truncated(c, &e.name, LEGEND_EM, max_w - swatch)?;
        }
        let mut legend = Legend {
            entries,
            entry_w: 0.0,
            row: c.px(LEGEND_EM * 1.55),
            columns: 1,
            gap: c.px(12.0),
        };
        legend.measure(c)?;
        Ok(legend)
    }

    fn measure<DB: DrawingBackend>(&mut self, c: &Canvas<'_, DB>) -> Result<(), FigureError> {
        let mut w: f64 = 0.0;
        for e in &self.entries {
            w = w.max(c.text_size(&e.name, LEGEND_EM)?.0);
        }
        self.entry_w = w + c.px(30.0);
        Ok(())
    }

    fn rows(&self) -> usize {
        self.entries.len().div_ceil(self.columns)
    }

    /// Width and height of the legend.
    pub(super) fn size(&self) -> (f64, f64) {
        let cols = self.columns as f64;
        (
            cols * self.entry_w + (cols - 1.0) * self.gap,
            self.rows() as f64 * self.row,
        )
    }

    /// The top-left corner of the legend in a corner of `plot` that holds no data, the
    /// top corners first (where curves rarely are), if the legend fits one.
    pub(super) fn inside(&self, plot: Rect, data: &Obstacles, pad: f64) -> Option<(f64, f64)> {
        let (w, h) = self.size();
        let (w, h) = (w + 2.0 * pad, h + 2.0 * pad);
        if w > plot.w() * 0.6 || h > plot.h() * 0.6 {
            return None;
        }
        let corners = [
            (plot.r - w, plot.t),
            (plot.l, plot.t),
            (plot.r - w, plot.b - h),
            (plot.l, plot.b - h),
        ];
        corners
            .into_iter()
            .find(|&(l, t)| {
                let r = Rect {
                    l,
                    t,
                    r: l + w,
                    b: t + h,
                };
                data.hit(&r) == 0
            })
            .map(|(l, t)| (l + pad, t + pad))
    }

    /// Make room for the legend outside the plot: at the right when the plot keeps 60 % of
    /// the width and the legend's height, else under the plot in as many columns as fit
    /// (and at most a quarter of the height: the entries that do not fit are counted in a
    /// last "+n more"). Returns the area left for the plot.
    pub(super) fn outside<DB: DrawingBackend>(
        &mut self,
        c: &Canvas<'_, DB>,
        area: Rect,
    ) -> Result<(Rect, Placement), FigureError> {
        let (w, h) = self.size();
        if area.w() - w - self.gap >= area.w() * 0.6 && h <= area.h() * 0.85 {
            let mut body = area;
            body.r -= w + self.gap;
            return Ok((body, Placement::Right));
        }
        self.columns = (((area.w() + self.gap) / (self.entry_w + self.gap)).floor() as usize)
            .clamp(1, self.entries.len().max(1));
        let max_rows = ((area.h() / 4.0) / self.row).floor().max(1.0) as usize;
        if self.rows() > max_rows {
            let keep = (max_rows * self.columns).saturating_sub(1);
            let more = self.entries.len() - keep;
            self.entries.truncate(keep);
            self.entries
                .push(LegendEntry::note(format!("+{more} more")));
            self.measure(c)?;
        }
        let mut body = area;
        body.b -= self.size().1 + c.px(6.0);
        Ok((body, Placement::Below))
    }

    /// The legend's top-left corner for its placement around the plot.
    pub(super) fn origin(&self, placement: Placement, plot: Rect, area: Rect) -> (f64, f64) {
        match placement {
            Placement::Inside(l, t) => (l, t),
            Placement::Right => (area.r - self.size().0, plot.t),
            Placement::Below => (
                area.l + (area.w() - self.size().0).max(0.0) / 2.0,
                area.b - self.size().1,
            ),
        }
    }

    /// Draw the legend from its top-left corner; inside the plot on a white ground.
    pub(super) fn draw<DB: DrawingBackend>(
        &self,
        c: &Canvas<'_, DB>,
        (l, t): (f64, f64),
        ground: bool,
    ) -> Result<Rect, FigureError> {
        let (w, h) = self.size();
        let bounds = Rect {
            l,
            t,
            r: l + w,
            b: t + h,
        };
        c.note_legend(Bounds::new(l, t, l + w, t + h));
        if ground {
            let p = c.px(3.0);
            c.fill_rect((l - p, t - p), (l + w + p, t + h + p), WHITE)?;
            c.stroke_rect((l - p, t - p), (l + w + p, t + h + p), GRID, 1.0)?;
        }
        for (i, e) in self.entries.iter().enumerate() {
            let (col, row) = (i % self.columns, i / self.columns);
            let x0 = l + col as f64 * (self.entry_w + self.gap);
            let y = t + self.row * (row as f64 + 0.5);
            draw_entry(c, e, x0, y)?;
        }
        Ok(bounds)
    }
}

fn draw_entry<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    e: &LegendEntry,
    x0: f64,
    y: f64,
) -> Result<(), FigureError> {
    let x1 = x0 + c.px(22.0);
    if e.band {
        let h = c.px(5.0);
        c.polygon(
            &[(x0, y - h), (x1, y - h), (x1, y + h), (x0, y + h)],
            e.color,
            0.2,
        )?;
    }
    if e.bar {
        c.fill_rect(
            (x0 + c.px(4.0), y - c.px(6.0)),
            (x1 - c.px(4.0), y + c.px(6.0)),
            e.color,
        )?;
    }
    if e.line {
        c.line((x0, y), (x1, y), e.color, 2.0)?;
    }
    if let Some(m) = e.marker {
        c.marker(m, ((x0 + x1) / 2.0, y), 3.5, e.color)?;
    }
    let swatchless = !(e.band || e.bar || e.line || e.marker.is_some());
    let x = if swatchless { x0 } else { x1 + c.px(8.0) };
    c.text(&e.name, (x, y), LEGEND_EM, TEXT, HPos::Left, false)
}
