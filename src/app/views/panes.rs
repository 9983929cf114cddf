//! The panes every room shares: a result's figure (drawn through the one figure model that
//! export uses), a pinned figure of another result, the detail selected through a figure,
//! the table of numbers and the replay.

use egui::RichText;
use egui_tiles::TileId;

use super::pane::{Pane, TileRequest};
use super::{Cx, Room, number};
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::heatmap;
use crate::app::replay::ReplayAction;
use crate::app::selection::Command;
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::{AnalysisKind, AnalysisResult, date_text};
use crate::figures::{self, ColorMap, Figure, FigureKind};

/// The file name a figure of result `r` exports under.
pub fn pane_ui(
    ui: &mut egui::Ui,
    pane: &Pane,
    tile: TileId,
    room: &mut dyn Room,
    cx: &mut Cx,
    requests: &mut Vec<TileRequest>,
) {
    match pane {
        Pane::Figure(name) => match room.kind().and_then(|k| cx.shown(k)) {
            Some(i) => figure_pane(ui, cx, i, *name, Some((tile, requests))),
            None => {
                ui.label("No result yet.");
            }
        },
        Pane::Pinned {
            figure,
            created,
            label,
        } => {
            let found = cx
                .analyses
                .results
                .iter()
                .position(|r| r.created == *created && &r.label == label);
            match found {
                Some(i) => {
                    ui.small(format!(
                        "pinned: {label} · {} ({})",
                        cx.analyses.results[i].session,
                        date_text(*created)
                    ));
                    figure_pane(ui, cx, i, *figure, None);
                }
                None => {
                    ui.label(format!(
                        "The pinned result «{label}» is not open (open its project to see it)."
                    ));
                }
            }
        }
        Pane::Detail(name) => match room.kind().and_then(|k| cx.shown(k)) {
            Some(i) => detail_pane(ui, cx, i, *name),
            None => {
                ui.label("No result yet.");
            }
        },
        Pane::Scores => match room.kind().and_then(|k| cx.shown(k)) {
            Some(i) => scores_pane(ui, &cx.analyses.results[i]),
            None => {
                ui.label("No result yet.");
            }
        },
        Pane::Replay => replay_pane(ui, cx),
        Pane::Grasp => match room.kind().and_then(|k| cx.shown(k)) {
            Some(i) => grasp_pane(ui, cx, i),
            None => {
                ui.label("No result yet.");
            }
        },
        Pane::Comparison
        | Pane::SpeedChart
        | Pane::Models
        | Pane::Frontier
        | Pane::Live(_)
        | Pane::Compare(_) => {
            ui.label("This pane belongs to another view.");
        }
    }
}

/// Figure `name` of result `i`, with its export and (for the shown result) compare buttons,
/// and whatever it lets the user select.
fn figure_pane(
    ui: &mut egui::Ui,
    cx: &mut Cx,
    i: usize,
    name: FigureId,
    layout: Option<(TileId, &mut Vec<TileRequest>)>,
) {
    let r = &cx.analyses.results[i];
    let Some(fig) = r.figure(name) else {
        ui.label(format!(
            "«{}» has no figure «{name}» (Reset layout fits the tiles to it).",
            r.label
        ));
        return;
    };
    let mut export = false;
    let (tile, requests) = match layout {
        Some((t, r)) => (Some(t), Some(r)),
        None => (None, None),
    };
    let mut requests = requests;
    // A pinned result's selection is scoped to its session only: it is not the shown result.
    let pinned = tile.is_none();
    ui.horizontal(|ui| {
        export = ui
            .small_button("Export")
            .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
            .clicked();
        if let (Some(tile), Some(requests)) = (tile, requests.as_deref_mut())
            && ui
                .small_button("Pin for comparison")
                .on_hover_text(
                    "Keep this figure of this result in a tab of its own, so another result's \
                     can be put beside it",
                )
                .clicked()
        {
            requests.push(TileRequest::AddBeside(
                Pane::Pinned {
                    figure: name,
                    created: r.created,
                    label: r.label.clone(),
                },
                tile,
            ));
        }
    });
    if export {
        let file = crate::experiments::result::export_name(i, r, name);
        let owned = fig.clone();
        cx.analyses.export_figure(&owned, &file);
    }
    let r = &cx.analyses.results[i];
    let Some(fig) = r.figure(name) else {
        return;
    };
    let id = format!("{i}-{name}");
    let linked_cells =
        r.links_of(name, None).is_some() && matches!(fig.kind, FigureKind::Heatmap(_));
    let Some(details) = r.details_of(name).filter(|d| !d.items.is_empty()) else {
        let key = (i, name, None);
        let selection = if linked_cells {
            FigureSelection::Cell(cx.analyses.cells.get(&key).copied())
        } else if r.kind == AnalysisKind::Robustness && matches!(fig.kind, FigureKind::Chart(_)) {
            match &cx.selection.strength {
                Some((ri, f, x)) if *ri == i && *f == name => FigureSelection::Marker(*x),
                _ => FigureSelection::Marker(f64::NAN),
            }
        } else {
            FigureSelection::None
        };
        // The chosen strength's scores above the chart, which takes the rest of the tile.
        if let FigureSelection::Marker(x) = selection
            && x.is_finite()
        {
            strength_values(ui, &cx.analyses.results[i], name, x);
        }
        let act = figure_view::show(ui, &id, fig, ui.available_height(), selection);
        if let Some(at) = act.clicked_cell {
            cx.analyses.cells.insert(key, at);
            select_linked(cx, i, name, None, at, pinned);
            if let Some(requests) = requests {
                requests.push(TileRequest::Activate(Pane::Grasp));
            }
        }
        if let Some(x) = act.marker_x {
            strength_chosen(cx, i, name, x);
        }
        return;
    };
    let key = (i, name);
    let chart = matches!(fig.kind, figures::FigureKind::Chart(_));
    let mut sel = cx.analyses.selected.get(&key).copied();
    if chart {
        // A chart always carries its marker, first at the threshold chosen without labels
        // when the result has one; a slider moves it too.
        let chosen = || {
            let t =
                cx.analyses.results[i].score(crate::cluster::order_agreement::CHOSEN_THRESHOLD)?;
            details.nearest(t)
        };
        let mut k = sel
            .or_else(chosen)
            .unwrap_or(0)
            .min(details.items.len() - 1);
        let keys: Vec<f64> = details.items.iter().map(|x| x.0).collect();
        // The slider fits the tile: its name beside it while a 60-point track stays, else
        // on hover (a wider slider would widen the tile and push the figure out of it).
        ui.scope(|ui| {
            let font = egui::TextStyle::Body.resolve(ui.style());
            let text_w = |t: &str| {
                (ui.painter())
                    .layout_no_wrap(t.to_string(), font.clone(), egui::Color32::WHITE)
                    .size()
                    .x
            };
            let value_w = keys
                .iter()
                .map(|v| text_w(&v.to_string()))
                .fold(0.0, f32::max);
            let gap = ui.spacing().item_spacing.x + ui.spacing().button_padding.x * 2.0;
            let track = ui.available_width() - value_w - 2.0 * gap;
            let named = track - text_w(&details.selector) - gap >= 60.0;
            ui.spacing_mut().slider_width = match named {
                true => track - text_w(&details.selector) - gap,
                false => track,
            }
            .max(30.0);
            let mut slider = egui::Slider::new(&mut k, 0..=details.items.len() - 1)
                .custom_formatter(move |v, _| format!("{}", keys[v as usize]))
                .custom_parser(|_| None);
            if named {
                slider = slider.text(&details.selector);
            }
            ui.add(slider).on_hover_text(&details.selector);
        });
        sel = Some(k);
    }
    let selection = match (chart, sel) {
        (true, Some(k)) => FigureSelection::Marker(details.items[k].0),
        _ => FigureSelection::Image(sel),
    };
    if sel.is_none() {
        ui.small(format!("Click a {} to see it in detail.", details.selector));
    }
    let act = figure_view::show(ui, &id, fig, ui.available_height(), selection);
    if let Some(x) = act.marker_x {
        sel = details.nearest(x);
    }
    if let Some(k) = act.clicked_image {
        sel = Some(k);
        cx.commands.push(Command::FocusBasis {
            result: i,
            basis: k,
        });
        select_linked(cx, i, name, None, [k, 0], pinned);
    }
    if (act.clicked_image.is_some() || act.marker_x.is_some())
        && let Some(requests) = requests
    {
        requests.push(TileRequest::Activate(Pane::Detail(name)));
    }
    if let Some(k) = sel {
        cx.analyses.selected.insert(key, k);
    }
}

/// The detail figure selected through figure `name` of result `i`.
fn detail_pane(ui: &mut egui::Ui, cx: &mut Cx, i: usize, name: FigureId) {
    let r = &cx.analyses.results[i];
    let Some(details) = r.details_of(name).filter(|d| !d.items.is_empty()) else {
        ui.label("Nothing to select in this result.");
        return;
    };
    let sel = cx.analyses.selected.get(&(i, name)).copied();
    let Some((_, detail)) = sel.and_then(|k| details.items.get(k)) else {
        ui.label(format!(
            "Click a {} in «{}» to see it here.",
            details.selector,
            name.key().replace('-', " ")
        ));
        return;
    };
    if ui
        .small_button("Export")
        .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
        .clicked()
    {
        let file = format!(
            "{}-{}",
            crate::experiments::result::export_name(i, r, name),
            crate::experiments::result::slug(&detail.title)
        );
        cx.analyses
            .export
            .write(detail, &file, &mut cx.analyses.notes);
    }
    let k = sel.expect("checked above");
    let r = &cx.analyses.results[i];
    let detail: &Figure = &r.details_of(name).expect("checked above").items[k].1;
    let id = format!("{i}-{name}-detail");
    let key = (i, name, Some(k));
    let selection = if r.links_of(name, Some(k)).is_some() {
        FigureSelection::Cell(cx.analyses.cells.get(&key).copied())
    } else {
        FigureSelection::None
    };
    let act = figure_view::show(ui, &id, detail, ui.available_height(), selection);
    if let Some(at) = act.clicked_cell {
        cx.analyses.cells.insert(key, at);
        select_linked(cx, i, name, Some(k), at, false);
    }
}

/// Select the grasps behind part `at` of figure `name` (detail item `detail`) of result `i`
/// (`pinned`: a result kept beside the shown one).
fn select_linked(
    cx: &mut Cx,
    i: usize,
    name: FigureId,
    detail: Option<usize>,
    at: [usize; 2],
    pinned: bool,
) {
    let r = &cx.analyses.results[i];
    let Some(session) = cx
        .sessions
        .iter()
        .position(|s| s.session.meta.name == r.session)
    else {
        cx.analyses.notes.error(format!(
            "the session «{}» of this result is not open",
            r.session
        ));
        return;
    };
    let n = cx.sessions[session].session.grasps.len();
    let (grasps, origin) = match r.links_of(name, detail).and_then(|l| l.item(at)) {
        // Indices come from a file: keep only those the session has.
        Some(item) => (
            item.grasps.iter().copied().filter(|&g| g < n).collect(),
            item.text.clone(),
        ),
        None => (Vec::new(), "no grasps".to_string()),
    };
    cx.commands.push(Command::SelectGrasps {
        session,
        grasps,
        origin,
        result: (!pinned).then_some(i),
    });
}

/// A click on a robustness chart chooses the strength nearest to `x` among its points.
fn strength_chosen(cx: &mut Cx, i: usize, name: FigureId, x: f64) {
    let r = &cx.analyses.results[i];
    let Some(fig) = r.figure(name) else {
        return;
    };
    let FigureKind::Chart(c) = &fig.kind else {
        return;
    };
    let nearest = c
        .series
        .iter()
        .flat_map(|s| s.x.iter().copied())
        .filter(|v| v.is_finite())
        .min_by(|a, b| (a - x).abs().total_cmp(&(b - x).abs()));
    if let Some(strength) = nearest {
        cx.commands.push(Command::Strength {
            result: i,
            figure: name,
            strength,
        });
    }
}

/// Each method's score at the chosen strength, under its chart.
fn strength_values(ui: &mut egui::Ui, r: &AnalysisResult, name: FigureId, x: f64) {
    let Some(fig) = r.figure(name) else {
        return;
    };
    let FigureKind::Chart(c) = &fig.kind else {
        return;
    };
    ui.horizontal_wrapped(|ui| {
        ui.strong(format!("At {} {}:", c.x.title, number(x)));
        for s in &c.series {
            if let Some(k) = s.x.iter().position(|&v| v == x)
                && let Some(y) = s.y.get(k)
            {
                ui.label(format!("{} {}", s.name, number(*y)));
            }
        }
    });
}

/// Every number of a result: scores, timing and parameters.
pub fn scores_pane(ui: &mut egui::Ui, r: &AnalysisResult) {
    egui::ScrollArea::vertical().show(ui, |ui| {
        egui::Grid::new(("scores", r.created, &r.label))
            .striped(true)
            .show(ui, |ui| {
                for (name, v) in &r.scores {
                    ui.label(name);
                    ui.label(RichText::new(format!("{v:.4}")).strong());
                    ui.end_row();
                }
                if r.held_out.is_none() {
                    ui.label("training time");
                    ui.label(format!("{:.2} s", r.train_seconds));
                    ui.end_row();
                }
                for (k, v) in &r.parameters {
                    ui.label(k);
                    ui.label(v);
                    ui.end_row();
                }
            });
    });
}

/// The focused grasp under stability result `i`: the SVM's decision against the truth, and
/// per sensor its key-frame patch beside the reconstruction from the active bases.
fn grasp_pane(ui: &mut egui::Ui, cx: &mut Cx, i: usize) {
    let r = &cx.analyses.results[i];
    let focus = cx.selection.focus.filter(|&(s, _)| {
        cx.sessions
            .get(s)
            .is_some_and(|x| x.session.meta.name == r.session)
    });
    let Some((s, g)) = focus else {
        ui.label(format!(
            "Focus a grasp of «{}» (click a confusion cell or a basis, or a grasp in the browser).",
            r.session
        ));
        return;
    };
    let session = &cx.sessions[s].session;
    let Some(code) = r.grasp_code(g) else {
        ui.label("This result has no code for the focused grasp.");
        return;
    };
    let grasp = &session.grasps[g];
    ui.horizontal_wrapped(|ui| {
        ui.strong(format!(
            "{}{}",
            grasp.object,
            grasp.trial.map(|t| format!(" #{t}")).unwrap_or_default()
        ));
        ui.label(format!("true: {}", code.truth));
        let right = code.truth == code.predicted;
        let text = RichText::new(format!("predicted: {}", code.predicted)).strong();
        ui.label(if right {
            text
        } else {
            text.color(ui.visuals().error_fg_color)
        });
        ui.label(format!(
            "decision value {:+.3} (> 0 predicts failure, ≤ 0 success)",
            code.decision
        ))
        .on_hover_text(if r.held_out.is_some() {
            "The model's decision value for this grasp of the session it did not train on"
        } else {
            "The linear SVM's decision value from the 10-fold fold that tested this grasp"
        });
    });
    // A held-out result keeps decisions only (its model's codes are not recomputed).
    if code.patches.is_empty() {
        return;
    }
    // Patch and reconstruction side by side for every sensor, fitted to the tile's width
    // (and wrapped onto more rows when even the smallest heatmaps do not fit).
    let n_sensors = code.patches.len().max(1) as f32;
    let gap = ui.spacing().item_spacing.x;
    let width = ((ui.available_width() - 24.0) / (2.0 * n_sensors) - gap).clamp(40.0, 220.0);
    let size = egui::vec2(width, width * 1.3);
    ui.spacing_mut().scroll = egui::style::ScrollStyle::solid();
    egui::ScrollArea::vertical().show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            for p in &code.patches {
                let Some(sensor) = session.sensors.get(p.sensor) else {
                    continue;
                };
                let m = p
                    .patch
                    .iter()
                    .chain(&p.reconstruction)
                    .fold(1e-9_f64, |m, v| m.max(v.abs()));
                let range = (-m, m);
                // Captions wrap to their heatmap's width so a column is never wider.
                ui.vertical(|ui| {
                    ui.set_max_width(size.x);
                    ui.add(egui::Label::new(format!("{}: patch", sensor.name)).wrap());
                    heatmap::sensor_heatmap(ui, sensor, &p.patch, range, ColorMap::Diverging, size);
                });
                ui.vertical(|ui| {
                    ui.set_max_width(size.x);
                    ui.add(
                        egui::Label::new(format!(
                            "reconstruction ({:.0} % error)",
                            100.0 * p.relative_error
                        ))
                        .wrap(),
                    );
                    heatmap::sensor_heatmap(
                        ui,
                        sensor,
                        &p.reconstruction,
                        range,
                        ColorMap::Diverging,
                        size,
                    );
                });
            }
        });
        ui.label("Active bases and coefficients (z-scored units), largest first:");
        for p in &code.patches {
            let name = session
                .sensors
                .get(p.sensor)
                .map_or("sensor", |x| x.name.as_str());
            let terms: Vec<String> = p
                .terms
                .iter()
                .map(|(b, c)| format!("basis {} {c:+.2}", b + 1))
                .collect();
            ui.label(format!(
                "{name}: {}",
                if terms.is_empty() {
                    "none".to_string()
                } else {
                    terms.join(", ")
                }
            ));
        }
    });
}

/// The focused grasp's replay, sized to the tile.
pub fn replay_pane(ui: &mut egui::Ui, cx: &mut Cx) {
    // Only a grasp of the view's session (the active one) plays here.
    let Some((s, g)) = cx.selection.focus.filter(|&(s, _)| s == cx.active) else {
        let name = cx.session().map_or("", |s| s.session.meta.name.as_str());
        ui.label(format!(
            "Select a grasp of «{name}» (in the browser, or by clicking a figure) to replay it here."
        ));
        return;
    };
    // A tile too short for the controls, the fingertips and the recognition scrolls them;
    // the traces fold to what is visible (they never stretch down the scrolled column).
    let action = egui::ScrollArea::vertical()
        .auto_shrink([false, false])
        .show(ui, |ui| {
            (cx.replay).ui(ui, &cx.sessions[s], g, cx.analyses.trace.as_ref())
        })
        .inner;
    match action {
        ReplayAction::Trace(learner) => {
            let ctx = cx.ctx.clone();
            cx.analyses.request_trace(&ctx, &cx.sessions[s], g, learner);
        }
        ReplayAction::PickTaxel { sensor, taxel } => {
            let signal = crate::compare::Signal::Taxel { sensor, taxel };
            cx.commands.push(Command::CompareSignal(signal));
        }
        ReplayAction::None => {}
    }
}
