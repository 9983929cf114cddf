//! Exporting figures from the window: the export settings and "Export all".

use super::*;

/// Export settings shared by every view; they persist between runs.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExportSettings {
    pub dir: PathBuf,
    pub width: u32,
    pub height: u32,
    pub dpi: f64,
    /// The user has confirmed the folder once (the first export asks where to write).
    #[serde(default)]
    pub chosen: bool,
}

/// An export asked for before the export folder was confirmed.
#[derive(Clone, Debug)]
pub enum PendingExport {
    /// One figure, by file name.
    Figure(Box<figures::Figure>, String),
    /// File > Export all figures.
    All,
}

/// The export folder's name in the data folder, the default until the user chooses one.
pub const EXPORTS: &str = "exports";

/// The formats every export writes: vector (SVG, PDF), raster (PNG) and the numbers (CSV).
const FORMATS: [Format; 4] = [Format::Svg, Format::Pdf, Format::Png, Format::Csv];

/// The size presets offered, by name: a journal column, a full page width (both 300 DPI,
/// 8–9 pt text) and the screen.
fn presets() -> [(&'static str, RenderOptions); 3] {
    [
        ("Column (3.5 in, 300 DPI)", RenderOptions::column()),
        ("Page width (7 in, 300 DPI)", RenderOptions::page()),
        ("Screen (960 × 640, 96 DPI)", RenderOptions::default()),
    ]
}

impl Default for ExportSettings {
    /// A journal column: what a figure exported from the workbench is most often for.
    fn default() -> Self {
        let o = RenderOptions::column();
        // The data folder's exports, never the working folder (often a source checkout).
        let data = eframe::storage_dir("Tactile Workbench").unwrap_or_else(std::env::temp_dir);
        ExportSettings {
            dir: data.join(EXPORTS),
            width: o.width,
            height: o.height,
            dpi: o.dpi,
            chosen: false,
        }
    }
}

impl ExportSettings {
    /// The export folder as an absolute path (a relative one typed in the form is taken
    /// from the data folder's exports, not from wherever the workbench was started).
    pub fn folder(&self) -> PathBuf {
        if self.dir.is_absolute() {
            self.dir.clone()
        } else {
            ExportSettings::default().dir.join(&self.dir)
        }
    }

    fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.width,
            height: self.height,
            dpi: self.dpi,
        }
    }

    /// The folder, size and DPI form, laid out down the panel so that opening it never
    /// widens the panel.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let caption = ui.label("Export folder");
        let mut dir = self.dir.display().to_string();
        if ui
            .add(egui::TextEdit::singleline(&mut dir).desired_width(ui.available_width()))
            .labelled_by(caption.id)
            .changed()
        {
            self.dir = PathBuf::from(dir);
        }
        for (name, o) in presets() {
            let on = self.options() == o;
            if ui.selectable_label(on, name).clicked() {
                (self.width, self.height, self.dpi) = (o.width, o.height, o.dpi);
            }
        }
        ui.horizontal_wrapped(|ui| {
            ui.add(
                egui::DragValue::new(&mut self.width)
                    .range(200..=6000)
                    .prefix("width "),
            );
            ui.add(
                egui::DragValue::new(&mut self.height)
                    .range(150..=6000)
                    .prefix("height "),
            );
            ui.add(
                egui::DragValue::new(&mut self.dpi)
                    .range(48.0..=600.0)
                    .prefix("DPI "),
            );
        });
    }

    /// Write `figure` as SVG, PDF, PNG and CSV named `name`, and say so in `notes`.
    pub fn write(&self, figure: &figures::Figure, name: &str, notes: &mut Notifications) {
        let opts = self.options();
        let dir = self.folder();
        let mut written = Vec::new();
        let result = std::fs::create_dir_all(&dir)
            .map_err(|e| format!("{}: {e}", dir.display()))
            .and_then(|_| {
                for f in FORMATS {
                    let path = dir.join(format!("{name}.{}", f.extension()));
                    figures::write_figure(figure, &path, &opts).map_err(|e| e.to_string())?;
                    written.push(path.display().to_string());
                }
                Ok(())
            });
        match result {
            Ok(()) => notes.info(format!("exported {}", written.join(", "))),
            Err(e) => notes.error(format!("export of {name} failed: {e}")),
        }
    }
}

impl Analyses {
    /// Export `figure` as `name` into the export folder; the first export asks for the
    /// folder first ([`Analyses::export_folder_ui`]).
    pub fn export_figure(&mut self, figure: &figures::Figure, name: &str) {
        if self.export.chosen {
            self.export.write(figure, name, &mut self.notes);
        } else {
            let pending = PendingExport::Figure(Box::new(figure.clone()), name.to_string());
            self.pending_export = Some(pending);
        }
    }

    /// The first export's question: which folder, with the data folder's exports offered.
    /// Once confirmed, the export waiting goes ahead and later ones do not ask again.
    pub fn export_folder_ui(&mut self, ctx: &egui::Context) {
        if self.pending_export.is_none() {
            return;
        }
        let (mut go, mut cancel) = (false, false);
        egui::Window::new("Export to which folder?")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label(
                    "Figures are written as SVG, PDF, PNG and CSV into this folder (it is made \
                     when missing). The folder and the size are kept under Export settings.",
                );
                self.export.ui(ui);
                ui.horizontal(|ui| {
                    go = ui.button("Export here").clicked();
                    cancel = ui.button("Cancel").clicked();
                });
            });
        if cancel {
            self.pending_export = None;
        } else if go {
            let Some(pending) = self.pending_export.take() else {
                return;
            };
            self.export.chosen = true;
            match pending {
                PendingExport::Figure(figure, name) => self.export_figure(&figure, &name),
                PendingExport::All => self.export_all(ctx),
            }
        }
    }

    /// Export every figure of every result in the background (the first export asks for
    /// the folder first).
    pub fn export_all(&mut self, ctx: &egui::Context) {
        if !self.export.chosen {
            self.pending_export = Some(PendingExport::All);
            return;
        }
        let set = result::figure_set(&self.results);
        let mut set_all = set;
        let extra = result::speed_accuracy_figures(&self.results)
            .into_iter()
            .chain(comparison_figures(&self.results));
        for (name, f) in extra {
            set_all.entries.push(figures::FigureEntry {
                name,
                figure: f,
                parameters: Default::default(),
                session: "all".into(),
                date: date_text(result::now_unix()),
            });
        }
        // Each session's frontiers on one chart per time axis.
        let mut sessions: Vec<&str> = self.frontiers.iter().map(|f| f.session.as_str()).collect();
        sessions.dedup();
        for session in sessions {
            let of: Vec<Frontier> = self
                .frontiers
                .iter()
                .filter(|f| f.session == session)
                .cloned()
                .collect();
            for (name, f) in frontier_figures(&of) {
                set_all.entries.push(figures::FigureEntry {
                    name: format!("{name}-{}", result::slug(session)),
                    figure: f,
                    parameters: Default::default(),
                    session: session.to_string(),
                    date: date_text(result::now_unix()),
                });
            }
        }
        let dir = self.export.folder();
        let opts = self.export.options();
        self.spawn(ctx, None, "Export all figures".into(), move |p| {
            p.set(0.0, format!("writing {} figures", set_all.entries.len()));
            let t0 = std::time::Instant::now();
            let index =
                figures::export_all(&set_all, &dir, &FORMATS, &opts).map_err(JobError::failed)?;
            let written = format!(
                "exported {} figures to {} in {:.2} s",
                index.entries.len(),
                dir.display(),
                t0.elapsed().as_secs_f64()
            );
            if index.not_drawn.is_empty() {
                Ok(JobOutput::Message(written))
            } else {
                Err(JobError::failed(format!(
                    "{written}; not drawn at this size (the index lists them): {}",
                    index.not_drawn_text()
                )))
            }
        });
    }
}
