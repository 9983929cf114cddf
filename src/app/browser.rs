//! The session browser: open sessions, their grasps with object, label and length,
//! filtered by label, object and the selection; the selected grasps are marked.

use egui::{ComboBox, RichText, ScrollArea};

use super::loader::LoadedSession;
use super::selection::Selection;

/// Browser state: which session is active and the filters on its grasps.
#[derive(Default, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Browser {
    pub active: usize,
    /// Class index of the first label set to keep (None: all).
    pub label: Option<usize>,
    /// Object name to keep (None: all).
    pub object: Option<String>,
    /// Keep only the selected grasps.
    #[serde(default)]
    pub only_selection: bool,
}

/// What the user did in the browser this frame.
pub enum BrowserAction {
    None,
    /// Focus this grasp of the active session.
    Select(usize),
    /// Focus and replay it (double-click).
    Replay(usize),
    Close(usize),
}

impl Browser {
    /// Grasps of `s` (session `index`) that pass the filters.
    pub fn visible(&self, s: &LoadedSession, index: usize, selection: &Selection) -> Vec<usize> {
        let session = &s.session;
        let only = self.only_selection && selection.session == Some(index);
        (0..session.grasps.len())
            .filter(|&g| {
                let grasp = &session.grasps[g];
                self.label.is_none_or(|l| grasp.labels.first() == Some(&l))
                    && self.object.as_ref().is_none_or(|o| &grasp.object == o)
                    && (!only || selection.grasps.contains(&g))
            })
            .collect()
    }

    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        sessions: &[LoadedSession],
        selection: &Selection,
    ) -> BrowserAction {
        let mut action = BrowserAction::None;
        ui.heading("Sessions");
        if sessions.is_empty() {
            ui.label("No session open. Use File > Open, or drop a file here.");
            return action;
        }
        // The active session persists by index: while the sessions of the last run are
        // still loading it may point past those loaded so far (the app clamps it once all
        // have loaded).
        for (i, s) in sessions.iter().enumerate() {
            ui.horizontal(|ui| {
                let name = &s.session.meta.name;
                if ui
                    .selectable_label(self.active == i, name)
                    .on_hover_text(s.source.label())
                    .clicked()
                    && self.active != i
                {
                    self.active = i;
                    self.label = None;
                    self.object = None;
                }
                if ui
                    .small_button("Close")
                    .on_hover_text("Close this session")
                    .clicked()
                {
                    action = BrowserAction::Close(i);
                }
            });
        }
        ui.separator();
        let active = self.active.min(sessions.len() - 1);
        let s = &sessions[active];
        let session = &s.session;
        if let Some(set) = session.label_sets.first() {
            let text = self
                .label
                .and_then(|l| set.classes.get(l).cloned())
                .unwrap_or_else(|| "all labels".to_string());
            ComboBox::from_label(format!("Filter by label ({})", set.name))
                .selected_text(text)
                .show_ui(ui, |ui| {
                    ui.selectable_value(&mut self.label, None, "all labels");
                    for (c, name) in set.classes.iter().enumerate() {
                        ui.selectable_value(&mut self.label, Some(c), name);
                    }
                });
        }
        let objects = session.objects();
        ComboBox::from_label("Filter by object")
            .selected_text(self.object.clone().unwrap_or_else(|| "all objects".into()))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut self.object, None, "all objects");
                for o in objects {
                    let label = o.clone();
                    ui.selectable_value(&mut self.object, Some(o), label);
                }
            });
        let selected_here = selection.session == Some(active) && !selection.grasps.is_empty();
        if selected_here {
            ui.checkbox(
                &mut self.only_selection,
                format!("Only the {} selected", selection.grasps.len()),
            )
            .on_hover_text(selection.origin.clone());
        }
        let visible = self.visible(s, active, selection);
        ui.horizontal(|ui| {
            ui.label(format!(
                "{} of {} grasps",
                visible.len(),
                session.grasps.len()
            ));
            ui.small("(double-click or Enter replays)");
        });
        ui.separator();
        let row_height = ui.text_style_height(&egui::TextStyle::Body) + 4.0;
        ScrollArea::vertical().auto_shrink(false).show_rows(
            ui,
            row_height,
            visible.len(),
            |ui, rows| {
                for &g in &visible[rows] {
                    let grasp = &session.grasps[g];
                    let label = grasp
                        .labels
                        .first()
                        .and_then(|&l| {
                            session
                                .label_sets
                                .first()
                                .and_then(|set| set.classes.get(l))
                        })
                        .map(String::as_str)
                        .unwrap_or("");
                    let trial = grasp.trial.map(|t| format!(" #{t}")).unwrap_or_default();
                    let text = format!(
                        "{}{trial} · {label} · {} frames",
                        grasp.object,
                        grasp.frames.len()
                    );
                    let focused = selection.focus == Some((active, g));
                    let text = if selection.contains(active, g) {
                        RichText::new(format!("» {text}")).strong()
                    } else {
                        RichText::new(text)
                    };
                    let row = ui.selectable_label(focused, text);
                    if row.double_clicked() {
                        action = BrowserAction::Replay(g);
                    } else if row.clicked() {
                        action = BrowserAction::Select(g);
                    }
                }
            },
        );
        action
    }
}
