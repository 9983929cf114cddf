//! The on-screen readability audit: every figure a result of each kind shows (analyses,
//! their detail figures, held-out evaluations, the frontier and speed charts, the replay's
//! class distribution), drawn by the workbench's figure widget in a pane of each tile size,
//! and judged on what egui painted: the text shapes with their galley rectangles, the plot
//! frames, the matrix cells and colour-bar segments, against the pane's rectangle.
//!
//! A case passes when no two texts overlap; no text, plot frame or cell lies outside the
//! pane (or is cut by its clip rectangle); every category of a category axis is labelled,
//! or named by the tooltip shown when the pointer rests on it; the tick labels of every
//! numeric axis (and colour bar) are distinct and at least three.
#![cfg(feature = "gui")]

mod common;

use std::cell::Cell;
use std::collections::BTreeSet;

use egui::epaint::{ClippedShape, Shape};
use egui::{Color32, Pos2, Rect, Vec2};
use egui_kittest::Harness;
use tactile_workbench::app::figure_view::{self, Selection};
use tactile_workbench::app::replay::{class_distribution_figure, finger_values_figure};
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::baselines::baselines_report;
use tactile_workbench::experiments::clustering::report::clustering_report;
use tactile_workbench::experiments::clustering::{
    ClusteringParams, UnsupervisedLearner, run_clustering,
};
use tactile_workbench::experiments::frontier::report::frontier_figures;
use tactile_workbench::experiments::frontier::{FrontierParams, run_frontier};
use tactile_workbench::experiments::recognition::report::{comparison_figures, recognition_report};
use tactile_workbench::experiments::recognition::{
    RecognitionParams, SupervisedLearner, run_recognition,
};
use tactile_workbench::experiments::result::{AnalysisResult, speed_accuracy_figures};
use tactile_workbench::experiments::robustness::report::robustness_report;
use tactile_workbench::experiments::robustness::{
    Family, Perturbation, RobustnessParams, run_robustness,
};
use tactile_workbench::experiments::stability::report::stability_report;
use tactile_workbench::experiments::stability::{
    self, Config, DataOptions, GridSpec, StabilityData, StabilityOptions,
};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::features::table_one::session_features;
use tactile_workbench::figures::{Figure, FigureKind};
use tactile_workbench::jobs::Progress;
use tactile_workbench::models::{
    Calibration, SequenceFitOptions, evaluate, fit_sequences, fit_stability, held_out_report,
    sequence_file,
};
use tactile_workbench::session::{Session, simulate};

/// The pane sizes every figure is drawn at: three tile sizes, and a tile maximised in a
/// window of 1400 × 900 and of 1000 × 700 (the window less its menu, browser, form, card
/// and tile bar: the smallest `figure_tiles_read_in_the_whole_window` measures).
const SIZES: [(&str, f32, f32); 5] = [
    ("360×240", 360.0, 240.0),
    ("520×360", 520.0, 360.0),
    ("800×560", 800.0, 560.0),
    ("maximised in 1400×900", 844.0, 736.0),
    ("maximised in 1000×700", 496.0, 495.0),
];

/// One text as painted: its string, its galley's rectangle on screen (rotation included)
/// and the rectangle it was clipped to.
#[derive(Clone, Debug)]
struct Text {
    text: String,
    rect: Rect,
    clip: Rect,
}

/// What a frame painted that the audit reads.
#[derive(Default)]
struct Painted {
    texts: Vec<Text>,
    /// Filled rectangles: (rectangle, fill, clip).
    rects: Vec<(Rect, Color32, Rect)>,
}

fn collect(shape: &Shape, clip: Rect, out: &mut Painted) {
    match shape {
        Shape::Vec(shapes) => {
            for s in shapes {
                collect(s, clip, out);
            }
        }
        Shape::Text(t) => {
            let text = t.galley.text().trim().to_string();
            if !text.is_empty() {
                let rect = t
                    .galley
                    .rect
                    .rotate_bb(egui::emath::Rot2::from_angle(t.angle))
                    .translate(t.pos.to_vec2());
                out.texts.push(Text { text, rect, clip });
            }
        }
        Shape::Rect(r) if r.fill != Color32::TRANSPARENT => {
            out.rects.push((r.rect, r.fill, clip));
        }
        _ => {}
    }
}

fn painted(shapes: &[ClippedShape]) -> Painted {
    let mut out = Painted::default();
    for s in shapes {
        collect(&s.shape, s.clip_rect, &mut out);
    }
    // Texts clipped away entirely are not seen (and judged as cut below, when in the pane).
    out
}

/// `a` lies within `b`, give or take a pixel of rounding.
fn within(a: Rect, b: Rect) -> bool {
    b.expand(1.0).contains_rect(a)
}

/// The two rectangles share more than a sliver (touching or antialiased edges do not count).
fn overlap(a: Rect, b: Rect) -> bool {
    let i = a.intersect(b);
    i.width() > 1.0 && i.height() > 1.0
}

fn number(text: &str) -> Option<f64> {
    text.replace('−', "-").parse::<f64>().ok()
}

/// `shown` is `name` as written, or cut with an ellipsis.
fn names(shown: &str, name: &str) -> bool {
    shown == name
        || shown
            .strip_suffix('…')
            .is_some_and(|head| !head.is_empty() && name.starts_with(head))
}

/// The plot frames: egui_plot's backgrounds (in the theme's extreme background colour)
/// that lie in no other (a legend's box lies in its plot).
fn plot_frames(p: &Painted, bg: Color32) -> Vec<Rect> {
    let bgs: Vec<Rect> = (p.rects.iter())
        .filter(|(_, fill, _)| *fill == bg)
        .map(|(r, _, _)| *r)
        .collect();
    (bgs.iter().enumerate())
        .filter(|(i, r)| {
            r.width() > 40.0
                && r.height() > 30.0
                && !(bgs.iter().enumerate())
                    .any(|(j, o)| j != *i && o.contains_rect(**r) && o != *r)
        })
        .map(|(_, r)| *r)
        .collect()
}

/// Colour bars: columns of at least 16 slices (far wider than tall, unlike the square
/// cells of a matrix or an image), equally wide and stacked on each other. A matrix's
/// stretched cells stack so too; the heatmap's audit leaves out those within its cells.
fn colour_bars(p: &Painted) -> Vec<Rect> {
    let mut bars: Vec<(Rect, usize)> = Vec::new();
    for (r, _, _) in &p.rects {
        if r.height() > 0.5 * r.width() || r.width() > 40.0 {
            continue;
        }
        match bars.iter_mut().find(|(b, _)| {
            (b.left() - r.left()).abs() < 0.5
                && (b.right() - r.right()).abs() < 0.5
                && ((r.top() - b.bottom()).abs() < 1.0 || (r.bottom() - b.top()).abs() < 1.0)
        }) {
            Some((b, n)) => {
                *b = b.union(*r);
                *n += 1;
            }
            None => bars.push((*r, 1)),
        }
    }
    bars.into_iter()
        .filter(|(_, n)| *n >= 16)
        .map(|(b, _)| b)
        .collect()
}

/// A matrix's cells: the `rows × cols` equal squares painted most often, as their
/// bounding rectangle (None when not painted).
fn matrix(p: &Painted, rows: usize, cols: usize) -> Option<Rect> {
    let key = |r: &Rect| {
        (
            (r.width() * 4.0).round() as i64,
            (r.height() * 4.0).round() as i64,
        )
    };
    let mut sizes: Vec<((i64, i64), usize)> = Vec::new();
    for (r, _, _) in &p.rects {
        match sizes.iter_mut().find(|(k, _)| *k == key(r)) {
            Some((_, n)) => *n += 1,
            None => sizes.push((key(r), 1)),
        }
    }
    let (size, _) = sizes.into_iter().find(|(_, n)| *n == rows * cols)?;
    (p.rects.iter())
        .filter(|(r, _, _)| key(r) == size)
        .map(|(r, _, _)| *r)
        .reduce(|a, b| a.union(b))
}

/// The tick labels of a numeric axis: distinct, and at least three.
fn check_ticks(what: &str, labels: &[&Text], problems: &mut Vec<String>) {
    let texts: Vec<&str> = labels.iter().map(|t| t.text.as_str()).collect();
    let distinct: BTreeSet<&str> = texts.iter().copied().collect();
    if texts.len() < 3 {
        problems.push(format!(
            "{what} shows {} tick labels {texts:?}",
            texts.len()
        ));
    } else if distinct.len() < texts.len() {
        problems.push(format!("{what} repeats tick labels {texts:?}"));
    }
}

/// Tooltips at once, under a pointer that has just moved: the audit rests the pointer for
/// a few frames, not half a second.
fn instant_tooltips(style: &mut egui::Style) {
    style.interaction.tooltip_delay = 0.0;
    style.interaction.show_tooltips_only_when_still = false;
}

/// A figure drawn in a pane of exactly `size`, as a tile hosts it.
struct Pane {
    harness: Harness<'static>,
    rect: std::rc::Rc<Cell<Rect>>,
}

impl Pane {
    fn new(figure: Figure, size: Vec2) -> Self {
        let rect = std::rc::Rc::new(Cell::new(Rect::NOTHING));
        let seen = rect.clone();
        let selection = match &figure.kind {
            FigureKind::ImageGrid(_) => Selection::Image(None),
            FigureKind::Heatmap(_) => Selection::Cell(None),
            _ => Selection::None,
        };
        // The harness puts a margin of 8 around the ui.
        let harness = Harness::builder()
            .with_size(size + Vec2::splat(16.0))
            .build_ui(move |ui| {
                seen.set(ui.max_rect());
                let height = ui.available_height();
                figure_view::show(ui, "audited", &figure, height, selection);
            });
        let mut pane = Pane { harness, rect };
        // Tooltips at once: the audit rests the pointer for a few frames, not half a second.
        (pane.harness.ctx).all_styles_mut(instant_tooltips);
        pane.harness.run_ok();
        pane
    }

    fn painted(&self) -> Painted {
        painted(&self.harness.output().shapes)
    }

    /// The texts painted once the pointer rests at `at` that were not painted before.
    fn hover_texts(&mut self, at: Pos2, before: &Painted) -> Vec<String> {
        self.harness.hover_at(at);
        self.harness.run_steps(3);
        let known: BTreeSet<&str> = before.texts.iter().map(|t| t.text.as_str()).collect();
        self.painted()
            .texts
            .into_iter()
            .map(|t| t.text)
            .filter(|t| !known.contains(t.as_str()))
            .collect()
    }
}

/// Everything wrong with `figure` drawn in a pane of `size`.
fn audit(figure: &Figure, size: Vec2) -> Vec<String> {
    let mut pane = Pane::new(figure.clone(), size);
    let area = pane.rect.get();
    let p = pane.painted();
    let bg = pane.harness.ctx.global_style().visuals.extreme_bg_color;
    let mut problems = Vec::new();
    let visible: Vec<&Text> = p.texts.iter().collect();
    for t in &visible {
        if !within(t.rect, area) || !within(t.rect, t.clip) {
            problems.push(format!(
                "{:?} at {:?} is cut or outside the pane",
                t.text, t.rect
            ));
        }
    }
    for (i, a) in visible.iter().enumerate() {
        for b in &visible[i + 1..] {
            let (ra, rb) = (a.rect.intersect(a.clip), b.rect.intersect(b.clip));
            if overlap(ra, rb) {
                problems.push(format!("{:?} overlaps {:?}", a.text, b.text));
            }
        }
    }
    let frames = plot_frames(&p, bg);
    for f in &frames {
        if !within(*f, area) {
            problems.push(format!("a plot frame {f:?} lies outside the pane {area:?}"));
        }
    }
    if let Some((r, _, _)) = p.rects.iter().find(|(r, _, _)| !within(*r, area)) {
        problems.push(format!(
            "a painted cell {r:?} lies outside the pane {area:?}"
        ));
    }
    let numeric = |t: &&Text| number(&t.text).is_some();
    let x_ticks = |f: &Rect| -> Vec<&Text> {
        (p.texts.iter())
            .filter(numeric)
            .filter(|t| {
                t.rect.top() >= f.bottom() - 1.0
                    && t.rect.top() <= f.bottom() + 30.0
                    && (f.left() - 20.0..=f.right() + 20.0).contains(&t.rect.center().x)
            })
            .collect()
    };
    let y_ticks = |f: &Rect| -> Vec<&Text> {
        (p.texts.iter())
            .filter(numeric)
            .filter(|t| {
                t.rect.right() <= f.left() + 1.0
                    && t.rect.right() >= f.left() - 90.0
                    && (f.top() - 10.0..=f.bottom() + 10.0).contains(&t.rect.center().y)
            })
            .collect()
    };
    let bars_of = colour_bars(&p);
    // A heatmap's stretched cells stack like a bar's slices: those within `cells` are not
    // a colour bar.
    let colour_bar_ticks = |problems: &mut Vec<String>, cells: Option<Rect>| {
        let bars: Vec<&Rect> = (bars_of.iter())
            .filter(|b| cells.is_none_or(|m| !within(**b, m)))
            .collect();
        if bars.is_empty() {
            problems.push("no colour bar painted".into());
        }
        for b in bars {
            let labels: Vec<&Text> = (p.texts.iter())
                .filter(numeric)
                .filter(|t| {
                    t.rect.left() >= b.right() - 1.0
                        && t.rect.left() <= b.right() + 16.0
                        && (b.top() - 8.0..=b.bottom() + 8.0).contains(&t.rect.center().y)
                })
                .collect();
            check_ticks("the colour bar", &labels, problems);
        }
    };
    match &figure.kind {
        // A category axis (strips of points per group): each category named like a bar's.
        FigureKind::Chart(c) if !c.x.categories.is_empty() => match frames.first() {
            Some(f) => {
                check_ticks("the y axis", &y_ticks(f), &mut problems);
                let below: Vec<Text> = (p.texts.iter())
                    .filter(|t| t.rect.top() >= f.bottom() - 1.0)
                    .cloned()
                    .collect();
                bar_categories(&mut pane, &p, *f, &c.x.categories, &below, &mut problems);
            }
            None => problems.push("no plot frame painted".into()),
        },
        FigureKind::Chart(_) => match frames.first() {
            Some(f) => {
                check_ticks("the x axis", &x_ticks(f), &mut problems);
                check_ticks("the y axis", &y_ticks(f), &mut problems);
            }
            None => problems.push("no plot frame painted".into()),
        },
        FigureKind::Bars(b) => match frames.first() {
            Some(f) => {
                check_ticks("the value axis", &y_ticks(f), &mut problems);
                let below: Vec<Text> = (p.texts.iter())
                    .filter(|t| t.rect.top() >= f.bottom() - 1.0)
                    .cloned()
                    .collect();
                bar_categories(&mut pane, &p, *f, &b.categories, &below, &mut problems);
            }
            None => problems.push("no plot frame painted".into()),
        },
        FigureKind::Heatmap(h) => {
            let cells = matrix(&p, h.rows.len(), h.columns.len());
            // Only a column of 16 cells or more can pass for a bar.
            colour_bar_ticks(&mut problems, cells.filter(|_| h.rows.len() >= 16));
            match cells {
                Some(m) if !within(m, area) => {
                    problems.push(format!("the matrix's cells {m:?} run past the pane"));
                }
                Some(m) => matrix_categories(&mut pane, &p, m, &h.rows, &h.columns, &mut problems),
                None => problems.push("the matrix's cells are not all painted".into()),
            }
        }
        FigureKind::ImageGrid(_) => colour_bar_ticks(&mut problems, None),
    }
    problems
}

/// Every category of a bar chart labelled under its bar, or named by the tooltip of its bar.
fn bar_categories(
    pane: &mut Pane,
    p: &Painted,
    frame: Rect,
    categories: &[String],
    below: &[Text],
    problems: &mut Vec<String>,
) {
    let at: Vec<Option<f32>> = (categories.iter())
        .map(|c| {
            below
                .iter()
                .find(|t| names(&t.text, c))
                .map(|t| t.rect.center().x)
        })
        .collect();
    let labelled: Vec<(usize, f32)> = (at.iter().enumerate())
        .filter_map(|(i, x)| Some((i, (*x)?)))
        .collect();
    if labelled.len() == categories.len() {
        return;
    }
    // Where a category's bar is: between the labelled ones, evenly spaced.
    let (Some(&(i0, x0)), Some(&(i1, x1))) = (labelled.first(), labelled.last()) else {
        problems.push(format!(
            "no category of {} labelled: {:?}…",
            categories.len(),
            &categories[..categories.len().min(3)]
        ));
        return;
    };
    let per = if i1 > i0 {
        (x1 - x0) / (i1 - i0) as f32
    } else {
        frame.width() / categories.len() as f32
    };
    let mut unnamed = Vec::new();
    for (i, c) in categories.iter().enumerate() {
        if at[i].is_some() {
            continue;
        }
        let x = x0 + (i as f32 - i0 as f32) * per;
        // Rest on the bar painted there (its middle), else mid-plot. The plot's own
        // background is no bar, though its middle may lie in the middle category's slot.
        let bar = (p.rects.iter())
            .filter(|(r, _, _)| {
                *r != frame && frame.contains_rect(*r) && (r.center().x - x).abs() < per.abs() / 2.0
            })
            .map(|(r, _, _)| r.center())
            .min_by(|a, b| (a.x - x).abs().total_cmp(&(b.x - x).abs()));
        let point = bar.unwrap_or(Pos2::new(x, frame.center().y));
        let shown = pane.hover_texts(point, p);
        if !shown.iter().any(|t| t.contains(c.as_str())) {
            unnamed.push(c.clone());
        }
    }
    if !unnamed.is_empty() {
        problems.push(format!(
            "{} of {} categories neither labelled nor named on hover: {:?}",
            unnamed.len(),
            categories.len(),
            &unnamed[..unnamed.len().min(4)]
        ));
    }
}

/// Every row and column of a matrix labelled beside it, or named by the tooltip of its cells.
fn matrix_categories(
    pane: &mut Pane,
    p: &Painted,
    m: Rect,
    rows: &[String],
    columns: &[String],
    problems: &mut Vec<String>,
) {
    let (cw, ch) = (
        m.width() / columns.len() as f32,
        m.height() / rows.len() as f32,
    );
    let row_labelled = |r: usize| {
        let y = m.top() + (r as f32 + 0.5) * ch;
        p.texts.iter().any(|t| {
            names(&t.text, &rows[r])
                && t.rect.right() <= m.left() + 1.0
                && (t.rect.center().y - y).abs() <= ch.max(t.rect.height()) / 2.0 + 2.0
        })
    };
    let column_labelled = |c: usize| {
        let x = m.left() + (c as f32 + 0.5) * cw;
        p.texts.iter().any(|t| {
            names(&t.text, &columns[c])
                && t.rect.top() >= m.bottom() - 1.0
                && (t.rect.center().x - x).abs() <= cw.max(t.rect.width()) / 2.0 + 2.0
        })
    };
    let cell = |r: usize, c: usize| {
        Pos2::new(
            m.left() + (c as f32 + 0.5) * cw,
            m.top() + (r as f32 + 0.5) * ch,
        )
    };
    let mut unnamed = Vec::new();
    for r in (0..rows.len()).filter(|&r| !row_labelled(r)) {
        let shown = pane.hover_texts(cell(r, columns.len() / 2), p);
        if !shown.iter().any(|t| t.contains(rows[r].as_str())) {
            unnamed.push(format!("row {}", rows[r]));
        }
    }
    for c in (0..columns.len()).filter(|&c| !column_labelled(c)) {
        let shown = pane.hover_texts(cell(rows.len() / 2, c), p);
        if !shown.iter().any(|t| t.contains(columns[c].as_str())) {
            unnamed.push(format!("column {}", columns[c]));
        }
    }
    if !unnamed.is_empty() {
        problems.push(format!(
            "{} of {} rows and columns neither labelled nor named on hover: {:?}",
            unnamed.len(),
            rows.len() + columns.len(),
            &unnamed[..unnamed.len().min(4)]
        ));
    }
}

/// Every figure a result shows: its figures and the first of each of its detail sets.
fn figures_of(r: &AnalysisResult, out: &mut Vec<(String, Figure)>) {
    let tag = r.label.clone();
    for (name, fig) in &r.figures {
        out.push((format!("{tag} · {name}"), fig.clone()));
    }
    for d in &r.details {
        if let Some((_, fig)) = d.items.first() {
            out.push((format!("{tag} · {} detail", d.figure), fig.clone()));
        }
    }
}

fn quick_recognition(session: &Session, learner: SupervisedLearner) -> AnalysisResult {
    let params = RecognitionParams {
        learner,
        reps: 1,
        seed: 1,
        ..Default::default()
    };
    let r = run_recognition(session, &params, &Progress::new()).expect("recognition runs");
    recognition_report(&session.meta.name, &r)
}

/// A held-out evaluation of a stability model and of a DS model (on their own sessions:
/// the figures are what matters here).
fn held_out(stab: &Session, data: &StabilityData, objects: &Session) -> Vec<AnalysisResult> {
    let opts = StabilityOptions {
        single: Config {
            num_bases: 8,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    };
    let fit = fit_stability(MethodId::SparseSvm, stab, data, &opts, &Progress::new())
        .expect("a stability model fits");
    let file = fit.into_file(stab, data);
    let stability = evaluate(&file, stab, Calibration::None).expect("evaluates");
    let (model, secs) = fit_sequences(
        objects,
        &SequenceFitOptions {
            method: MethodId::Ds,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            seed: 1,
            ds: Default::default(),
            gs: Default::default(),
        },
    )
    .expect("a DS model fits");
    let file = sequence_file(model, objects, secs, Default::default(), None);
    let recognition = evaluate(&file, objects, Calibration::None).expect("evaluates");
    vec![held_out_report(&stability), held_out_report(&recognition)]
}

/// The results every test here reads: one of each kind (and their figures), computed once.
struct Computed {
    results: Vec<AnalysisResult>,
    figures: Vec<(String, Figure)>,
}

fn computed() -> &'static Computed {
    static COMPUTED: std::sync::OnceLock<Computed> = std::sync::OnceLock::new();
    COMPUTED.get_or_init(every_figure)
}

/// Every kind of figure the workbench shows, from small, fast runs on the two samples.
fn every_figure() -> Computed {
    let stab = simulate::grasp_stability(0);
    let objects = simulate::object_recognition(0);
    let data = StabilityData::from_session(&stab, &DataOptions::default()).expect("data");
    let progress = Progress::new();
    let mut results = Vec::new();
    // The grid search's map, and the differentials of a model of many bases.
    let grid = StabilityOptions {
        grid: Some(GridSpec {
            num_bases: vec![4, 8, 50],
            beta: vec![0.5, 1.0],
            gamma: vec![0.5, 1.0],
        }),
        ..Default::default()
    };
    let r = stability::run(&data, &grid, &progress).expect("stability runs");
    results.push(stability_report(&r));
    let many = StabilityOptions {
        single: Config {
            num_bases: 50,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    };
    let r = stability::run(&data, &many, &progress).expect("stability runs");
    results.push(stability_report(&r));
    results.push(quick_recognition(&objects, SupervisedLearner::Ds));
    results.push(quick_recognition(&objects, SupervisedLearner::Gs));
    let clustering = ClusteringParams {
        reps: 1,
        seed: 1,
        ..ClusteringParams::for_learner(UnsupervisedLearner::Du)
    };
    let r = run_clustering(&objects, &clustering, &progress).expect("clustering runs");
    results.push(clustering_report(&objects.meta.name, &r));
    let set = objects.label_set("object").expect("objects");
    let truth = objects.labels_of(set);
    let features = session_features(&objects).expect("features");
    // One SVM setting: the search's size does not change the figures.
    let params = tactile_workbench::experiments::baselines::BaselinesParams {
        orders: 1,
        seed: 1,
        svm_c: vec![10.0],
        svm_gamma: vec![0.1],
        cv_repeats: 1,
        ..Default::default()
    };
    let b = tactile_workbench::experiments::baselines::run_baselines(
        features.view(),
        &truth,
        &params,
        &progress,
    )
    .expect("baselines run");
    results.push(baselines_report(&objects.meta.name, &b, 1.0));
    // Two perturbations of the ten at three strengths: their charts are all of one shape.
    let mut robustness = RobustnessParams {
        reps: 1,
        seed: 1,
        ..RobustnessParams::defaults(Family::Recognition)
    };
    (robustness.sweeps)
        .retain(|s| matches!(s.perturbation, Perturbation::Noise | Perturbation::Gain));
    for s in &mut robustness.sweeps {
        s.strengths.truncate(3);
    }
    let r = run_robustness(&objects, &robustness, &progress).expect("robustness runs");
    results.push(robustness_report(&objects.meta.name, &r));
    results.extend(held_out(&stab, &data, &objects));

    let mut out = Vec::new();
    for r in &results {
        figures_of(r, &mut out);
    }
    out.extend(comparison_figures(&results));
    out.extend(speed_accuracy_figures(&results));
    // A small frontier: four sizes are enough for its figures' shapes.
    let frontier = FrontierParams {
        reps: 2,
        seed: 1,
        capacities: vec![5, 20],
        taus: vec![1, 5],
        ..FrontierParams::for_method(MethodId::Ds)
    };
    let f = run_frontier(&objects, &frontier, &progress).expect("a frontier runs");
    out.extend(frontier_figures(&[f]));
    // The replay's live class distribution, of the sample's objects.
    let set = objects.label_set("object").expect("objects");
    let classes: Vec<String> = objects.label_sets[set].classes.clone();
    let p: Vec<f64> = (0..classes.len()).map(|c| 1.0 / (1.0 + c as f64)).collect();
    let total: f64 = p.iter().sum();
    let p: Vec<f64> = p.iter().map(|v| v / total).collect();
    out.push((
        "replay · class distribution".into(),
        class_distribution_figure(&classes, &p, 0, 0),
    ));
    // A one-frame grasp's values, a bar per finger (BTS3's replay).
    out.push((
        "replay · one frame's values".into(),
        finger_values_figure(&stab, &stab.grasps[0], 0),
    ));
    out.extend(compare_figures(&objects, &stab));
    out.push(("live · model at work".into(), live_figure(&objects)));
    out.push((
        "live · novelty at work".into(),
        live_novelty_figure(&objects),
    ));
    Computed {
        results,
        figures: out,
    }
}

/// The Compare view's plots: the samples' total pressure, 40 grasps overlaid, bands by
/// object and the grasps × time heatmap; for single frames, strips by outcome.
fn compare_figures(objects: &Session, stab: &Session) -> Vec<(String, Figure)> {
    use tactile_workbench::compare::{self, Event, Groups, Request, Signal, Spread};
    let request = |s: &Session, groups: Groups| Request {
        signal: Signal::HandTotal,
        event: Event::ContactOnset,
        spread: Spread::MeanSd,
        // Every grasp, as the window overlays them: the heatmap's 200 rows of the sample.
        overlaid: (0..s.grasps.len()).collect(),
        groups,
        seed: 1,
    };
    let c = compare::compare(objects, &[], &request(objects, Groups::by_object(objects)));
    let mut single = stab.clone();
    for g in &mut single.grasps {
        g.frames.truncate(1);
        g.key_frame = 0;
    }
    let d = compare::compare(
        &single,
        &[],
        &request(&single, Groups::by_label_set(&single, 0)),
    );
    vec![
        ("compare · overlay".into(), c.overlay),
        ("compare · bands".into(), c.groups),
        ("compare · heatmap".into(), c.heatmap),
        ("compare · single-frame overlay".into(), d.overlay),
        ("compare · distributions".into(), d.groups),
    ]
}

/// The Live view's "Model at work" chart: DS (fitted on 30 grasps) following a grasp it
/// did not see, as the live engine gives its verdict.
fn live_figure(objects: &Session) -> Figure {
    use tactile_workbench::live::model::LiveModel;
    let mut train = objects.clone();
    train.grasps.truncate(30);
    let defaults = RecognitionParams::default();
    let mut ds = defaults.ds;
    ds.gp.capacity = 20;
    let opts = tactile_workbench::models::SequenceFitOptions {
        method: MethodId::Ds,
        features: tactile_workbench::features::FeatureSet::ALL,
        label_set: "object".into(),
        seed: 1,
        ds,
        gs: defaults.gs,
    };
    let (model, secs) = tactile_workbench::models::fit_sequences(&train, &opts).expect("DS fits");
    let file =
        tactile_workbench::models::sequence_file(model, &train, secs, Default::default(), None);
    let path = common::temp_dir("audit-live").child("ds.json");
    tactile_workbench::models::save(&file, &path).expect("the model saves");
    let one = Session {
        grasps: vec![objects.grasps[35].clone()],
        ..objects.clone()
    };
    let verdict = LiveModel::load(&path, false)
        .expect("the model loads")
        .verdict(&one)
        .expect("a verdict");
    verdict.figure(5).expect("DS gives steps")
}

/// The Live view's "Model at work" chart of a clustering: DU (taught 30 grasps) following
/// a grasp it did not see, its novelty step by step against the threshold.
fn live_novelty_figure(objects: &Session) -> Figure {
    use tactile_workbench::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use tactile_workbench::live::model::LiveModel;
    let mut train = objects.clone();
    train.grasps.truncate(30);
    let mut params = ClusteringParams::for_learner(UnsupervisedLearner::Du);
    params.ds.gp.capacity = 20;
    let opts = tactile_workbench::models::ClusterFitOptions {
        method: MethodId::Du,
        features: tactile_workbench::features::FeatureSet::ALL,
        label_set: "object".into(),
        threshold: 0.4,
        seed: 1,
        params,
    };
    let (model, _) = tactile_workbench::models::fit_clusters(&train, &opts).expect("DU fits");
    let file = tactile_workbench::models::cluster_file(model, &train, 0.0, None);
    let path = common::temp_dir("audit-live-du").child("du.json");
    tactile_workbench::models::save(&file, &path).expect("the model saves");
    let one = Session {
        grasps: vec![objects.grasps[35].clone()],
        ..objects.clone()
    };
    let verdict = LiveModel::load(&path, false)
        .expect("the model loads")
        .verdict(&one)
        .expect("a verdict");
    verdict
        .figure(5)
        .expect("DU gives its novelty step by step")
}

#[test]
fn every_figure_reads_in_every_pane_size() {
    let figures = &computed().figures;
    assert!(figures.len() > 30, "{} figures", figures.len());
    let mut failing: BTreeSet<(String, String)> = BTreeSet::new();
    let mut report = Vec::new();
    for (name, fig) in figures {
        for (size_name, w, h) in SIZES {
            let problems = audit(fig, Vec2::new(w, h));
            if !problems.is_empty() {
                failing.insert((name.clone(), size_name.to_string()));
                report.push(format!(
                    "{name} at {size_name}:\n    {}",
                    problems.join("\n    ")
                ));
            }
        }
    }
    assert!(
        failing.is_empty(),
        "{} of {} cases fail:\n{}",
        failing.len(),
        figures.len() * SIZES.len(),
        report.join("\n")
    );
}

/// The problems of the pane drawn in `area` of a whole window: the texts painted in it
/// (clipped to it or to a part of it) and its plot frames, by the same rules as above.
fn audit_in_window(p: &Painted, area: Rect, bg: Color32) -> Vec<String> {
    let mine = |clip: &Rect| within(*clip, area) || (within(area, *clip) && clip.area() > 0.0);
    let texts: Vec<&Text> = (p.texts.iter())
        .filter(|t| mine(&t.clip) && t.rect.intersects(area))
        .collect();
    let mut problems = Vec::new();
    for t in &texts {
        if !within(t.rect, area) || !within(t.rect, t.clip) {
            problems.push(format!(
                "{:?} at {:?} (clipped to {:?}) is cut or outside the pane {area:?}",
                t.text, t.rect, t.clip
            ));
        }
    }
    for (i, a) in texts.iter().enumerate() {
        for b in &texts[i + 1..] {
            if overlap(a.rect.intersect(a.clip), b.rect.intersect(b.clip)) {
                problems.push(format!("{:?} overlaps {:?}", a.text, b.text));
            }
        }
    }
    for f in plot_frames(p, bg) {
        if f.intersects(area) && !within(f, area) {
            problems.push(format!("a plot frame {f:?} lies outside the pane {area:?}"));
        }
    }
    problems
}

/// Whole windows of 1400 × 900 and 1000 × 700 showing a result of each kind: every figure
/// tile of the default layout, then each figure tile maximised, read through the real tiles.
#[test]
fn figure_tiles_read_in_the_whole_window() {
    use tactile_workbench::app::selection::Command;
    use tactile_workbench::app::views::Pane as TilePane;
    let results = &computed().results;
    let mut report = Vec::new();
    let mut failing: BTreeSet<String> = BTreeSet::new();
    let mut maximised = Vec::new();
    for (w, h) in [(1400.0, 900.0), (1000.0, 700.0)] {
        let mut harness = common::gui::workbench(w, h);
        harness.ctx.all_styles_mut(instant_tooltips);
        for r in results {
            let app = harness.state_mut();
            app.analyses.results.push(r.clone());
            let i = app.analyses.results.len() - 1;
            app.commands.push(Command::OpenResult(i));
            harness.run_ok();
            let bg = harness.ctx.global_style().visuals.extreme_bg_color;
            let key = tactile_workbench::app::views::result_layout_key(harness.state().view, r);
            let Some(layout) = harness.state().layouts.get(&key) else {
                report.push(format!("{} has no layout", r.label));
                continue;
            };
            let tiles: Vec<(egui_tiles::TileId, Rect, String)> = (layout.tree.tiles.iter())
                .filter_map(|(id, t)| match t {
                    egui_tiles::Tile::Pane(pane @ TilePane::Figure(_))
                        if layout.tree.is_visible(*id) =>
                    {
                        Some((*id, layout.tree.tiles.rect(*id)?, format!("{pane:?}")))
                    }
                    _ => None,
                })
                .collect();
            let p = painted(&harness.output().shapes);
            // The card above the tiles wraps its words inside the panel: none is cut at
            // the panel's edge.
            let top = (layout.tree.tiles.iter())
                .filter_map(|(id, _)| layout.tree.tiles.rect(*id))
                .map(|r| r.top())
                .fold(f32::INFINITY, f32::min);
            if let Some(hide) = p.texts.iter().find(|t| t.text == "Hide form") {
                for t in &p.texts {
                    let central =
                        t.rect.left() < hide.clip.right() && t.rect.top() >= hide.rect.top() - 1.0;
                    if central && t.rect.bottom() < top && t.rect.right() > hide.clip.right() + 0.5
                    {
                        report.push(format!(
                            "{} in {w}×{h}: the card's {:?} is cut at the panel's edge",
                            r.label, t.text
                        ));
                        failing.insert(format!("{} card in {w}×{h}", r.label));
                    }
                }
            }
            // Every tile keeps to the central panel, left of the form beside it.
            if let Some(hide) = p.texts.iter().find(|t| t.text == "Hide form") {
                for (id, _) in layout.tree.tiles.iter() {
                    let Some(rect) = layout.tree.tiles.rect(*id) else {
                        continue;
                    };
                    if layout.tree.is_visible(*id) && rect.right() > hide.clip.right() + 0.5 {
                        report.push(format!(
                            "{} in {w}×{h}: a tile reaches x = {} past the central panel's \
                             edge at {}",
                            r.label,
                            rect.right(),
                            hide.clip.right()
                        ));
                        failing.insert(format!("{} tiles in {w}×{h}", r.label));
                    }
                }
            }
            for (_, area, pane) in &tiles {
                let case = format!("{} · {pane} in {w}×{h}", r.label);
                for problem in audit_in_window(&p, *area, bg) {
                    report.push(format!("{case}: {problem}"));
                    failing.insert(case.clone());
                }
            }
            for (id, _, pane) in &tiles {
                if let Some(layout) = harness.state_mut().layouts.get_mut(&key) {
                    layout.maximised = Some(*id);
                }
                // The frame after the one that resized the plot: egui_plot lays its axes out
                // from the last frame's tick labels.
                harness.run_ok();
                harness.run_steps(2);
                let p = painted(&harness.output().shapes);
                // The maximised pane: under the "Restore layout" row, to the bottom of the
                // central panel.
                let Some(restore) = p.texts.iter().find(|t| t.text == "Restore layout") else {
                    report.push(format!("{} {pane}: no maximised tile", r.label));
                    continue;
                };
                let area = Rect::from_min_max(
                    Pos2::new(restore.clip.left(), restore.rect.bottom() + 4.0),
                    restore.clip.right_bottom(),
                );
                maximised.push(((w, h), area.size()));
                let case = format!("{} · {pane} maximised in {w}×{h}", r.label);
                for problem in audit_in_window(&p, area, bg) {
                    report.push(format!("{case}: {problem}"));
                    failing.insert(case.clone());
                }
                if let Some(layout) = harness.state_mut().layouts.get_mut(&key) {
                    layout.maximised = None;
                }
            }
        }
    }
    // The audited sizes are those of a maximised tile (the smallest seen, within a point).
    for ((w, h), size) in maximised {
        let name = format!("maximised in {w}×{h}");
        let (_, aw, ah) = SIZES.iter().find(|(n, _, _)| *n == name).expect("audited");
        assert!(
            size.x + 1.0 >= *aw && size.y + 1.0 >= *ah,
            "{name}: a tile of {size:?}, audited at {aw}×{ah}"
        );
    }
    assert!(
        failing.is_empty(),
        "{} cases fail: {failing:#?}\n{}",
        failing.len(),
        report.join("\n")
    );
}

/// The speed charts' x axes are measured times, so their span differs from run to run:
/// the same figure with its times scaled over two decades, in steps finer than its own
/// span, reads at the smallest size (a run once gave an axis of only "0.06 0.07").
#[test]
fn speed_charts_read_whatever_their_measured_times() {
    let speed: Vec<&(String, Figure)> = (computed().figures.iter())
        .filter(|(name, _)| name.contains("speed-against-accuracy"))
        .collect();
    assert!(!speed.is_empty(), "no speed chart among the figures");
    let mut report = Vec::new();
    for (name, fig) in speed {
        for k in -12..=12 {
            let factor = 10f64.powf(f64::from(k) / 12.0);
            let mut scaled = fig.clone();
            if let FigureKind::Chart(chart) = &mut scaled.kind {
                for s in &mut chart.series {
                    s.x.iter_mut().for_each(|x| *x *= factor);
                }
            }
            let (_, w, h) = SIZES[0];
            let problems = audit(&scaled, Vec2::new(w, h));
            if !problems.is_empty() {
                report.push(format!("{name} × {factor:.3}: {}", problems.join("; ")));
            }
        }
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
}

/// The same figures through the export's layout at every export preset: the
/// export's layout record judged by the same rules (no overprint, nothing off the image,
/// three distinct ticks, every category axis labelled, no data under the legend).
#[test]
fn every_figure_reads_at_every_export_preset() {
    let mut report = Vec::new();
    for (name, fig) in &computed().figures {
        // The presets (a tile of the window is audited on screen above).
        let presets = common::legibility::sizes();
        for (size, opts) in presets.into_iter().filter(|(n, _)| n.ends_with("preset")) {
            for p in common::legibility::legibility_problems(fig, &opts) {
                report.push(format!("{name} at {size}: {p}"));
            }
        }
    }
    assert!(report.is_empty(), "{}", report.join("\n"));
}
