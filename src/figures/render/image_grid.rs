//! Image grids: small multiples of equal-shape images on one colour scale.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::colorbar::{colorbar_span, colorbar_width, draw_colorbar};
use super::{NOTE_EM, Rect, fitting_em, too_small, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, TEXT};
use crate::figures::colormap::Rgb;
use crate::figures::model::ImageGrid;

pub(super) fn draw_image_grid<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    g: &ImageGrid,
    area: Rect,
) -> Result<(), FigureError> {
    let n = g.images.len();
    let (ih, iw) = (g.images[0].values.len(), g.images[0].values[0].len());
    let limits = g.colors.resolve(
        g.images
            .iter()
            .flat_map(|im| im.values.iter().flatten().copied()),
    );
    let (cb_w, cb_ticks) = colorbar_width(c, &g.colors, limits, area.h() * 0.7)?;
    let avail = Rect {
        l: area.l,
        t: area.t,
        r: area.r - cb_w,
        b: area.b,
    };
    let has_caption = g.images.iter().any(|im| !im.caption.is_empty());
    let cell_for = |cols: usize, gap: f64, cap_h: f64| {
        let rows = n.div_ceil(cols);
        let by_w = (avail.w() - gap * (cols - 1) as f64) / (cols * iw) as f64;
        let by_h = (avail.h() - gap * (rows - 1) as f64 - cap_h * rows as f64) / (rows * ih) as f64;
        by_w.min(by_h)
    };
    let best_cols = |gap: f64, cap_h: f64| {
        if g.columns > 0 {
            g.columns.min(n)
        } else {
            (1..=n)
                .max_by(|&a, &b| cell_for(a, gap, cap_h).total_cmp(&cell_for(b, gap, cap_h)))
                .unwrap_or(1)
        }
    };
    // Many images in a small figure (50 bases in a journal column): narrower gaps, then
    // smaller captions, before a taxel gets smaller than a readable 4 px (about 1 mm).
    let (gap, caption_em, cols) = [(16.0, 1.0), (8.0, 1.0), (4.0, 0.8), (3.0, 0.6)]
        .into_iter()
        .map(|(gap, scale)| {
            let em = if has_caption { NOTE_EM * scale } else { 0.0 };
            let (gap, cap_h) = (c.px(gap), c.px(em * 1.8));
            (gap, em, best_cols(gap, cap_h))
        })
        .find(|&(gap, em, cols)| cell_for(cols, gap, c.px(em * 1.8)) >= c.px(4.0))
        .unwrap_or_else(|| {
            let gap = c.px(3.0);
            let em = if has_caption { NOTE_EM * 0.6 } else { 0.0 };
            (gap, em, best_cols(gap, c.px(em * 1.8)))
        });
    let cap_h = c.px(caption_em * 1.8);
    let cs = cell_for(cols, gap, cap_h);
    // Under a pixel of the image a taxel is nothing: the figure cannot be drawn this size.
    if cs < 1.0 {
        return Err(too_small());
    }
    let rows = n.div_ceil(cols);
    let (img_w, img_h) = (cs * iw as f64, cs * ih as f64);
    let total_w = img_w * cols as f64 + gap * (cols - 1) as f64;
    let total_h = (img_h + cap_h) * rows as f64 + gap * (rows - 1) as f64;
    let x0 = avail.l + (avail.w() - total_w) / 2.0;
    let y0 = avail.t + (avail.h() - total_h) / 2.0;
    let outline = cs >= c.px(8.0);
    for (i, im) in g.images.iter().enumerate() {
        let (gr, gc) = (i / cols, i % cols);
        let left = x0 + gc as f64 * (img_w + gap);
        let top = y0 + gr as f64 * (img_h + cap_h + gap);
        for (r, row) in im.values.iter().enumerate() {
            for (k, &v) in row.iter().enumerate() {
                // A missing cell has no taxel: left as background.
                if !v.is_finite() {
                    continue;
                }
                let (a, b) = (
                    (left + cs * k as f64, top + cs * r as f64),
                    (left + cs * (k + 1) as f64, top + cs * (r + 1) as f64),
                );
                c.fill_rect(a, b, g.colors.map.color(v, limits))?;
                if outline {
                    c.stroke_rect(a, b, Rgb(0xbb, 0xbb, 0xbb), 0.5)?;
                }
            }
        }
        // The sensor's outline, so that sparse images stay apart.
        let pad = c.px(2.0);
        let frame = Rgb(0xcc, 0xcc, 0xcc);
        c.stroke_rect(
            (left - pad, top - pad),
            (left + img_w + pad, top + img_h + pad),
            frame,
            1.0,
        )?;
        if !im.caption.is_empty() {
            // Smaller to fit, then cut: a caption never runs into its neighbour's.
            let room = img_w + gap * 0.8;
            let em = fitting_em(c, &im.caption, caption_em, room)?;
            let caption = truncated(c, &im.caption, em, room)?;
            c.text(
                &caption,
                (left + img_w / 2.0, top + img_h + cap_h / 2.0),
                em,
                TEXT,
                HPos::Center,
                false,
            )?;
        }
    }
    let data = Rect {
        l: x0,
        t: y0,
        r: x0 + total_w,
        b: y0 + total_h,
    };
    let (cb_top, cb_bottom) = colorbar_span(c, data, area);
    draw_colorbar(
        c, &g.colors, limits, &cb_ticks, avail.r, cb_top, cb_bottom, cb_w,
    )
}
