//! Opening and saving without a system dialog. rfd's portal backend returns nothing when the
//! machine has no desktop portal and no zenity, which cannot be told from a cancel; so every
//! open and save goes through this in-app picker (a path field on the default location and a
//! listing of its folder), with the system dialog offered beside it.

use std::path::{Path, PathBuf};

use super::notify::Notifications;

/// What the picker is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    Sessions,
    Folder,
    OpenProject,
    SaveProject,
    /// Model `0` of the Models list.
    SaveModel(usize),
    LoadModel,
    /// The selected grasps as a session.
    SaveSelection,
}

impl Purpose {
    pub fn title(self) -> &'static str {
        match self {
            Purpose::Sessions => "Open sessions",
            Purpose::Folder => "Open folder",
            Purpose::OpenProject => "Open project",
            Purpose::SaveProject => "Save project",
            Purpose::SaveModel(_) => "Save model",
            Purpose::LoadModel => "Load model",
            Purpose::SaveSelection => "Save selection as session",
        }
    }

    /// A save (else an open).
    pub fn saves(self) -> bool {
        matches!(
            self,
            Purpose::SaveProject | Purpose::SaveModel(_) | Purpose::SaveSelection
        )
    }

    /// The files it lists, by name and extensions (folders are always listed; a folder
    /// pick lists nothing else). The system dialog filters by the same.
    pub fn file_types(self) -> (&'static str, &'static [&'static str]) {
        match self {
            Purpose::Sessions => (
                "Sessions, datasets and recordings",
                &["json", "csv", "mcap"],
            ),
            Purpose::Folder => ("Folders", &[]),
            Purpose::OpenProject | Purpose::SaveProject => ("Projects", &["json"]),
            Purpose::SaveModel(_) | Purpose::LoadModel => ("Models", &["json"]),
            Purpose::SaveSelection => ("Sessions", &["json"]),
        }
    }

    /// Whether a file named `name` is of the purpose's types.
    fn lists(self, name: &str) -> bool {
        let ext = Path::new(name).extension().and_then(|e| e.to_str());
        let (_, types) = self.file_types();
        ext.is_some_and(|e| types.iter().any(|t| e.eq_ignore_ascii_case(t)))
    }

    fn action(self) -> &'static str {
        if self.saves() { "Save" } else { "Open" }
    }

    /// The file a save names when the path field holds only a folder.
    fn save_name(self) -> &'static str {
        match self {
            Purpose::SaveModel(_) => "model.json",
            Purpose::SaveSelection => "selection.json",
            _ => "project.json",
        }
    }
}

/// One line of the folder listing.
struct Entry {
    name: String,
    dir: bool,
}

/// The in-app picker: a path field, its folder's listing, and the buttons.
pub struct FilePicker {
    pub purpose: Purpose,
    /// The path as typed (the accessible label of its field is "Path").
    pub path: String,
    /// The folder listed and its entries (or why it cannot be read).
    listing: Option<(PathBuf, Result<Vec<Entry>, String>)>,
    /// The system dialog was tried and gave nothing back.
    pub system_gave_nothing: bool,
    /// List every file, not only those of the purpose's types.
    pub all_files: bool,
}

/// What the user did in the picker this frame.
pub enum Picked {
    None,
    /// These paths, for the picker's purpose.
    Paths(Vec<PathBuf>),
    /// Try the system dialog (the picker stays open in case it gives nothing back).
    System,
    Cancel,
}

impl FilePicker {
    /// A picker for `purpose` starting at `start` (a folder, or a file to save to).
    pub fn new(purpose: Purpose, start: PathBuf) -> Self {
        FilePicker {
            purpose,
            path: start.display().to_string(),
            listing: None,
            system_gave_nothing: false,
            all_files: false,
        }
    }

    /// The folder the path field points into: the path itself when it is a folder, else its
    /// parent.
    fn folder(&self) -> PathBuf {
        let p = PathBuf::from(&self.path);
        if p.is_dir() {
            p
        } else {
            match p.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            }
        }
    }

    fn listing(&mut self) -> &Result<Vec<Entry>, String> {
        let folder = self.folder();
        if self.listing.as_ref().is_none_or(|(f, _)| *f != folder) {
            let read = list(&folder);
            self.listing = Some((folder, read));
        }
        &self.listing.as_ref().expect("set above").1
    }

    /// Check the typed path for the purpose: the paths to open or save, or why not.
    pub fn check(&self) -> Result<PathBuf, String> {
        let p = PathBuf::from(self.path.trim());
        if p.as_os_str().is_empty() {
            return Err("type a path first".into());
        }
        match self.purpose {
            purpose if purpose.saves() => {
                let p = if p.is_dir() {
                    p.join(purpose.save_name())
                } else {
                    p
                };
                let parent = p.parent().filter(|d| !d.as_os_str().is_empty());
                match parent {
                    Some(d) if !d.is_dir() => Err(format!(
                        "cannot save to {}: no folder {}",
                        p.display(),
                        d.display()
                    )),
                    _ => Ok(p),
                }
            }
            Purpose::Folder if !p.is_dir() => Err(format!("{} is not a folder", p.display())),
            Purpose::OpenProject | Purpose::LoadModel if !p.is_file() => {
                Err(format!("cannot open {}: no such file", p.display()))
            }
            Purpose::Sessions if !p.exists() => {
                Err(format!("cannot open {}: no such file", p.display()))
            }
            _ => Ok(p),
        }
    }

    /// Draw the picker as a window. Failures (a path that cannot be used) are toasts.
    pub fn show(&mut self, ctx: &egui::Context, notes: &mut Notifications) -> Picked {
        let mut picked = Picked::None;
        let mut open = true;
        egui::Window::new(self.purpose.title())
            .open(&mut open)
            .collapsible(false)
            .resizable(true)
            .default_width(460.0)
            .max_width((ctx.content_rect().width() - 40.0).max(240.0))
            .show(ctx, |ui| {
                let mut confirm = false;
                ui.horizontal(|ui| {
                    let caption = ui.label("Path");
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.path)
                            .desired_width(ui.available_width()),
                    );
                    let field = field.labelled_by(caption.id);
                    confirm |= field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                });
                ui.horizontal(|ui| {
                    confirm |= ui.button(self.purpose.action()).clicked();
                    if ui.button("Up").on_hover_text("The parent folder").clicked() {
                        let up = self.folder().parent().map(Path::to_path_buf);
                        if let Some(up) = up.filter(|u| !u.as_os_str().is_empty()) {
                            self.path = up.display().to_string();
                        }
                    }
                    if ui
                        .button("System dialog…")
                        .on_hover_text("The desktop's own file dialog, where there is one")
                        .clicked()
                    {
                        picked = Picked::System;
                    }
                    if ui.button("Cancel").clicked() {
                        picked = Picked::Cancel;
                    }
                });
                if self.system_gave_nothing {
                    ui.small(
                        "The system dialog gave nothing back (cancelled, or no dialog on this \
                         machine): type the path above or pick it below.",
                    );
                }
                ui.separator();
                let folder = self.folder();
                ui.horizontal_wrapped(|ui| {
                    ui.small(format!("In {}:", folder.display()));
                    let (name, types) = self.purpose.file_types();
                    if !types.is_empty() {
                        let types: Vec<String> = types.iter().map(|t| format!(".{t}")).collect();
                        ui.checkbox(&mut self.all_files, "All files")
                            .on_hover_text(format!(
                                "Else only {} ({}) and folders",
                                name.to_lowercase(),
                                types.join(", ")
                            ));
                    }
                });
                let (purpose, all_files) = (self.purpose, self.all_files);
                let mut go: Option<PathBuf> = None;
                egui::ScrollArea::vertical()
                    .max_height(260.0)
                    .auto_shrink([false, true])
                    .show(ui, |ui| match self.listing() {
                        Err(e) => {
                            ui.colored_label(ui.visuals().error_fg_color, e);
                        }
                        Ok(entries) if entries.is_empty() => {
                            ui.small("(empty folder)");
                        }
                        Ok(entries) => {
                            let shown = (entries.iter())
                                .filter(|e| e.dir || all_files || purpose.lists(&e.name));
                            for e in shown {
                                let text = if e.dir {
                                    format!("{}/", e.name)
                                } else {
                                    e.name.clone()
                                };
                                let r = ui.selectable_label(false, text);
                                if r.clicked() {
                                    go = Some(folder.join(&e.name));
                                }
                                if r.double_clicked() && !e.dir {
                                    confirm = true;
                                }
                            }
                        }
                    });
                if let Some(p) = go {
                    // A file of the folder for a save keeps its name; a folder is entered.
                    self.path = p.display().to_string();
                }
                if confirm {
                    match self.check() {
                        Ok(p) => picked = Picked::Paths(vec![p]),
                        Err(e) => notes.error(e),
                    }
                }
            });
        if !open {
            picked = Picked::Cancel;
        }
        picked
    }
}

/// The folders then the files of `folder`, by name, hidden ones left out.
fn list(folder: &Path) -> Result<Vec<Entry>, String> {
    let read = std::fs::read_dir(folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    let mut entries: Vec<Entry> = read
        .filter_map(Result::ok)
        .filter_map(|d| {
            let name = d.file_name().to_string_lossy().into_owned();
            (!name.starts_with('.')).then(|| Entry {
                dir: d.path().is_dir(),
                name,
            })
        })
        .collect();
    entries.sort_by(|a, b| b.dir.cmp(&a.dir).then_with(|| a.name.cmp(&b.name)));
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_purpose_lists_its_own_file_types() {
        assert!(Purpose::Sessions.lists("run.MCAP") && Purpose::Sessions.lists("bts3.csv"));
        assert!(!Purpose::Sessions.lists("notes.txt") && !Purpose::Sessions.lists("csv"));
        assert!(Purpose::LoadModel.lists("ds.json") && !Purpose::LoadModel.lists("a.csv"));
        assert!(!Purpose::Folder.lists("a.json"));
    }

    #[test]
    fn a_save_into_a_folder_names_the_project_file_and_a_missing_folder_is_an_error() {
        let dir = std::env::temp_dir().join(format!("tw-picker-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let picker = FilePicker::new(Purpose::SaveProject, dir.clone());
        assert_eq!(picker.check(), Ok(dir.join("project.json")));
        let missing = FilePicker::new(Purpose::SaveProject, dir.join("nope/p.json"));
        assert!(missing.check().unwrap_err().contains("no folder"));
        let open = FilePicker::new(Purpose::OpenProject, dir.join("absent.json"));
        assert!(open.check().unwrap_err().contains("no such file"));
        let listed = list(&dir).unwrap();
        assert!(listed.is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
