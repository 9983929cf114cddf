//! A spec from what the server advertises: its channels listed on a thread of their own,
//! a proposed spec to edit, saved atomically and then used by the form.

use std::sync::mpsc::channel;
use std::time::Duration;

use super::{LiveRoom, path_or_none};
use crate::live::discover;
use crate::session::ImportSpec;

impl LiveRoom {
    fn discover(&mut self, ctx: &egui::Context) {
        let (tx, rx) = channel();
        let url = self.form.url.trim().to_string();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let _ = tx
                .send(discover::discover(&url, Duration::from_secs(3)).map_err(|e| e.to_string()));
            ctx.request_repaint();
        });
        self.discovering = Some(rx);
        self.found_error = None;
    }

    pub(super) fn poll_discovery(&mut self) {
        let Some(rx) = &self.discovering else { return };
        let Ok(answer) = rx.try_recv() else { return };
        self.discovering = None;
        match answer {
            Ok(found) => {
                let (spec, left_out) = discover::propose("live stream", &found);
                self.proposed = serde_json::to_string_pretty(&spec).unwrap_or_default();
                self.left_out = left_out;
                self.found = found;
            }
            Err(e) => self.found_error = Some(e),
        }
    }

    /// Save the edited proposal atomically, once it reads as a spec; the form then uses it.
    fn save_proposal(&mut self) {
        let Some(path) = path_or_none(&self.save_to) else {
            self.saved = Some(Err("give a file to save the spec to".into()));
            return;
        };
        let outcome = ImportSpec::from_str(&self.proposed, &path)
            .map_err(|e| e.to_string())
            .and_then(|_| {
                crate::fsutil::write_atomic(&path, self.proposed.as_bytes())
                    .map_err(|e| format!("{}: {e}", path.display()))
            });
        self.saved = Some(match outcome {
            Ok(()) => {
                self.form.spec = path.display().to_string();
                Ok(format!("saved {}", path.display()))
            }
            Err(e) => Err(e),
        });
    }

    pub(super) fn discovery_ui(&mut self, ui: &mut egui::Ui) {
        ui.label("No spec? List what the server advertises and start from a proposed spec.");
        if ui
            .add_enabled(
                self.discovering.is_none(),
                egui::Button::new("List channels"),
            )
            .clicked()
        {
            self.discover(ui.ctx());
        }
        if self.discovering.is_some() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("listening to the server…");
            });
        }
        if let Some(e) = &self.found_error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        if self.found.is_empty() {
            return;
        }
        ui.label(format!("{} channels advertised:", self.found.len()));
        for f in &self.found {
            ui.small(f.line());
        }
        for l in &self.left_out {
            ui.small(format!("left out: {l}"));
        }
        let l = ui.label("Proposed spec (edit it: units, ranges, label sets):");
        // A long spec scrolls in a box of its own, so Save stays in reach.
        egui::ScrollArea::vertical()
            .id_salt("proposed-spec")
            .max_height(260.0)
            .show(ui, |ui| {
                ui.add(
                    egui::TextEdit::multiline(&mut self.proposed)
                        .code_editor()
                        .desired_rows(10)
                        .desired_width(f32::INFINITY),
                )
                .labelled_by(l.id);
            });
        ui.horizontal(|ui| {
            let l = ui.label("Save as");
            ui.add(egui::TextEdit::singleline(&mut self.save_to).hint_text("robot.spec.json"))
                .labelled_by(l.id);
        });
        if ui.button("Save spec").clicked() {
            self.save_proposal();
        }
        match &self.saved {
            Some(Ok(t)) => {
                ui.label(t);
            }
            Some(Err(e)) => {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            None => {}
        }
    }
}
