//! A thin pixel-space drawing layer over a plotters drawing area: every figure kind is
//! laid out by hand in pixels (so that margins, ticks and colour bars look the same across
//! kinds and backends), and sizes given in CSS pixels at 96 DPI are scaled by `dpi / 96`.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use std::cell::RefCell;

use super::FigureError;
use super::colormap::Rgb;
use super::layout::{AxisLabels, Bounds, FigureLayout, PlacedText};

/// The family name the embedded font is registered under.
pub(super) const FONT: &str = "sans-serif";

/// plotters sizes fonts by line height, about 1.24 em (its SVG backend divides by it).
const EM_TO_PLOTTERS: f64 = 1.24;

pub(super) const TEXT: Rgb = Rgb(0x22, 0x22, 0x22);
pub(super) const MUTED: Rgb = Rgb(0x55, 0x55, 0x55);
pub(super) const GRID: Rgb = Rgb(0xe6, 0xe6, 0xe6);
pub(super) const AXIS: Rgb = Rgb(0x44, 0x44, 0x44);
pub(super) const WHITE: Rgb = Rgb(0xff, 0xff, 0xff);

pub(super) fn color(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

/// How text reaches the output.
pub(super) enum TextMode {
    /// As `<text>` elements (selectable, searchable), sized with the embedded font.
    Svg,
    /// Rasterised here from the embedded font's outlines.
    Raster,
    /// As SVG paths of the glyph outlines (for the PDF, which then needs no font).
    Outline,
}

pub(super) struct Canvas<'a, DB: DrawingBackend> {
    area: &'a DrawingArea<DB, Shift>,
    /// DPI / 96: multiplies every length given in CSS pixels.
    pub scale: f64,
    font: &'a FontRef<'static>,
    mode: TextMode,
    /// What was placed where, for the layout checks.
    record: RefCell<FigureLayout>,
    /// Glyph outlines as SVG `<path>` elements ([`TextMode::Outline`]).
    glyph_paths: RefCell<String>,
}

/// A line of text laid out from its baseline origin, in device pixels.
struct Layout {
    glyphs: Vec<ab_glyph::Glyph>,
    width: f64,
}

fn render_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> FigureError {
    FigureError::Render(e.to_string())
}

impl<'a, DB: DrawingBackend> Canvas<'a, DB> {
    pub fn new(
        area: &'a DrawingArea<DB, Shift>,
        scale: f64,
        font: &'a FontRef<'static>,
        mode: TextMode,
    ) -> Self {
        let (w, h) = area.dim_in_pixel();
        Canvas {
            area,
            scale,
            font,
            mode,
            record: RefCell::new(FigureLayout {
                width: w as f64,
                height: h as f64,
                ..FigureLayout::default()
            }),
            glyph_paths: RefCell::new(String::new()),
        }
    }

    /// The glyph outlines drawn in [`TextMode::Outline`], as SVG elements.
    pub fn glyph_paths(&self) -> String {
        self.glyph_paths.borrow().clone()
    }

    /// What was drawn so far.
    pub fn layout_record(&self) -> FigureLayout {
        self.record.borrow().clone()
    }

    /// Record the tick labels of an axis; `categories` for a category axis.
    pub fn note_axis(&self, title: &str, categories: Option<usize>, labels: &[String]) {
        self.record.borrow_mut().axes.push(AxisLabels {
            title: title.to_string(),
            categories,
            labels: labels.to_vec(),
        });
    }

    pub fn note_legend(&self, bounds: Bounds) {
        self.record.borrow_mut().legend = Some(bounds);
    }

    /// Record a data mark (marker, line vertex, bar).
    pub fn note_data(&self, bounds: Bounds) {
        self.record.borrow_mut().data.push(bounds);
    }

    /// The box `text` takes when drawn by [`Canvas::text`] with these arguments: the
    /// glyphs' em box (not the line height), so that stacked lines do not count as touching.
    pub fn text_bounds(
        &self,
        text: &str,
        (x, y): (f64, f64),
        em_css: f64,
        anchor: HPos,
        rotated: bool,
    ) -> Bounds {
        let w = self.layout(text, em_css).width;
        let h = em_css * self.scale;
        let (a, b) = match anchor {
            HPos::Left => (0.0, w),
            HPos::Center => (-w / 2.0, w / 2.0),
            HPos::Right => (-w, 0.0),
        };
        if rotated {
            // Reads bottom to top: the text's x runs up the page.
            Bounds::new(x - h / 2.0, y - b, x + h / 2.0, y - a)
        } else {
            Bounds::new(x + a, y - h / 2.0, x + b, y + h / 2.0)
        }
    }

    pub fn size(&self) -> (f64, f64) {
        let (w, h) = self.area.dim_in_pixel();
        (w as f64, h as f64)
    }

    /// A length in CSS pixels, scaled to device pixels.
    pub fn px(&self, css: f64) -> f64 {
        css * self.scale
    }

    fn stroke(&self, css_width: f64) -> u32 {
        (css_width * self.scale).round().max(1.0) as u32
    }

    fn layout(&self, text: &str, em_css: f64) -> Layout {
        let em_px = (em_css * self.scale) as f32;
        // ab_glyph scales by the ascent-to-descent height, not by the em.
        let per_em = self.font.height_unscaled() / self.font.units_per_em().unwrap_or(1000.0);
        let scale = PxScale::from(em_px * per_em);
        let sf = self.font.as_scaled(scale);
        let mut caret = 0.0f32;
        let mut prev = None;
        let mut glyphs = Vec::with_capacity(text.len());
        for ch in text.chars() {
            let id = sf.glyph_id(ch);
            if let Some(p) = prev {
                caret += sf.kern(p, id);
            }
            glyphs.push(id.with_scale_and_position(scale, point(caret, 0.0)));
            caret += sf.h_advance(id);
            prev = Some(id);
        }
        Layout {
            glyphs,
            width: caret as f64,
        }
    }

    /// Draw laid-out glyphs with coverage blending, the line centred vertically on `y` by
    /// its cap height (about 0.7 em), optionally rotated to read bottom to top.
    fn raster_text(
        &self,
        layout: &Layout,
        (x, y): (f64, f64),
        em_css: f64,
        c: Rgb,
        h: HPos,
        rotated: bool,
    ) -> Result<(), FigureError> {
        let dx = match h {
            HPos::Left => 0.0,
            HPos::Center => -layout.width / 2.0,
            HPos::Right => -layout.width,
        };
        let baseline = 0.35 * em_css * self.scale;
        let ink = color(c);
        for g in &layout.glyphs {
            let Some(outline) = self.font.outline_glyph(g.clone()) else {
                continue;
            };
            let b = outline.px_bounds();
            let mut result = Ok(());
            outline.draw(|gx, gy, coverage| {
                if coverage <= 0.0 || result.is_err() {
                    return;
                }
                let lx = dx + f64::from(b.min.x + gx as f32);
                let ly = baseline + f64::from(b.min.y + gy as f32);
                // Rotated by 270°: the text's x axis points up.
                let (px, py) = if rotated {
                    (x + ly, y - lx)
                } else {
                    (x + lx, y + ly)
                };
                result = self
                    .area
                    .draw_pixel(
                        (px.round() as i32, py.round() as i32),
                        &ink.mix(f64::from(coverage.min(1.0))),
                    )
                    .map_err(render_err);
            });
            result?;
        }
        Ok(())
    }

    /// Append the glyphs' outlines as one SVG path, placed as [`Canvas::raster_text`] places
    /// its pixels.
    fn outline_text(
        &self,
        layout: &Layout,
        (x, y): (f64, f64),
        em_css: f64,
        c: Rgb,
        h: HPos,
        rotated: bool,
    ) {
        use std::fmt::Write;
        let dx = match h {
            HPos::Left => 0.0,
            HPos::Center => -layout.width / 2.0,
            HPos::Right => -layout.width,
        };
        let em_px = em_css * self.scale;
        let baseline = 0.35 * em_px;
        // Font units (y up) to pixels.
        let k = em_px / f64::from(self.font.units_per_em().unwrap_or(1000.0));
        let mut d = String::new();
        for g in &layout.glyphs {
            let Some(outline) = self.font.outline(g.id) else {
                continue;
            };
            let gx = dx + f64::from(g.position.x);
            let place = |p: ab_glyph::Point| {
                let (lx, ly) = (gx + f64::from(p.x) * k, baseline - f64::from(p.y) * k);
                if rotated {
                    (x + ly, y - lx)
                } else {
                    (x + lx, y + ly)
                }
            };
            let mut last: Option<ab_glyph::Point> = None;
            for curve in &outline.curves {
                let (start, end) = match curve {
                    ab_glyph::OutlineCurve::Line(a, b) => (*a, *b),
                    ab_glyph::OutlineCurve::Quad(a, _, b) => (*a, *b),
                    ab_glyph::OutlineCurve::Cubic(a, _, _, b) => (*a, *b),
                };
                if last != Some(start) {
                    let (px, py) = place(start);
                    let _ = write!(d, "M{px:.2} {py:.2}");
                }
                match curve {
                    ab_glyph::OutlineCurve::Line(_, b) => {
                        let (px, py) = place(*b);
                        let _ = write!(d, "L{px:.2} {py:.2}");
                    }
                    ab_glyph::OutlineCurve::Quad(_, c1, b) => {
                        let ((ax, ay), (bx, by)) = (place(*c1), place(*b));
                        let _ = write!(d, "Q{ax:.2} {ay:.2} {bx:.2} {by:.2}");
                    }
                    ab_glyph::OutlineCurve::Cubic(_, c1, c2, b) => {
                        let ((ax, ay), (bx, by), (ex, ey)) = (place(*c1), place(*c2), place(*b));
                        let _ = write!(d, "C{ax:.2} {ay:.2} {bx:.2} {by:.2} {ex:.2} {ey:.2}");
                    }
                }
                last = Some(end);
            }
        }
        if !d.is_empty() {
            let _ = writeln!(
                self.glyph_paths.borrow_mut(),
                r##"<path fill="#{:02x}{:02x}{:02x}" d="{d}"/>"##,
                c.0,
                c.1,
                c.2
            );
        }
    }

    /// Width and height of `text` in device pixels at font size `em_css`.
    pub fn text_size(&self, text: &str, em_css: f64) -> Result<(f64, f64), FigureError> {
        if text.is_empty() {
            return Ok((0.0, 0.0));
        }
        Ok((self.layout(text, em_css).width, em_css * self.scale * 1.2))
    }

    /// Draw `text` aligned at `x` by `anchor` and centred vertically on `y`; `rotated`
    /// reads bottom to top (y-axis titles).
    pub fn text(
        &self,
        text: &str,
        (x, y): (f64, f64),
        em_css: f64,
        c: Rgb,
        anchor: HPos,
        rotated: bool,
    ) -> Result<(), FigureError> {
        if text.is_empty() {
            return Ok(());
        }
        let bounds = self.text_bounds(text, (x, y), em_css, anchor, rotated);
        self.record.borrow_mut().texts.push(PlacedText {
            text: text.to_string(),
            bounds,
        });
        match self.mode {
            TextMode::Raster => {
                let layout = self.layout(text, em_css);
                self.raster_text(&layout, (x, y), em_css, c, anchor, rotated)
            }
            TextMode::Outline => {
                let layout = self.layout(text, em_css);
                self.outline_text(&layout, (x, y), em_css, c, anchor, rotated);
                Ok(())
            }
            TextMode::Svg => {
                let mut style = (FONT, em_css * self.scale * EM_TO_PLOTTERS)
                    .into_font()
                    .color(&color(c))
                    .pos(Pos::new(anchor, VPos::Center));
                if rotated {
                    style = style.transform(FontTransform::Rotate270);
                }
                let at = (x.round() as i32, y.round() as i32);
                self.area
                    .draw(&Text::new(text.to_string(), at, style))
                    .map_err(render_err)
            }
        }
    }

    pub fn fill_rect(
        &self,
        (x0, y0): (f64, f64),
        (x1, y1): (f64, f64),
        c: Rgb,
    ) -> Result<(), FigureError> {
        let p0 = (x0.round() as i32, y0.round() as i32);
        let p1 = (x1.round() as i32, y1.round() as i32);
        if p0.0 == p1.0 || p0.1 == p1.1 {
            return Ok(());
        }
        self.area
            .draw(&Rectangle::new([p0, p1], color(c).filled()))
            .map_err(render_err)
    }

    pub fn stroke_rect(
        &self,
        (x0, y0): (f64, f64),
        (x1, y1): (f64, f64),
        c: Rgb,
        css_width: f64,
    ) -> Result<(), FigureError> {
        let p0 = (x0.round() as i32, y0.round() as i32);
        let p1 = (x1.round() as i32, y1.round() as i32);
        let style = color(c).stroke_width(self.stroke(css_width));
        self.area
            .draw(&Rectangle::new([p0, p1], style))
            .map_err(render_err)
    }

    pub fn polyline(
        &self,
        points: &[(f64, f64)],
        c: Rgb,
        css_width: f64,
    ) -> Result<(), FigureError> {
        if points.len() < 2 {
            return Ok(());
        }
        let pts: Vec<(i32, i32)> = points
            .iter()
            .map(|&(x, y)| (x.round() as i32, y.round() as i32))
            .collect();
        let style = color(c).stroke_width(self.stroke(css_width));
        self.area
            .draw(&PathElement::new(pts, style))
            .map_err(render_err)
    }

    pub fn line(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        c: Rgb,
        css_width: f64,
    ) -> Result<(), FigureError> {
        self.polyline(&[a, b], c, css_width)
    }

    /// A dashed straight line (reference lines).
    pub fn dashed_line(
        &self,
        a: (f64, f64),
        b: (f64, f64),
        c: Rgb,
        css_width: f64,
    ) -> Result<(), FigureError> {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy);
        let (dash, gap) = (self.px(6.0), self.px(4.0));
        let mut t = 0.0;
        while t < len {
            let t1 = (t + dash).min(len);
            let p = |s: f64| (a.0 + dx * s / len, a.1 + dy * s / len);
            self.line(p(t), p(t1), c, css_width)?;
            t = t1 + gap;
        }
        Ok(())
    }

    /// A filled polygon, `opacity` in 0..=1 (error bands).
    pub fn polygon(&self, points: &[(f64, f64)], c: Rgb, opacity: f64) -> Result<(), FigureError> {
        if points.len() < 3 {
            return Ok(());
        }
        let pts: Vec<(i32, i32)> = points
            .iter()
            .map(|&(x, y)| (x.round() as i32, y.round() as i32))
            .collect();
        self.area
            .draw(&Polygon::new(pts, color(c).mix(opacity).filled()))
            .map_err(render_err)
    }

    /// A data marker of the given shape, `r_css` its half size.
    pub fn marker(
        &self,
        shape: Marker,
        (x, y): (f64, f64),
        r_css: f64,
        c: Rgb,
    ) -> Result<(), FigureError> {
        let r = self.px(r_css);
        let (xi, yi) = (x.round() as i32, y.round() as i32);
        let fill = color(c).filled();
        let outline = |pts: Vec<(f64, f64)>| -> Result<(), FigureError> {
            let pts: Vec<(i32, i32)> = pts
                .into_iter()
                .map(|(px, py)| (px.round() as i32, py.round() as i32))
                .collect();
            self.area.draw(&Polygon::new(pts, fill)).map_err(render_err)
        };
        match shape {
            Marker::Circle => self
                .area
                .draw(&Circle::new((xi, yi), r.round().max(1.0) as u32, fill))
                .map_err(render_err),
            Marker::Square => {
                let s = r * 0.88;
                self.fill_rect((x - s, y - s), (x + s, y + s), c)
            }
            Marker::Triangle => outline(vec![
                (x, y - r * 1.15),
                (x + r * 1.05, y + r * 0.75),
                (x - r * 1.05, y + r * 0.75),
            ]),
            Marker::Diamond => outline(vec![
                (x, y - r * 1.2),
                (x + r, y),
                (x, y + r * 1.2),
                (x - r, y),
            ]),
        }
    }
}

/// Marker shapes, cycled per series so that series stay apart in black and white.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
}

impl Marker {
    pub fn nth(i: usize) -> Marker {
        [
            Marker::Circle,
            Marker::Square,
            Marker::Triangle,
            Marker::Diamond,
        ][i % 4]
    }
}
