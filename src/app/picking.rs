//! Choosing files: the in-app picker, the system dialog beside it, and what a pick does.

use std::path::PathBuf;
use std::sync::mpsc::channel;

use super::files::{FilePicker, Picked, Purpose};
use super::{WorkbenchApp, models};

impl WorkbenchApp {
    /// Open, save or add what the user picked for `purpose`.
    pub(super) fn picked(&mut self, purpose: Purpose, paths: Vec<PathBuf>, ctx: &egui::Context) {
        if let Some(p) = paths.first() {
            let folder = if p.is_dir() {
                Some(p.as_path())
            } else {
                p.parent()
            };
            self.last_folder = folder.map(std::path::Path::to_path_buf);
        }
        for p in paths {
            match purpose {
                Purpose::Sessions | Purpose::Folder => self.open_path(p, ctx),
                Purpose::OpenProject => self.analyses.open_project(ctx, p),
                Purpose::SaveProject => {
                    let sessions = self.sessions.iter().map(|s| s.source.label()).collect();
                    self.analyses.save_project(ctx, p, sessions);
                }
                Purpose::SaveModel(i) => self.analyses.save_model(ctx, i, p),
                Purpose::LoadModel => self.analyses.load_model(ctx, p),
                Purpose::SaveSelection => match self.selection.session {
                    Some(s) if !self.selection.grasps.is_empty() => {
                        let grasps = self.selection.grasps.clone();
                        if let Some(ls) = self.sessions.get(s) {
                            self.analyses.save_selection(ctx, ls, grasps, p);
                        }
                    }
                    _ => self.analyses.notes.error("no grasps are selected"),
                },
            }
        }
    }

    /// Open the in-app picker for `purpose` on its default location: the folder last used
    /// (for sessions, that of the most recent file), else the working folder.
    pub fn open_picker(&mut self, purpose: Purpose) {
        let recent = self
            .recent
            .first()
            .and_then(|p| p.parent())
            .map(|p| p.to_path_buf());
        let folder = match purpose {
            Purpose::Sessions | Purpose::Folder => recent.or_else(|| self.last_folder.clone()),
            _ => self.last_folder.clone().or(recent),
        }
        .filter(|d| d.is_dir())
        .or_else(|| std::env::current_dir().ok())
        .unwrap_or_else(|| PathBuf::from("."));
        let start = match purpose {
            Purpose::SaveProject => folder.join("project.json"),
            Purpose::SaveModel(i) => match self.analyses.models.list.get(i) {
                Some(m) => folder.join(models::file_name(&m.file)),
                None => folder.join("model.json"),
            },
            Purpose::SaveSelection => {
                let name = self
                    .selection
                    .session
                    .and_then(|s| self.sessions.get(s))
                    .map_or("session".into(), |s| {
                        crate::experiments::result::slug(&s.session.meta.name)
                    });
                folder.join(format!("{name}-selection.json"))
            }
            _ => folder,
        };
        self.picker = Some(FilePicker::new(purpose, start));
    }

    /// The system file dialog for `purpose`, on a thread of its own.
    fn open_dialog(&mut self, purpose: Purpose) {
        let (tx, rx) = channel();
        self.dialog = Some((purpose, rx));
        // The portal dialog blocks its thread; keep it off the UI thread.
        std::thread::spawn(move || {
            let (name, types) = purpose.file_types();
            let dialog = rfd::FileDialog::new();
            let dialog = if types.is_empty() {
                dialog
            } else {
                dialog.add_filter(name, types)
            };
            let picked = match purpose {
                Purpose::Folder => dialog.pick_folder().map(|p| vec![p]),
                Purpose::Sessions => dialog.pick_files(),
                Purpose::OpenProject | Purpose::LoadModel => dialog.pick_file().map(|p| vec![p]),
                Purpose::SaveProject => dialog
                    .set_file_name("project.json")
                    .save_file()
                    .map(|p| vec![p]),
                Purpose::SaveModel(_) | Purpose::SaveSelection => {
                    dialog.save_file().map(|p| vec![p])
                }
            };
            let _ = tx.send(picked.unwrap_or_default());
        });
    }

    /// The in-app picker, when open.
    pub(super) fn picker_ui(&mut self, ctx: &egui::Context) {
        let Some(picker) = &mut self.picker else {
            return;
        };
        let purpose = picker.purpose;
        match picker.show(ctx, &mut self.analyses.notes) {
            Picked::None => {}
            Picked::Cancel => self.picker = None,
            Picked::System => {
                picker.system_gave_nothing = false;
                self.open_dialog(purpose);
            }
            Picked::Paths(paths) => {
                self.picker = None;
                self.picked(purpose, paths, ctx);
            }
        }
    }
}
