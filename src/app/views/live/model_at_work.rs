//! The model at work: the open grasp's running decision and the last grasp's verdict
//! (class distribution over the steps, or novelty), and the latest grasps below.

use egui::{Color32, Sense, Vec2};

use super::LiveRoom;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::live::model::Verdict;

impl LiveRoom {
    pub(super) fn model_ui(&self, ui: &mut egui::Ui) {
        // Under the lock: the verdicts' last steps and charts, not every step of them.
        let Some(view) = self.shown(|s| {
            (
                s.open_verdict.as_ref().map(Shown::of),
                s.last_verdict.as_ref().map(Shown::of),
                s.early_error.clone(),
                s.in_progress,
                s.recent.iter().rev().take(4).cloned().collect::<Vec<_>>(),
            )
        }) else {
            ui.label("No stream.");
            return;
        };
        let (open, last, early_error, in_progress, recent) = view;
        // The latest grasps' lines stay in sight below the chart where it has its minimum.
        let reserve = if recent.is_empty() {
            0.0
        } else {
            (recent.len() as f32 + 1.0) * 15.0 + 12.0
        };
        if let Some(e) = early_error {
            ui.colored_label(ui.visuals().warn_fg_color, format!("model: {e}"));
        }
        match (&open, &last) {
            (Some(v), _) => {
                ui.strong(format!("Grasp in progress: {in_progress} frames"));
                verdict_ui(ui, v, true, reserve);
            }
            (None, Some(v)) => {
                ui.strong("Last grasp");
                verdict_ui(ui, v, false, reserve);
            }
            (None, None) => {
                ui.label(if in_progress > 0 {
                    format!("Grasp in progress: {in_progress} frames")
                } else {
                    "Waiting for a grasp (choose a model file in the form to see it at work)."
                        .into()
                });
            }
        }
        // As many of the latest grasps as the chart leaves room for, the newest first.
        let line = ui.text_style_height(&egui::TextStyle::Small) + ui.spacing().item_spacing.y;
        let fit = ((ui.available_height() - 12.0) / line - 1.0)
            .floor()
            .max(0.0) as usize;
        if fit > 0 && !recent.is_empty() {
            ui.separator();
            ui.small("Latest grasps");
            for line in recent.into_iter().take(fit) {
                // The CLI's arrow is not in the window's font; one line each (a cut line
                // shows whole on hover).
                let line = line.replace('→', "->");
                ui.add(egui::Label::new(egui::RichText::new(line).small()).truncate());
            }
        }
    }
}

/// What the model tile draws of a verdict: the verdict with its latest step only, how many
/// steps it has, and its chart.
struct Shown {
    verdict: Verdict,
    steps: usize,
    figure: Option<crate::figures::Figure>,
}

impl Shown {
    fn of(v: &Verdict) -> Shown {
        Shown {
            verdict: Verdict {
                method: v.method,
                predicted: v.predicted.clone(),
                decision: v.decision,
                classes: v.classes.clone(),
                steps: v.steps.last().cloned().into_iter().collect(),
                settled: v.settled,
                novelty: v.novelty,
                novelty_steps: v.novelty_steps.last().copied().into_iter().collect(),
            },
            steps: v.steps.len(),
            figure: v.figure(5),
        }
    }
}

/// The height the model's chart keeps before class bars and the latest grasps give way.
const CHART_MIN: f32 = 150.0;

/// The chart's height: what is left less the latest grasps' `reserve`, but never less
/// than [`CHART_MIN`] where the tile has that (the grasps' lines then give way).
fn chart_height(ui: &egui::Ui, reserve: f32) -> f32 {
    let avail = ui.available_height();
    (avail - reserve).max(CHART_MIN.min(avail))
}

/// A verdict: the decision, when it settled, the latest step's distribution as bars and
/// every class's probability over the steps.
/// `reserve`: the height to leave below the chart.
fn verdict_ui(ui: &mut egui::Ui, shown: &Shown, open: bool, reserve: f32) {
    let v = &shown.verdict;
    let word = if open { "running decision" } else { "decided" };
    let mut head = format!("{}: {word} {}", v.method.key(), v.predicted);
    if v.decision.is_finite() {
        head += &format!(" ({:.3})", v.decision);
    }
    if let Some(s) = v.settled {
        head += &format!(" · settled at step {} of {}", s + 1, shown.steps);
    }
    if let Some((n, t)) = v.novelty {
        head += &format!(" · novelty {n:.3} (new cluster above {t:.3})");
    }
    ui.label(head);
    if v.steps.is_empty() {
        novelty_ui(ui, shown, open, reserve);
        return;
    }
    let Some(last) = v.steps.last() else { return };
    ui.small(format!("Class distribution at step {}", shown.steps));
    let text = ui.visuals().text_color();
    let accent = ui.visuals().selection.bg_fill;
    let width = ui.available_width().min(420.0);
    let mut order: Vec<usize> = (0..last.len()).collect();
    order.sort_by(|&a, &b| last[b].total_cmp(&last[a]));
    // The chart keeps a readable height: in a short tile, fewer class bars (the chart
    // names every class it draws).
    let bars = match shown.figure {
        Some(_) => ((ui.available_height() - reserve - CHART_MIN - 20.0) / 16.0).floor() as usize,
        None => 5,
    };
    for &k in order.iter().take(bars.clamp(1, 5)) {
        let (rect, _) = ui.allocate_exact_size(Vec2::new(width, 16.0), Sense::hover());
        let p = last[k].clamp(0.0, 1.0) as f32;
        let label_w = 110.0;
        let bar = egui::Rect::from_min_size(
            rect.min + Vec2::new(label_w, 2.0),
            Vec2::new((rect.width() - label_w - 50.0).max(0.0) * p, 12.0),
        );
        let painter = ui.painter_at(rect);
        let chosen = v.classes.get(k) == Some(&v.predicted);
        painter.rect_filled(bar, 2.0, if chosen { accent } else { Color32::GRAY });
        let name = v.classes.get(k).cloned().unwrap_or_default();
        painter.text(
            rect.left_center(),
            egui::Align2::LEFT_CENTER,
            name,
            egui::FontId::proportional(12.0),
            text,
        );
        painter.text(
            rect.right_center(),
            egui::Align2::RIGHT_CENTER,
            format!("{:.3}", last[k]),
            egui::FontId::proportional(12.0),
            text,
        );
    }
    // The top classes' probability at every step: how the decision formed (a figure of
    // the figure model, so its legend and axes follow the audited layout rules).
    let id = if open {
        "live-steps-open"
    } else {
        "live-steps-last"
    };
    chart_ui(ui, shown, id, reserve);
}

/// The verdict's chart, if it has one, in what the tile leaves less `reserve`.
fn chart_ui(ui: &mut egui::Ui, shown: &Shown, id: &str, reserve: f32) {
    if let Some(figure) = &shown.figure {
        let height = chart_height(ui, reserve);
        figure_view::show(ui, id, figure, height, FigureSelection::None);
    }
}

/// DU/GU: the cluster of the grasp so far and its novelty at every step, against the
/// threshold (the chart's reference line).
fn novelty_ui(ui: &mut egui::Ui, shown: &Shown, open: bool, reserve: f32) {
    let Some(s) = shown.verdict.novelty_steps.last() else {
        return;
    };
    let cluster = crate::models::clustering::cluster_name(s.cluster);
    ui.small(format!(
        "At step {}: novelty {:.3} of the grasp so far against {cluster}",
        s.step + 1,
        s.novelty
    ));
    let id = if open {
        "live-novelty-open"
    } else {
        "live-novelty-last"
    };
    chart_ui(ui, shown, id, reserve);
}
