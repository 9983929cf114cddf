//! The dialog that imports a researcher's own recording (a ROS 2 bag or a long-format CSV)
//! with the import spec that describes it (docs/import.md). Opening or dropping such a file
//! queues it here; the spec is chosen, checked, and only then is the recording read, on the
//! loader's worker thread like any session.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};

use super::loader::Source;
use crate::session::ImportSpec;

/// Recordings waiting for their spec, the first one shown.
#[derive(Default)]
pub struct ImportDialog {
    queue: Vec<PathBuf>,
    /// The spec's path as typed or chosen, for the recording at the front of the queue.
    spec: String,
    /// Why the spec was refused, shown until the spec changes.
    error: Option<String>,
    picking: Option<Receiver<Option<PathBuf>>>,
    /// The last spec that imported, offered again for the next recording of a batch.
    last_spec: Option<PathBuf>,
}

/// The spec a recording most likely goes with: `<name>.spec.json` beside it (the fixtures'
/// and docs' convention), else the spec used last.
fn guess_spec(recording: &Path, last: Option<&Path>) -> String {
    let stem = recording
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let beside = recording.with_file_name(format!("{stem}.spec.json"));
    if beside.is_file() {
        return beside.display().to_string();
    }
    last.map(|p| p.display().to_string()).unwrap_or_default()
}

impl ImportDialog {
    pub fn is_open(&self) -> bool {
        !self.queue.is_empty()
    }

    /// Queue a recording that needs a spec (see `session::needs_spec`).
    pub fn push(&mut self, recording: PathBuf) {
        if self.queue.contains(&recording) {
            return;
        }
        if self.queue.is_empty() {
            self.spec = guess_spec(&recording, self.last_spec.as_deref());
            self.error = None;
        }
        self.queue.push(recording);
    }

    fn next(&mut self) {
        self.queue.remove(0);
        self.error = None;
        if let Some(r) = self.queue.first() {
            self.spec = guess_spec(r, self.last_spec.as_deref());
        }
    }

    fn pick_spec(&mut self) {
        let (tx, rx) = channel();
        self.picking = Some(rx);
        // The portal dialog blocks its thread; keep it off the UI thread.
        std::thread::spawn(move || {
            let picked = rfd::FileDialog::new()
                .add_filter("Import specs", &["json"])
                .pick_file();
            let _ = tx.send(picked);
        });
    }

    /// Draw the dialog; returns the source to load once a spec was accepted.
    pub fn show(&mut self, ctx: &egui::Context) -> Option<Source> {
        if let Some(rx) = &self.picking
            && let Ok(picked) = rx.try_recv()
        {
            self.picking = None;
            if let Some(p) = picked {
                self.spec = p.display().to_string();
                self.error = None;
            }
        }
        let recording = self.queue.first()?.clone();
        let mut accepted = None;
        let mut cancel = false;
        egui::Window::new("Import a recording")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                let name = crate::session::file_name(&recording);
                ui.label(format!("{name} needs an import spec: which topics or columns are sensors, their layouts and the label sets."));
                if self.queue.len() > 1 {
                    ui.label(format!("{} more recordings wait after this one.", self.queue.len() - 1));
                }
                ui.horizontal(|ui| {
                    let label = ui.label("Spec file");
                    let edit = ui
                        .add(
                            egui::TextEdit::singleline(&mut self.spec)
                                .desired_width(320.0)
                                .hint_text("a .spec.json (docs/import.md)"),
                        )
                        .labelled_by(label.id);
                    if edit.changed() {
                        self.error = None;
                    }
                    if ui
                        .add_enabled(self.picking.is_none(), egui::Button::new("Choose…"))
                        .clicked()
                    {
                        self.pick_spec();
                    }
                });
                if let Some(e) = &self.error {
                    ui.colored_label(ui.visuals().error_fg_color, e);
                }
                ui.horizontal(|ui| {
                    if ui.button("Import").clicked() {
                        match self.check_spec() {
                            Ok(spec) => accepted = Some(spec),
                            Err(e) => self.error = Some(e),
                        }
                    }
                    if ui.button("Cancel").clicked() {
                        cancel = true;
                    }
                });
            });
        if let Some(spec) = accepted {
            self.last_spec = Some(spec.clone());
            self.next();
            return Some(Source::Imported { recording, spec });
        }
        if cancel {
            self.next();
        }
        None
    }

    /// The spec must read before the recording is: its errors name the spec and its field.
    fn check_spec(&self) -> Result<PathBuf, String> {
        let text = self.spec.trim();
        if text.is_empty() {
            return Err("Choose the recording's spec file first.".to_string());
        }
        let path = PathBuf::from(text);
        ImportSpec::load(&path).map_err(|e| e.to_string())?;
        Ok(path)
    }
}
