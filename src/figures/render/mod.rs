//! Lays out and draws a [`Figure`] on a [`Canvas`]: title, axes with ticks and light
//! gridlines, data, legends outside the data area, colour bars.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::FigureError;
use super::canvas::{Canvas, MUTED, TEXT};
use super::model::{Figure, FigureKind};

mod bars;
mod categories;
mod chart;
mod colorbar;
mod frame;
mod heatmap;
mod image_grid;
mod legend;
mod scale;

pub use bars::bar_limits;
pub use chart::chart_limits;
pub use frame::fitted_axis_ticks;
pub use scale::{axis_limits, axis_ticks, tick_label};

// Font sizes in CSS pixels at 96 DPI (a point is 4/3 px): 8–9 pt text and a 10-pt title,
// the sizes journals ask for once a figure is printed at its exported width and DPI.
const PT: f64 = 4.0 / 3.0;
const TITLE_EM: f64 = 10.0 * PT;
const SUBTITLE_EM: f64 = 8.5 * PT;
const AXIS_TITLE_EM: f64 = 9.0 * PT;
const TICK_EM: f64 = 8.0 * PT;
const LEGEND_EM: f64 = 8.0 * PT;
const NOTE_EM: f64 = 8.0 * PT;

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
    pub(super) fn overlaps(&self, o: &Rect) -> bool {
        self.l < o.r && o.l < self.r && self.t < o.b && o.t < self.b
    }
    pub(super) fn contains(&self, o: &Rect) -> bool {
        o.l >= self.l && o.r <= self.r && o.t >= self.t && o.b <= self.b
    }
}

/// Does the segment `a`–`b` cross the rectangle? (Liang–Barsky clipping.)
fn segment_hits(r: &Rect, a: (f64, f64), b: (f64, f64)) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - r.l),
        (dx, r.r - a.0),
        (-dy, a.1 - r.t),
        (dy, r.b - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
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

/// Title and subtitle; returns the area left for the figure body. The title shrinks (then
/// is cut) to one line; the subtitle wraps onto one line at tile size, up to four on a
/// large figure, the last cut with an ellipsis.
fn draw_title<DB: DrawingBackend>(c: &Canvas<'_, DB>, fig: &Figure) -> Result<Rect, FigureError> {
    let (w, h) = c.size();
    let m = c.px(14.0);
    let mut top = m;
    if !fig.title.is_empty() {
        let em = fitting_em(c, &fig.title, TITLE_EM, w - 2.0 * m)?;
        let title = truncated(c, &fig.title, em, w - 2.0 * m)?;
        let lh = c.px(em * 1.3);
        c.text(
            &title,
            (w / 2.0, top + lh / 2.0),
            em,
            TEXT,
            HPos::Center,
            false,
        )?;
        top += lh;
    }
    if let Some(sub) = fig.subtitle.as_deref().filter(|s| !s.is_empty()) {
        let em = SUBTITLE_EM;
        let lh = c.px(em * 1.3);
        // A tile keeps its height for the data.
        let max_lines = if h >= c.px(400.0) {
            4
        } else if h >= c.px(250.0) {
            2
        } else {
            1
        };
        for line in wrapped(c, sub, em, w - 2.0 * m, max_lines)? {
            c.text(
                &line,
                (w / 2.0, top + lh / 2.0),
                em,
                MUTED,
                HPos::Center,
                false,
            )?;
            top += lh;
        }
        top += c.px(2.0);
    }
    Ok(Rect {
        l: m,
        t: top + c.px(8.0),
        r: w - m,
        b: h - m,
    })
}

/// `text` broken at spaces into lines of at most `max_w`; at most `max_lines`, the last
/// cut with an ellipsis when the text does not end there.
fn wrapped<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    text: &str,
    em: f64,
    max_w: f64,
    max_lines: usize,
) -> Result<Vec<String>, FigureError> {
    let mut lines: Vec<String> = Vec::new();
    let mut current = String::new();
    let words: Vec<&str> = text.split_whitespace().collect();
    for (i, word) in words.iter().enumerate() {
        let candidate = if current.is_empty() {
            word.to_string()
        } else {
            format!("{current} {word}")
        };
        if current.is_empty() || c.text_size(&candidate, em)?.0 <= max_w {
            current = candidate;
            continue;
        }
        lines.push(std::mem::take(&mut current));
        if lines.len() == max_lines {
            let last = lines.pop().unwrap_or_default();
            let rest = words[i..].join(" ");
            lines.push(truncated(c, &format!("{last} {rest}"), em, max_w)?);
            return Ok(lines);
        }
        current = word.to_string();
    }
    if !current.is_empty() {
        lines.push(truncated(c, &current, em, max_w)?);
    }
    Ok(lines)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_hit_rectangles() {
        let r = Rect {
            l: 0.0,
            t: 0.0,
            r: 10.0,
            b: 10.0,
        };
        assert!(segment_hits(&r, (-5.0, 5.0), (15.0, 5.0)));
        assert!(segment_hits(&r, (5.0, 5.0), (50.0, 50.0)));
        assert!(!segment_hits(&r, (-5.0, -1.0), (15.0, -1.0)));
        assert!(!segment_hits(&r, (11.0, 0.0), (20.0, 10.0)));
    }
}
