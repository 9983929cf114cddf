//! Lays out and draws a [`Figure`] on a [`Canvas`]: title, axes with ticks and light
//! gridlines, data, legends outside the data area, colour bars.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::FigureError;
use super::canvas::{Canvas, MUTED, TEXT};
use super::model::{Figure, FigureKind};

mod bars;
mod chart;
mod colorbar;
mod frame;
mod heatmap;
mod image_grid;
mod legend;
mod scale;

// Font sizes (em, CSS pixels at 96 DPI).
const TITLE_EM: f64 = 15.0;
const SUBTITLE_EM: f64 = 11.0;
const AXIS_TITLE_EM: f64 = 12.0;
const TICK_EM: f64 = 10.5;
const LEGEND_EM: f64 = 11.0;
const NOTE_EM: f64 = 9.5;

/// Pixel rectangle: left, top, right, bottom.
#[derive(Clone, Copy, Debug)]
struct Rect {
    l: f64,
    t: f64,
    r: f64,
    b: f64,
}

impl Rect {
    fn w(&self) -> f64 {
        self.r - self.l
    }
    fn h(&self) -> f64 {
        self.b - self.t
    }
    fn overlaps(&self, o: &Rect) -> bool {
        self.l < o.r && o.l < self.r && self.t < o.b && o.t < self.b
    }
    fn contains(&self, o: &Rect) -> bool {
        o.l >= self.l && o.r <= self.r && o.t >= self.t && o.b <= self.b
    }
}

/// Draw any figure on the canvas (already filled with white).
pub(super) fn draw<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    fig: &Figure,
) -> Result<(), FigureError> {
    fig.validate()?;
    let area = draw_title(c, fig)?;
    if area.w() < c.px(120.0) || area.h() < c.px(80.0) {
        return Err(too_small());
    }
    match &fig.kind {
        FigureKind::Chart(chart) => chart::draw_chart(c, chart, area),
        FigureKind::Bars(bars) => bars::draw_bars(c, bars, area),
        FigureKind::Heatmap(h) => heatmap::draw_heatmap(c, h, area),
        FigureKind::ImageGrid(g) => image_grid::draw_image_grid(c, g, area),
    }
}

fn too_small() -> FigureError {
    FigureError::Options(
        "the image is too small for this figure at this DPI: enlarge it or lower the DPI".into(),
    )
}

/// Text scaled down (to at most 60%) so that it fits `max_w`.
fn fitting_em<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    text: &str,
    em: f64,
    max_w: f64,
) -> Result<f64, FigureError> {
    let (w, _) = c.text_size(text, em)?;
    Ok(if w > max_w && w > 0.0 {
        (em * max_w / w).max(em * 0.6)
    } else {
        em
    })
}

/// Title and subtitle; returns the area left for the figure body.
fn draw_title<DB: DrawingBackend>(c: &Canvas<'_, DB>, fig: &Figure) -> Result<Rect, FigureError> {
    let (w, h) = c.size();
    let m = c.px(14.0);
    let mut top = m;
    if !fig.title.is_empty() {
        let em = fitting_em(c, &fig.title, TITLE_EM, w - 2.0 * m)?;
        let lh = c.px(em * 1.3);
        c.text(
            &fig.title,
            (w / 2.0, top + lh / 2.0),
            em,
            TEXT,
            HPos::Center,
            false,
        )?;
        top += lh;
    }
    if let Some(sub) = fig.subtitle.as_deref().filter(|s| !s.is_empty()) {
        let em = fitting_em(c, sub, SUBTITLE_EM, w - 2.0 * m)?;
        let lh = c.px(em * 1.4);
        c.text(
            sub,
            (w / 2.0, top + lh / 2.0),
            em,
            MUTED,
            HPos::Center,
            false,
        )?;
        top += lh;
    }
    Ok(Rect {
        l: m,
        t: top + c.px(8.0),
        r: w - m,
        b: h - m,
    })
}

/// `text`, cut with an ellipsis to fit `max_w` at size `em`.
fn truncated<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    text: &str,
    em: f64,
    max_w: f64,
) -> Result<String, FigureError> {
    if c.text_size(text, em)?.0 <= max_w {
        return Ok(text.to_string());
    }
    let chars: Vec<char> = text.chars().collect();
    for n in (1..chars.len()).rev() {
        let cut: String = chars[..n].iter().collect::<String>() + "…";
        if c.text_size(&cut, em)?.0 <= max_w {
            return Ok(cut);
        }
    }
    Ok("…".to_string())
}

fn missing_note(name: &str, missing: usize) -> String {
    if missing == 0 {
        name.to_string()
    } else {
        format!("{name} ({missing} missing)")
    }
}
