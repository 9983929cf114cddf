//! Speed against accuracy: every trained model's training time, or its prediction time per
//! step or sample (log axis), against its headline score, with the Pareto front. Clicking a
//! model's point (or its button) opens its view on that result.

use super::tiles::Pane;
use super::{Cx, Room};
use crate::app::View;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::selection::Command;
use crate::experiments::report::{self, TimeAxis, date_text};
use crate::figures;

#[derive(Default)]
pub struct SpeedRoom {
    /// The time on the chart's x axis.
    pub time_axis: TimeAxis,
}

impl Room for SpeedRoom {
    fn view(&self) -> View {
        View::SpeedAccuracy
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![vec![Pane::SpeedChart], vec![Pane::Models]]
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, _cx: &mut Cx) {
        ui.heading("Speed against accuracy");
        ui.label("Time axis:");
        ui.selectable_value(&mut self.time_axis, TimeAxis::Training, "training time");
        ui.selectable_value(
            &mut self.time_axis,
            TimeAxis::Prediction,
            "prediction time per step or sample",
        );
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, pane: &Pane, cx: &mut Cx) -> bool {
        match pane {
            Pane::SpeedChart => self.chart(ui, cx),
            Pane::Models => models(ui, cx),
            _ => return false,
        }
        true
    }
}

impl SpeedRoom {
    fn chart(&self, ui: &mut egui::Ui, cx: &mut Cx) {
        let axis = self.time_axis;
        let results = &cx.analyses.results;
        let Some(fig) = report::speed_accuracy(results, axis) else {
            if axis == TimeAxis::Prediction && !results.is_empty() {
                ui.label("None of the results times its predictions (the OIESGP learners do).");
            } else {
                ui.label("Train a model in any analysis view: every result appears here.");
            }
            return;
        };
        let file = match axis {
            TimeAxis::Training => "speed-against-accuracy",
            TimeAxis::Prediction => "prediction-speed-against-accuracy",
        };
        if ui
            .small_button("Export")
            .on_hover_text("SVG, PNG and CSV into the export folder")
            .clicked()
        {
            cx.analyses.export.write(&fig, file, &mut cx.analyses.notes);
        }
        let height = (ui.available_height() - 40.0).max(160.0);
        let act = figure_view::show(ui, "speed-accuracy", &fig, height, FigureSelection::None);
        // Clicking a model's point opens its view, like its button.
        let sources = report::speed_accuracy_sources(&cx.analyses.results, axis);
        if let Some((series, k)) = act.clicked_point
            && let figures::FigureKind::Chart(c) = &fig.kind
            && c.series
                .get(series)
                .is_some_and(|s| s.name == "trained models")
            && let Some(&i) = sources.get(k)
        {
            cx.commands.push(Command::OpenResult(i));
        }
    }
}

/// Every result with a headline score, as a button that opens its view.
fn models(ui: &mut egui::Ui, cx: &mut Cx) {
    ui.label("Open a model's views:");
    egui::ScrollArea::vertical().show(ui, |ui| {
        for (i, r) in cx.analyses.results.iter().enumerate() {
            if r.headline.is_some()
                && ui
                    .button(format!("{} · {}", r.label, r.session))
                    .on_hover_text(date_text(r.created))
                    .clicked()
            {
                cx.commands.push(Command::OpenResult(i));
            }
        }
    });
}
