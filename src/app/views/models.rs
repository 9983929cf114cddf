//! The Models list in a room's form panel (the models of the room's methods, those trained on
//! the active session first) and the "Evaluate on session…" window. The list speaks of a
//! model only through its provenance (method, size, score, training session, when), so
//! every method's model shows the same way.

use egui::RichText;

use super::{Cx, number};
use crate::app::models::{EvaluateForm, KeptModel, Readable, trained_when};
use crate::app::selection::Command;
use crate::catalogue::MethodId;
use crate::models::{self, Calibration};

/// The collapsible Models section of a form panel: the models whose method `shows`.
pub fn section(ui: &mut egui::Ui, cx: &mut Cx, shows: impl Fn(MethodId) -> bool) {
    let active = cx
        .session()
        .map(|s| s.session.meta.name.clone())
        .unwrap_or_default();
    let of_task: Vec<usize> = (0..cx.analyses.models.list.len())
        .filter(|&i| shows(cx.analyses.models.list[i].file.provenance.method))
        .collect();
    let (mine, others): (Vec<usize>, Vec<usize>) = of_task
        .iter()
        .partition(|&&i| cx.analyses.models.list[i].file.provenance.session.name == active);
    ui.separator();
    egui::CollapsingHeader::new(format!("Models ({})", of_task.len()))
        .id_salt("models")
        .default_open(true)
        .show(ui, |ui| {
            if of_task.is_empty() {
                ui.small("Each run keeps its model here, to save or to test on another session.");
            } else if mine.is_empty() {
                ui.small(format!("None trained on «{active}»."));
            }
            for &i in &mine {
                row(ui, cx, i);
            }
            if !others.is_empty() {
                egui::CollapsingHeader::new(format!(
                    "Trained on other sessions ({})",
                    others.len()
                ))
                .id_salt("models-others")
                .default_open(mine.is_empty())
                .show(ui, |ui| {
                    for &i in &others {
                        row(ui, cx, i);
                    }
                });
            }
            ui.add_space(4.0);
            if ui
                .small_button("Load model…")
                .on_hover_text("Add a model file (tactile-workbench-model) to the list")
                .clicked()
            {
                cx.commands.push(Command::LoadModel);
            }
        });
}

/// One model: what it is and how good, on what and when it trained, and what to do with it.
fn row(ui: &mut egui::Ui, cx: &mut Cx, i: usize) {
    let KeptModel { file, .. } = &cx.analyses.models.list[i];
    let p = &file.provenance;
    let size: Vec<String> = p.size.iter().map(|(k, v)| format!("{k} {v}")).collect();
    let title = if size.is_empty() {
        p.method.title().to_string()
    } else {
        format!("{} · {}", p.method.title(), size.join(", "))
    };
    let score = p
        .selection
        .first()
        .map(|s| format!("{} {} ({})", s.name, number(s.value), s.protocol));
    let scores_hover = p
        .selection
        .iter()
        .map(|s| format!("{} {} ({})", s.name, number(s.value), s.protocol))
        .collect::<Vec<_>>()
        .join("\n");
    ui.add_space(2.0);
    ui.label(RichText::new(title).strong());
    let mut line = format!(
        "trained {} on {} ({} grasps)",
        trained_when(file),
        p.session.name,
        p.session.grasps,
    );
    if let Some(s) = score {
        line = format!("{s}; {line}");
    }
    ui.small(line).on_hover_text(format!(
        "Selected with:\n{scores_hover}\nSize: {}\nFeatures: {}\nLabel set {} ({})",
        p.size_reason.text(),
        p.features,
        p.label_set,
        p.classes.join(", ")
    ));
    let mut remove = false;
    ui.horizontal_wrapped(|ui| {
        if ui
            .small_button("Evaluate on session…")
            .on_hover_text("Test it on another open session (held out)")
            .clicked()
        {
            let trained = &cx.analyses.models.list[i].file.provenance.session.name;
            // The active session, unless the model trained on it: then another open one.
            let other = |k: &usize| &cx.sessions[*k].session.meta.name != trained;
            let session = Some(cx.active)
                .filter(|k| *k < cx.sessions.len() && other(k))
                .or_else(|| (0..cx.sessions.len()).find(other))
                .unwrap_or(cx.active);
            cx.analyses.models.evaluate = Some(EvaluateForm::new(i, session));
        }
        if ui.small_button("Save model…").clicked() {
            cx.commands.push(Command::SaveModel(i));
        }
        remove = ui
            .small_button("Remove")
            .on_hover_text("Off the list and out of the data folder (saved copies stay)")
            .clicked();
    });
    if remove {
        cx.analyses.remove_model(i);
    }
}

/// The "Evaluate on session…" window, while open: model, open session, calibration.
pub fn evaluate_window(ctx: &egui::Context, cx: &mut Cx) {
    let Some(mut form) = cx.analyses.models.evaluate.clone() else {
        return;
    };
    if cx.analyses.models.list.is_empty() || cx.sessions.is_empty() {
        cx.analyses.models.evaluate = None;
        return;
    }
    let models = &cx.analyses.models.list;
    form.model = form.model.min(models.len() - 1);
    form.session = form.session.min(cx.sessions.len() - 1);
    let names: Vec<String> = (cx.sessions.iter())
        .map(|s| s.session.meta.name.clone())
        .collect();
    if form
        .readable
        .as_ref()
        .is_none_or(|r| r.model != form.model || r.sessions != names)
    {
        let file = &models[form.model].file;
        let verdicts = (cx.sessions.iter())
            .map(|s| models::check_readable(file, &s.session).map_err(|e| e.to_string()))
            .collect();
        form.readable = Some(Readable {
            model: form.model,
            sessions: names,
            verdicts,
        });
    }
    let verdicts = form.readable.as_ref().map(|r| r.verdicts.clone());
    let verdicts = verdicts.unwrap_or_default();
    let fits = |k: usize| verdicts.get(k).is_some_and(Result::is_ok);
    let trained = &models[form.model].file.provenance.session.name;
    if !fits(form.session) {
        // The first session the model can read, one it did not train on if there is one.
        let other = |k: &usize| fits(*k) && &cx.sessions[*k].session.meta.name != trained;
        form.session = (0..cx.sessions.len())
            .find(other)
            .or_else(|| (0..cx.sessions.len()).find(|k| fits(*k)))
            .unwrap_or(form.session);
    }
    let any = (0..cx.sessions.len()).any(fits);
    let mut open = true;
    let mut go = false;
    let mut cancel = false;
    egui::Window::new("Evaluate on session")
        .pivot(egui::Align2::CENTER_TOP)
        .default_pos(ctx.content_rect().center_top() + egui::vec2(0.0, 120.0))
        .open(&mut open)
        .collapsible(false)
        .resizable(false)
        .default_width(420.0)
        .show(ctx, |ui| {
            egui::Grid::new("evaluate-form")
                .num_columns(2)
                .show(ui, |ui| {
                    let caption = ui.label("Model");
                    egui::ComboBox::from_id_salt("evaluate-model")
                        .width(300.0)
                        .selected_text(models[form.model].file.provenance.summary())
                        .show_ui(ui, |ui| {
                            for (k, m) in models.iter().enumerate() {
                                ui.selectable_value(
                                    &mut form.model,
                                    k,
                                    m.file.provenance.summary(),
                                );
                            }
                        })
                        .response
                        .labelled_by(caption.id);
                    ui.end_row();
                    let name = |k: usize| {
                        let n = &cx.sessions[k].session.meta.name;
                        if n == trained {
                            format!("{n} (its training session)")
                        } else {
                            n.clone()
                        }
                    };
                    let caption = ui.label("Session");
                    egui::ComboBox::from_id_salt("evaluate-session")
                        .width(300.0)
                        .selected_text(match any {
                            true => name(form.session),
                            false => "(none this model can read)".into(),
                        })
                        .show_ui(ui, |ui| {
                            for k in (0..cx.sessions.len()).filter(|k| fits(*k)) {
                                ui.selectable_value(&mut form.session, k, name(k));
                            }
                        })
                        .response
                        .labelled_by(caption.id);
                    ui.end_row();
                    let caption = ui.label("Calibration");
                    let first = Calibration::First { grasps: form.first };
                    ui.horizontal(|ui| {
                        egui::ComboBox::from_id_salt("evaluate-calibration")
                            .selected_text(calibration_choice(form.calibration))
                            .show_ui(ui, |ui| {
                                for c in [Calibration::None, Calibration::Session, first] {
                                    ui.selectable_value(
                                        &mut form.calibration,
                                        c,
                                        calibration_choice(c),
                                    );
                                }
                            })
                            .response
                            .labelled_by(caption.id);
                        if let Calibration::First { .. } = form.calibration {
                            let n = cx.sessions[form.session].session.grasps.len().max(1);
                            ui.add(
                                egui::DragValue::new(&mut form.first)
                                    .range(1..=n)
                                    .prefix("K "),
                            );
                            form.calibration = Calibration::First { grasps: form.first };
                        }
                    });
                    ui.end_row();
                });
            ui.small(format!("Calibration: {}.", form.calibration.describe()));
            for (k, v) in verdicts.iter().enumerate() {
                if let Err(why) = v {
                    let name = &cx.sessions[k].session.meta.name;
                    ui.small(format!("Not listed: {name}: {why}."));
                }
            }
            ui.horizontal(|ui| {
                go = ui.add_enabled(any, egui::Button::new("Evaluate")).clicked();
                cancel = ui.button("Cancel").clicked();
            });
        });
    if go {
        let session = &cx.sessions[form.session];
        let ctx = cx.ctx.clone();
        cx.analyses
            .evaluate_model(&ctx, form.model, session, form.calibration);
    }
    cx.analyses.models.evaluate = (open && !go && !cancel).then_some(form);
}

/// A calibration as the window offers it.
fn calibration_choice(c: Calibration) -> &'static str {
    match c {
        Calibration::None => "none (the training session's statistics)",
        Calibration::Session => "session (the new session's own)",
        Calibration::First { .. } => "first K grasps",
    }
}
