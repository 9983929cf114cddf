//! The card above a room's tiles: the result shown (and the others to choose from), its
//! headline numbers, and the line that says what is selected.

use egui::RichText;

use super::{Cx, number};
use crate::app::selection::Command;
use crate::experiments::result::{AnalysisResult, date_text};

/// The card above a room's tiles: which result, its headline numbers (at most six), the
/// selection, and the layout's reset.
pub fn card(ui: &mut egui::Ui, cx: &mut Cx, i: usize, reset: &mut bool) {
    let kind = cx.analyses.results[i].kind;
    let session = cx.analyses.results[i].session.clone();
    let mine = cx.analyses.of_session(kind, &session);
    ui.horizontal_wrapped(|ui| {
        let r = &cx.analyses.results[i];
        let mut chosen = i;
        // A long label (a held-out result's) is cut to the card's width rather than
        // wrapped down it.
        let caption = ui.label("Result");
        // What is left of the row (a wrapping row's `available_width` is a whole row's).
        let rest = ui.max_rect().right() - ui.cursor().min.x;
        let width = (rest - 8.0).clamp(120.0, 520.0);
        ui.scope(|ui| {
            ui.set_max_width(width);
            egui::ComboBox::from_id_salt(("result", kind))
                .truncate()
                .selected_text(format!("{} ({})", r.label, date_text(r.created)))
                .show_ui(ui, |ui| {
                    for &k in &mine {
                        let x = &cx.analyses.results[k];
                        ui.selectable_value(
                            &mut chosen,
                            k,
                            format!("{} ({})", x.label, date_text(x.created)),
                        );
                    }
                })
                .response
                .labelled_by(caption.id)
                .on_hover_text(&r.label);
        });
        if chosen != i {
            cx.analyses.shown.insert(kind, chosen);
        }
        ui.separator();
        let r = &cx.analyses.results[i];
        for (name, v) in headline(r) {
            ui.label(format!("{name}:"));
            ui.label(RichText::new(number(v)).strong());
        }
        ui.separator();
        let r = &cx.analyses.results[i];
        let trained = cx.analyses.models.list.iter().enumerate().filter(|(_, m)| {
            m.result
                .as_ref()
                .is_some_and(|(c, l)| *c == r.created && *l == r.label)
        });
        for (k, m) in trained {
            let text = format!("Save {} model…", m.file.provenance.method.title());
            if ui
                .button(text)
                .on_hover_text("The model this result trained, as a model file")
                .clicked()
            {
                cx.commands.push(Command::SaveModel(k));
            }
        }
        if ui
            .button("Reset layout")
            .on_hover_text("Back to the default tiles for this result")
            .clicked()
        {
            *reset = true;
        }
    });
    if let Some(h) = &cx.analyses.results[i].held_out {
        ui.label(RichText::new(format!("Held out: {}", h.text())).strong());
    }
    selection_line(ui, cx);
}

/// The selection in one line, with Clear.
pub fn selection_line(ui: &mut egui::Ui, cx: &mut Cx) {
    let sel = cx.selection;
    if sel.grasps.is_empty() {
        return;
    }
    ui.horizontal_wrapped(|ui| {
        ui.label(
            RichText::new(format!(
                "Selected: {} grasp{}",
                sel.grasps.len(),
                if sel.grasps.len() == 1 { "" } else { "s" }
            ))
            .strong(),
        );
        if !sel.origin.is_empty() {
            ui.label(format!("({})", sel.origin));
        }
        if ui.small_button("Clear selection").clicked() {
            cx.commands.push(Command::ClearSelection);
        }
        if ui
            .small_button("Save selection as session…")
            .on_hover_text("These grasps as a session file of their own (a test set)")
            .clicked()
        {
            cx.commands.push(Command::SaveSelection);
        }
    });
}

/// At most six numbers that sum a result up: its headline first, then its first scores
/// (a learner's own, not those of the methods it is compared with), then the training time.
pub fn headline(r: &AnalysisResult) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    if let Some((n, v)) = &r.headline {
        out.push((n.clone(), *v));
    }
    // The card of a learner's clustering result (DU, GU) does not show the numbers of the
    // baselines it is compared with as its own.
    let learner = r
        .methods
        .iter()
        .any(|m| m.task() == crate::catalogue::Task::Clustering && m.uses_features());
    let own = |n: &str| {
        !learner
            || !crate::cluster::BASELINE_NAMES
                .iter()
                .any(|m| n.starts_with(m))
    };
    for (n, v) in &r.scores {
        if out.len() >= 5 {
            break;
        }
        if own(n) && !out.iter().any(|(m, _)| m == n) {
            out.push((n.clone(), *v));
        }
    }
    // A held-out result trained nothing: its model's training is in its provenance.
    if r.held_out.is_none() {
        out.push(("training time (s)".into(), r.train_seconds));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalogue::MethodId;

    #[test]
    fn a_learners_card_shows_its_own_numbers_not_its_baselines() {
        let mut du = crate::experiments::result::tests::result();
        du.methods = vec![MethodId::Du];
        du.headline = None;
        du.scores = vec![
            ("sequential k-means purity at 10".into(), 0.7),
            ("SOM purity at 10".into(), 0.8),
            ("DU purity at 10".into(), 0.9),
        ];
        let names = |r: &AnalysisResult| -> Vec<String> {
            headline(r).into_iter().map(|(n, _)| n).collect()
        };
        assert_eq!(names(&du), ["DU purity at 10", "training time (s)"]);
        // The baselines' own result shows them.
        let mut baselines = du.clone();
        baselines.methods = vec![MethodId::KMeans, MethodId::Som];
        assert_eq!(names(&baselines).len(), 4);
    }
}
