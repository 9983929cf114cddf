//! Rendering to SVG / PNG bytes and writing files: one figure, or a whole [`FigureSet`]
//! with an index. Files are written atomically, so a failed export never leaves a
//! half-written figure.

use std::collections::{BTreeMap, HashSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use ab_glyph::FontRef;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use serde::{Deserialize, Serialize};

use super::FigureError;
use super::canvas::{Canvas, FONT, TextMode};
use super::csv::to_csv;
use super::layout::FigureLayout;
use super::model::{Figure, FigureSet};
use super::render;
use crate::fsutil;

/// Size of the exported image in pixels, and its resolution: text and lines are scaled by
/// `dpi / 96`, so a 300-DPI export of a larger image keeps the proportions of a 96-DPI one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub dpi: f64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 960,
            height: 640,
            dpi: 96.0,
        }
    }
}

impl RenderOptions {
    /// A journal column: 3.5 in wide (and 7/3 in tall) at 300 DPI; text is 8–9 pt.
    pub fn column() -> Self {
        RenderOptions {
            width: 1050,
            height: 700,
            dpi: 300.0,
        }
    }

    /// A full page width: 7 in wide (and 3.5 in tall) at 300 DPI; text is 8–9 pt.
    pub fn page() -> Self {
        RenderOptions {
            width: 2100,
            height: 1050,
            dpi: 300.0,
        }
    }
}

/// Largest side accepted (an RGB buffer of 8192² is 200 MB).
const MAX_SIDE: u32 = 8192;

impl RenderOptions {
    pub fn validate(&self) -> Result<(), FigureError> {
        let side = |v: u32, what: &str| {
            if (64..=MAX_SIDE).contains(&v) {
                Ok(())
            } else {
                Err(FigureError::Options(format!(
                    "{what} must be 64..={MAX_SIDE} pixels, got {v}"
                )))
            }
        };
        side(self.width, "width")?;
        side(self.height, "height")?;
        if !(self.dpi.is_finite() && (24.0..=1200.0).contains(&self.dpi)) {
            return Err(FigureError::Options(format!(
                "dpi must be 24..=1200, got {}",
                self.dpi
            )));
        }
        Ok(())
    }

    fn scale(&self) -> f64 {
        self.dpi / 96.0
    }
}

/// Export formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    Svg,
    Png,
    Csv,
    /// Vector, with the text as glyph outlines (no font needed to view or print it).
    Pdf,
}

impl Format {
    pub fn extension(self) -> &'static str {
        match self {
            Format::Svg => "svg",
            Format::Png => "png",
            Format::Csv => "csv",
            Format::Pdf => "pdf",
        }
    }

    /// The format a path's extension names.
    pub fn from_path(path: &Path) -> Result<Format, FigureError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            Some("csv") => Ok(Format::Csv),
            Some("pdf") => Ok(Format::Pdf),
            _ => Err(FigureError::Options(format!(
                "{}: the file name must end in .svg, .png, .pdf or .csv",
                path.display()
            ))),
        }
    }
}

/// The embedded font, parsed once; also registered with plotters, whose SVG text style
/// needs the family to exist.
fn font() -> Result<&'static FontRef<'static>, FigureError> {
    static FONT_REF: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT_REF
        .get_or_init(|| {
            let bytes = epaint_default_fonts::UBUNTU_LIGHT;
            register_font(FONT, FontStyle::Normal, bytes).ok()?;
            FontRef::try_from_slice(bytes).ok()
        })
        .as_ref()
        .ok_or_else(|| FigureError::Render("the embedded font could not be loaded".into()))
}

fn draw_err(e: impl std::fmt::Display) -> FigureError {
    FigureError::Render(e.to_string())
}

/// The figure as an SVG document (text as `<text>` or as glyph outlines), with what was
/// placed where.
fn svg_and_layout(
    fig: &Figure,
    opts: &RenderOptions,
    mode: TextMode,
) -> Result<(String, FigureLayout), FigureError> {
    opts.validate()?;
    let font = font()?;
    let mut out = String::new();
    let (layout, glyphs);
    {
        let root = SVGBackend::with_string(&mut out, (opts.width, opts.height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let canvas = Canvas::new(&root, opts.scale(), font, mode);
        render::draw(&canvas, fig)?;
        layout = canvas.layout_record();
        glyphs = canvas.glyph_paths();
        root.present().map_err(draw_err)?;
    }
    // Bands are translucent fills: `fill-opacity` says so in every renderer (plotters
    // writes `opacity`, which some renderers ignore on polygons).
    let mut out = out.replace("<polygon opacity=", "<polygon fill-opacity=");
    if let Some(end) = out.rfind("</svg>") {
        out.insert_str(end, &glyphs);
    }
    Ok((out, layout))
}

/// The figure as an SVG document.
pub fn render_svg(fig: &Figure, opts: &RenderOptions) -> Result<String, FigureError> {
    Ok(svg_and_layout(fig, opts, TextMode::Svg)?.0)
}

/// The figure as a one-page PDF of the image's physical size (pixels / DPI), converted
/// from the SVG with its text as glyph outlines.
pub fn render_pdf(fig: &Figure, opts: &RenderOptions) -> Result<Vec<u8>, FigureError> {
    let svg = svg_and_layout(fig, opts, TextMode::Outline)?.0;
    let tree = svg2pdf::usvg::Tree::from_str(&svg, &svg2pdf::usvg::Options::default())
        .map_err(draw_err)?;
    let page = svg2pdf::PageOptions {
        dpi: opts.dpi as f32,
    };
    svg2pdf::to_pdf(&tree, svg2pdf::ConversionOptions::default(), page).map_err(draw_err)
}

/// Where the export places each text, tick label, the legend and the data of `fig` at
/// this size: for checking that a figure stays legible (see [`FigureLayout`]).
pub fn layout_of(fig: &Figure, opts: &RenderOptions) -> Result<FigureLayout, FigureError> {
    Ok(svg_and_layout(fig, opts, TextMode::Svg)?.1)
}

/// The figure as PNG bytes (RGB, 8 bits), with its DPI recorded in the pHYs chunk.
pub fn render_png(fig: &Figure, opts: &RenderOptions) -> Result<Vec<u8>, FigureError> {
    opts.validate()?;
    let font = font()?;
    // Sides ≤ MAX_SIDE: the product fits a usize.
    let mut pixels = vec![0u8; opts.width as usize * opts.height as usize * 3];
    {
        let root =
            BitMapBackend::with_buffer(&mut pixels, (opts.width, opts.height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        render::draw(
            &Canvas::new(&root, opts.scale(), font, TextMode::Raster),
            fig,
        )?;
        root.present().map_err(draw_err)?;
    }
    let mut png_bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut png_bytes, opts.width, opts.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let per_metre = (opts.dpi / 0.0254).round() as u32;
    encoder.set_pixel_dims(Some(png::PixelDimensions {
        xppu: per_metre,
        yppu: per_metre,
        unit: png::Unit::Meter,
    }));
    let mut writer = encoder.write_header().map_err(draw_err)?;
    writer.write_image_data(&pixels).map_err(draw_err)?;
    writer.finish().map_err(draw_err)?;
    Ok(png_bytes)
}

fn render(fig: &Figure, format: Format, opts: &RenderOptions) -> Result<Vec<u8>, FigureError> {
    Ok(match format {
        Format::Svg => render_svg(fig, opts)?.into_bytes(),
        Format::Png => render_png(fig, opts)?,
        Format::Csv => to_csv(fig)?.into_bytes(),
        Format::Pdf => render_pdf(fig, opts)?,
    })
}

/// Write `bytes` to `path` atomically (see [`crate::fsutil`]); the error names `path`.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FigureError> {
    fsutil::write_atomic(path, bytes).map_err(|source| FigureError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Render `fig` to `path`, the format given by the extension (.svg, .png or .csv).
pub fn write_figure(fig: &Figure, path: &Path, opts: &RenderOptions) -> Result<(), FigureError> {
    let bytes = render(fig, Format::from_path(path)?, opts)?;
    write_atomic(path, &bytes)
}

/// One line of the index of an "export all".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IndexEntry {
    pub name: String,
    pub title: String,
    /// File names, relative to the export directory.
    pub files: Vec<String>,
    pub parameters: BTreeMap<String, String>,
    pub session: String,
    pub date: String,
}

/// What an "export all" wrote; also written as `index.md` in the directory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Index {
    pub dir: PathBuf,
    pub entries: Vec<IndexEntry>,
    /// Figures that could not be drawn at the export's size and DPI, with why; every
    /// other figure is written all the same.
    #[serde(default)]
    pub not_drawn: Vec<NotDrawn>,
}

/// A figure an "export all" could not draw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NotDrawn {
    pub name: String,
    pub title: String,
    pub reason: String,
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

impl Index {
    /// "name (title): reason; …" of the figures not drawn, for a message.
    pub fn not_drawn_text(&self) -> String {
        self.not_drawn
            .iter()
            .map(|n| format!("{} («{}»): {}", n.name, n.title, n.reason))
            .collect::<Vec<_>>()
            .join("; ")
    }

    pub fn to_markdown(&self) -> String {
        let mut out = String::from(
            "# Figures\n\n| Figure | Files | Parameters | Session | Date |\n|---|---|---|---|---|\n",
        );
        for e in &self.entries {
            let files: Vec<String> = e.files.iter().map(|f| format!("[{f}]({f})")).collect();
            let params: Vec<String> = e
                .parameters
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect();
            out.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                md_cell(&e.title),
                files.join(", "),
                md_cell(&params.join(", ")),
                md_cell(&e.session),
                md_cell(&e.date)
            ));
        }
        if !self.not_drawn.is_empty() {
            out.push_str("\n## Not drawn at this size\n\n");
            for n in &self.not_drawn {
                out.push_str(&format!(
                    "- {} ({}): {}\n",
                    md_cell(&n.name),
                    md_cell(&n.title),
                    md_cell(&n.reason)
                ));
            }
        }
        out
    }
}

/// Write every figure of `set` to `dir` (created if missing) in each of `formats`, plus
/// `index.md`. All figures and names are checked before the first file is written. A figure
/// that cannot be drawn at `opts` is listed in the index's `not_drawn` and the others are
/// still written; a file that cannot be written stops the export.
pub fn export_all(
    set: &FigureSet,
    dir: &Path,
    formats: &[Format],
    opts: &RenderOptions,
) -> Result<Index, FigureError> {
    if formats.is_empty() {
        return Err(FigureError::Options("no export format chosen".into()));
    }
    opts.validate()?;
    let mut seen = HashSet::new();
    for e in &set.entries {
        let valid_name = !e.name.is_empty()
            && e.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
        if !valid_name {
            return Err(FigureError::Options(format!(
                "figure name {:?}: use letters, digits, '-' and '_' only",
                e.name
            )));
        }
        if !seen.insert(e.name.as_str()) {
            return Err(FigureError::Options(format!(
                "figure name {:?} is used twice",
                e.name
            )));
        }
        e.figure.validate()?;
    }
    fs::create_dir_all(dir).map_err(|source| FigureError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut index = Index {
        dir: dir.to_path_buf(),
        entries: Vec::new(),
        not_drawn: Vec::new(),
    };
    for e in &set.entries {
        // Every format is drawn before any is written: a figure is exported whole or not.
        let drawn: Result<Vec<(String, Vec<u8>)>, FigureError> = formats
            .iter()
            .map(|&format| {
                let file = format!("{}.{}", e.name, format.extension());
                render(&e.figure, format, opts).map(|bytes| (file, bytes))
            })
            .collect();
        let drawn = match drawn {
            Ok(d) => d,
            Err(io @ FigureError::Io { .. }) => return Err(io),
            // Too small at this size and DPI, or not drawable: this figure only.
            Err(why) => {
                index.not_drawn.push(NotDrawn {
                    name: e.name.clone(),
                    title: e.figure.title.clone(),
                    reason: why.to_string(),
                });
                continue;
            }
        };
        let mut files = Vec::new();
        for (file, bytes) in drawn {
            write_atomic(&dir.join(&file), &bytes)?;
            files.push(file);
        }
        index.entries.push(IndexEntry {
            name: e.name.clone(),
            title: e.figure.title.clone(),
            files,
            parameters: e.parameters.clone(),
            session: e.session.clone(),
            date: e.date.clone(),
        });
    }
    write_atomic(&dir.join("index.md"), index.to_markdown().as_bytes())?;
    Ok(index)
}
