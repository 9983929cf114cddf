//! The Compare view driven as a user would, by accessible labels: a signal picked from the
//! searched tree, grasps overlaid as the selection changes, a click that seeks the replay;
//! on the real datasets (skipped when absent) one band per iCub object, BTS3 electrodes as
//! distributions of successes and failures, and a DS model's true class probability for
//! correct and wrong recognitions against time from contact.
#![cfg(feature = "gui")]

mod common;

use std::time::{Duration, Instant};

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::WorkbenchApp;
use tactile_workbench::app::selection::Command;
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::compare::{Event, Signal};
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::features::FeatureSet;
use tactile_workbench::figures::{Chart, Figure, FigureKind};
use tactile_workbench::models::{self, SequenceFitOptions};
use tactile_workbench::session::{SubsetSpec, import_icub, subset};

/// Step until the Compare view has computed what it shows (bounded).
fn settle(h: &mut Harness<'static, WorkbenchApp>) {
    let t = Instant::now();
    h.run_ok();
    while (h.state().rooms.compare.computing() || h.state().rooms.compare.shown.is_none())
        && t.elapsed() < Duration::from_secs(120)
    {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.run_ok();
}

fn chart(f: &Figure) -> &Chart {
    match &f.kind {
        FigureKind::Chart(c) => c,
        other => panic!("a chart, not {other:?}"),
    }
}

fn names(c: &Chart) -> Vec<String> {
    c.series.iter().map(|s| s.name.clone()).collect()
}

fn open_compare(h: &mut Harness<'static, WorkbenchApp>) {
    h.get_by_label("Compare").click();
    settle(h);
}

fn choose(h: &mut Harness<'static, WorkbenchApp>, combo: &str, item: &str) {
    h.get_by_role_and_label(Role::ComboBox, combo).click();
    h.run_ok();
    h.get_by_label(item).click();
    settle(h);
}

#[test]
fn a_searched_signal_is_plotted_and_overlays_follow_the_selection() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    let active = h.state().browser.active;
    let n = h.state().sessions[active].session.grasps.len();
    let c = h.state().rooms.compare.shown.clone().unwrap();
    // Nothing selected: every grasp of the session overlaid, one line each.
    assert_eq!(chart(&c.overlay).series.len(), n);

    // The tree searched for one taxel: the only leaf left is clicked and plotted.
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("thumb taxel 3");
    h.run_ok();
    h.get_by_label("taxel 3").click();
    settle(&mut h);
    assert_eq!(
        h.state().rooms.compare.form.signal,
        Signal::Taxel {
            sensor: 0,
            taxel: 2
        }
    );
    let c = h.state().rooms.compare.shown.clone().unwrap();
    assert!(chart(&c.overlay).y.title.contains("taxel 3"));

    // A selection of three grasps: their three traces, named after them.
    let grasps = vec![4, 1, 7];
    h.state_mut().commands.push(Command::SelectGrasps {
        session: active,
        grasps: grasps.clone(),
        origin: "test".into(),
        result: None,
    });
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    assert_eq!(c.overlay_grasps, [vec![4], vec![1], vec![7]]);
    let s = &h.state().sessions[active].session;
    let expected: Vec<String> = grasps
        .iter()
        .map(|&g| tactile_workbench::compare::grasp_name(s, g))
        .collect();
    assert_eq!(names(chart(&c.overlay)), expected);
    // The bands still sum up every grasp of the session by its class.
    let groups = chart(&c.groups);
    let total: usize = (groups.series.iter())
        .map(|s| {
            let n = s.name.rsplit("n=").next().unwrap().trim_end_matches(')');
            n.parse::<usize>().unwrap()
        })
        .sum();
    assert_eq!(total, n);
}

#[test]
fn a_click_on_a_time_plot_seeks_the_replay() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    choose(&mut h, "Align at", "first frame");
    let active = h.state().browser.active;
    h.state_mut().commands.push(Command::Focus {
        session: active,
        grasp: 0,
    });
    settle(&mut h);
    let start = h.state().replay.frame;
    let (_, g) = h.state().selection.focus.unwrap();
    let times = Event::FirstFrame.times(&h.state().sessions[active].session, g);
    // Click the groups plot at the grasp's last frame's time, well away from the key frame.
    let last = times.len() - 1;
    assert_ne!(start, last);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let at = tactile_workbench::app::figure_view::marker_position(
        &h.ctx,
        "compare-compare-groups",
        chart(&c.groups),
        0,
        chart(&c.groups).series[0]
            .x
            .iter()
            .position(|&x| (x - times[last]).abs() < 1e-9)
            .expect("the band reaches the last frame"),
    )
    .expect("the groups plot was drawn");
    h.hover_at(at);
    h.run_ok();
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Default::default(),
    });
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Default::default(),
    });
    h.run_ok();
    assert_eq!(h.state().replay.frame, last);
}

#[test]
fn on_icub_mean_total_pressure_by_object_gives_one_band_per_object() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    let mut h = common::gui::workbench_opening(
        vec![dir, common::sample("grasp-stability.json")],
        1400.0,
        900.0,
    );
    h.get_by_label("iCub grasp dataset").click();
    h.run_ok();
    open_compare(&mut h);
    choose(&mut h, "Groups", "object");
    assert_eq!(h.state().rooms.compare.form.signal, Signal::HandTotal);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let bands = chart(&c.groups);
    assert_eq!(bands.series.len(), 10, "{:?}", names(bands));
    assert!(bands.series.iter().all(|s| s.name.ends_with("(n=20)")));
    assert!(bands.series.iter().all(|s| s.error.is_some()));
    assert_eq!(bands.x.title, "time from contact onset");
    assert_eq!(chart(&c.overlay).series.len(), 200);
}

#[test]
fn on_bts3_an_electrode_compares_successes_and_failures_as_distributions() {
    let Some(csv) = common::dataset("bts3/biotac-palmdown-grasps.csv") else {
        return;
    };
    let mut h = common::gui::workbench_opening(
        vec![csv, common::sample("grasp-stability.json")],
        1400.0,
        900.0,
    );
    h.get_by_label_contains("BioTac SP grasp stability").click();
    h.run_ok();
    open_compare(&mut h);
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("mf taxel 7");
    h.run_ok();
    h.get_by_label("taxel 7").click();
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    assert!(c.single_frame);
    let d = chart(&c.groups);
    // A strip per outcome and the medians with quartiles; no time axis.
    let n = names(d);
    assert_eq!(n.len(), 3, "{n:?}");
    assert!(n[0].starts_with("success (n=") && n[1].starts_with("failure (n="));
    assert!(!d.x.title.contains("time"), "{}", d.x.title);
    let points: usize = d.series[..2].iter().map(|s| s.y.len()).sum();
    assert_eq!(points, 1276);
    // Each strip's group is named on its axis, not a position.
    assert_eq!(d.x.categories, ["success", "failure"]);
    assert_eq!(d.x.title, "outcome");
    // Single frames have no time: the grasps × time tile folds away.
    let key = tactile_workbench::app::views::layout_key(tactile_workbench::app::View::Compare);
    let layout = &h.state().layouts[&key];
    let tile = (layout.tree.tiles)
        .find_pane(&tactile_workbench::app::views::Pane::Compare(
            tactile_workbench::compare::ComparePlot::Heatmap,
        ))
        .expect("the layout has the tile");
    assert!(!layout.tree.tiles.is_visible(tile));
    // ... and the replay beside it takes its row: no empty cell.
    let rect = |pane| {
        let id = layout.tree.tiles.find_pane(&pane).expect("a tile");
        layout.tree.tiles.rect(id).expect("shown")
    };
    use tactile_workbench::app::views::Pane;
    use tactile_workbench::compare::ComparePlot;
    let replay = rect(Pane::Replay).width();
    let above = rect(Pane::Compare(ComparePlot::Groups)).width()
        + rect(Pane::Compare(ComparePlot::Overlay)).width();
    assert!(
        replay >= 0.95 * above,
        "the replay {replay} wide under {above}"
    );
    // Overlaid single frames are points too, every grasp's.
    let o = chart(&c.overlay);
    assert_eq!(o.series[..2].iter().map(|s| s.y.len()).sum::<usize>(), 1276);
}

#[test]
fn on_icub_a_ds_models_true_class_probability_by_correct_and_wrong() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    // DS taught trials 1–3 of each object: some of the other grasps it gets wrong.
    let icub = import_icub(&dir).unwrap();
    let spec = SubsetSpec {
        trials: (1..=3).into(),
        ..Default::default()
    };
    let part = subset(&icub, &spec, "iCub trials 1-3").unwrap();
    let defaults = RecognitionParams::default();
    let opts = SequenceFitOptions {
        method: MethodId::Ds,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        seed: 0,
        ds: defaults.ds.clone(),
        gs: defaults.gs.clone(),
    };
    let (m, secs) = models::fit_sequences(&part, &opts).unwrap();
    let file = models::sequence_file(m, &part, secs, Default::default(), None);
    let mut h = common::gui::workbench_opening(
        vec![dir, common::sample("grasp-stability.json")],
        1400.0,
        900.0,
    );
    h.state_mut().analyses.models.add(file);
    h.get_by_label("iCub grasp dataset").click();
    h.run_ok();
    open_compare(&mut h);
    choose(&mut h, "Model outputs", "DS, trained on iCub trials 1-3");
    choose(&mut h, "Groups", "correct vs wrong (model)");
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("true class");
    h.run_ok();
    h.get_by_label("DS · true class probability").click();
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let bands = chart(&c.groups);
    let n = names(bands);
    assert_eq!(n.len(), 2, "{n:?}");
    assert!(n[0].starts_with("correct (n=") && n[1].starts_with("wrong (n="));
    assert_eq!(bands.x.title, "time from contact onset");
    assert_eq!(bands.y.title, "DS · true class probability");
    // Probabilities, and the correct grasps end surer of their class than the wrong ones.
    for s in &bands.series {
        assert!(s.y.iter().all(|p| (0.0..=1.0).contains(p)), "{}", s.name);
    }
    let last = |k: usize| *bands.series[k].y.last().unwrap();
    assert!(last(0) > last(1), "correct {} wrong {}", last(0), last(1));
}

/// Where chart `id` drew point `k` of its series `series` in the last frame.
fn point_at(
    h: &Harness<'static, WorkbenchApp>,
    id: &str,
    c: &Chart,
    series: usize,
    k: usize,
) -> egui::Pos2 {
    tactile_workbench::app::figure_view::marker_position(&h.ctx, id, c, series, k)
        .unwrap_or_else(|| panic!("{id} was drawn"))
}

const OVERLAY: &str = "compare-compare-overlay";
const GROUPS: &str = "compare-compare-groups";

#[test]
fn zooming_one_time_plot_zooms_them_all_and_the_heatmap_follows() {
    use tactile_workbench::app::figure_view::{linked_x_range, shown_x_range};
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    h.run_ok();
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let (overlay, groups) = (chart(&c.overlay), chart(&c.groups));
    let before = shown_x_range(&h.ctx, OVERLAY, overlay).expect("the overlay was drawn");
    assert!(linked_x_range(&h.ctx, egui::Id::unique("compare-time-axis")).is_none());
    let columns =
        |h: &Harness<'static, WorkbenchApp>| match h.state().rooms.compare.heatmap_in_zoom() {
            Some(f) => match &f.kind {
                FigureKind::Heatmap(m) => m.columns.len(),
                other => panic!("a heatmap, not {other:?}"),
            },
            None => 0,
        };
    assert_eq!(columns(&h), 0, "not zoomed: the whole heatmap");
    // Zoom in (as ctrl + wheel does) over the overlay's middle.
    let s = &overlay.series[0];
    let at = point_at(&h, OVERLAY, overlay, 0, s.x.len() / 2);
    h.hover_at(at);
    h.run_ok();
    h.event(egui::Event::Zoom(2.0));
    h.run_ok();
    // The plots drawn before the zoomed one in its frame follow in the next.
    h.step();
    h.step();
    let zoomed = shown_x_range(&h.ctx, OVERLAY, overlay).unwrap();
    let width = |r: (f64, f64)| r.1 - r.0;
    assert!(
        width(zoomed) < 0.75 * width(before),
        "{before:?} → {zoomed:?}"
    );
    // The bands follow along time, and the heatmap keeps the columns in that range.
    let follows = shown_x_range(&h.ctx, GROUPS, groups).unwrap();
    assert!((follows.0 - zoomed.0).abs() < 1e-9 && (follows.1 - zoomed.1).abs() < 1e-9);
    assert_eq!(
        linked_x_range(&h.ctx, egui::Id::unique("compare-time-axis")),
        Some(zoomed)
    );
    let in_range = (c.heatmap_times.iter())
        .filter(|t| (zoomed.0..=zoomed.1).contains(*t))
        .count();
    assert!(in_range > 0 && in_range < c.heatmap_times.len());
    assert_eq!(columns(&h), in_range);
}

#[test]
fn a_signal_dragged_from_the_tree_onto_a_plot_is_plotted() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("thumb taxel 3");
    h.run_ok();
    let from = h.get_by_label("taxel 3").rect().center();
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let to = point_at(&h, GROUPS, chart(&c.groups), 0, 0);
    assert_eq!(h.state().rooms.compare.form.signal, Signal::HandTotal);
    h.event(egui::Event::PointerMoved(from));
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Default::default(),
    });
    h.step();
    for k in 1..=10 {
        h.event(egui::Event::PointerMoved(
            from + (to - from) * (k as f32 / 10.0),
        ));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Default::default(),
    });
    settle(&mut h);
    assert_eq!(
        h.state().rooms.compare.form.signal,
        Signal::Taxel {
            sensor: 0,
            taxel: 2
        }
    );
}

#[test]
fn a_taxel_clicked_in_the_replay_is_compared() {
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    let active = h.state().browser.active;
    h.state_mut().commands.push(Command::Focus {
        session: active,
        grasp: 0,
    });
    settle(&mut h);
    let sensor = h.state().sessions[active].session.sensors[0].clone();
    // The replay's first heatmap is under its sensor's caption (taxels at their places in
    // the fingertip): click across it until a taxel is hit.
    let caption = format!("{} ({} taxels)", sensor.name, sensor.layout.taxel_count());
    let top = h.get_by_label(&caption).rect();
    let spots = (0..16).flat_map(|row| (0..6).map(move |col| (row, col)));
    for (row, col) in spots {
        if matches!(h.state().rooms.compare.form.signal, Signal::Taxel { .. }) {
            break;
        }
        let at = egui::pos2(
            top.left() + 8.0 + 8.0 * col as f32,
            top.bottom() + 8.0 + 8.0 * row as f32,
        );
        for pressed in [true, false] {
            h.event(egui::Event::PointerMoved(at));
            h.event(egui::Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Default::default(),
            });
            h.step();
        }
        h.run_ok();
    }
    assert!(
        matches!(
            h.state().rooms.compare.form.signal,
            Signal::Taxel { sensor: 0, .. }
        ),
        "{:?}",
        h.state().rooms.compare.form.signal
    );
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    assert!(
        chart(&c.overlay).y.title.contains("taxel"),
        "{}",
        chart(&c.overlay).y.title
    );
}

#[test]
fn a_stability_models_decision_value_by_correct_and_wrong() {
    use tactile_workbench::experiments::stability::{
        Config, DataOptions, StabilityData, StabilityOptions,
    };
    use tactile_workbench::jobs::Progress;
    let session =
        tactile_workbench::session::load(&common::sample("grasp-stability.json")).unwrap();
    let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
    let opts = StabilityOptions {
        single: Config {
            num_bases: 8,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    };
    let fit = models::fit_stability(MethodId::RawSvm, &session, &data, &opts, &Progress::new());
    let file = fit.unwrap().into_file(&session, &data);
    let predictions = models::predict(&file, &session, models::Calibration::None).unwrap();
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.state_mut().analyses.models.add(file);
    h.get_by_label("Simulated grasp stability").click();
    h.run_ok();
    open_compare(&mut h);
    choose(
        &mut h,
        "Model outputs",
        "raw linear SVM, trained on Simulated grasp stability",
    );
    choose(&mut h, "Align at", "key frame");
    choose(&mut h, "Groups", "correct vs wrong (model)");
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("decision");
    h.run_ok();
    h.get_by_label("raw linear SVM · SVM decision value")
        .click();
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let bands = chart(&c.groups);
    assert_eq!(bands.y.title, "raw linear SVM · SVM decision value");
    // One value per grasp, at its key frame: each band is one point at time 0, the mean of
    // its grasps' decision values.
    for (k, correct) in [(0, true), (1, false)] {
        let d: Vec<f64> = (predictions.iter())
            .filter(|p| (p.truth.as_deref() == Some(p.predicted.as_str())) == correct)
            .map(|p| p.decision)
            .collect();
        if d.is_empty() {
            continue;
        }
        let s = bands
            .series
            .iter()
            .find(|s| {
                s.name
                    .starts_with(if correct { "correct" } else { "wrong" })
            })
            .unwrap();
        assert!(s.name.ends_with(&format!("(n={})", d.len())), "{}", s.name);
        let at: Vec<usize> = (0..s.x.len()).filter(|&i| s.y[i].is_finite()).collect();
        assert_eq!(at.len(), 1, "{k}: {:?}", s.y);
        assert_eq!(s.x[at[0]], 0.0);
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        assert!((s.y[at[0]] - mean).abs() < 1e-9, "{} vs {mean}", s.y[at[0]]);
    }
}

#[test]
fn a_clustering_models_clusters_are_offered_as_groups() {
    use tactile_workbench::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use tactile_workbench::models::ClusterFitOptions;
    let session =
        tactile_workbench::session::load(&common::sample("object-recognition.json")).unwrap();
    let opts = ClusterFitOptions {
        method: MethodId::Du,
        features: FeatureSet::ALL,
        label_set: "object".into(),
        threshold: 0.4,
        seed: 2,
        params: ClusteringParams::for_learner(UnsupervisedLearner::Du),
    };
    // Taught three objects' first five trials: the others open clusters of their own.
    let spec = SubsetSpec {
        objects: session.objects()[..3].to_vec(),
        trials: (1..=5).into(),
        labels: Vec::new(),
    };
    let part = subset(&session, &spec, "part").unwrap();
    let (model, _) = models::fit_clusters(&part, &opts).unwrap();
    let file = models::cluster_file(model, &part, 0.0, None);
    let assigned = models::predict(&file, &session, models::Calibration::None).unwrap();
    let mut h = common::gui::workbench(1400.0, 900.0);
    h.state_mut().analyses.models.add(file);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    open_compare(&mut h);
    choose(&mut h, "Model outputs", "DU, trained on part");
    choose(&mut h, "Groups", "clusters (model)");
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let bands = chart(&c.groups);
    // One band per cluster some grasp is in, its size the grasps the model puts there.
    let mut clusters: Vec<&str> = assigned.iter().map(|p| p.predicted.as_str()).collect();
    clusters.sort_unstable();
    clusters.dedup();
    assert_eq!(bands.series.len(), clusters.len(), "{:?}", names(bands));
    for s in &bands.series {
        let name = s.name.split(" (n=").next().unwrap();
        let n = assigned.iter().filter(|p| p.predicted == name).count();
        assert_eq!(s.name, format!("{name} (n={n})"));
    }
    // Its novelty of each grasp so far, step by step, is a signal to plot by cluster.
    h.get_by_role_and_label(Role::TextInput, "Signals").click();
    h.run_ok();
    h.get_by_role_and_label(Role::TextInput, "Signals")
        .type_text("novelty");
    h.run_ok();
    h.get_by_label("DU · novelty").click();
    settle(&mut h);
    let c = h.state().rooms.compare.shown.clone().unwrap();
    let bands = chart(&c.groups);
    assert_eq!(bands.y.title, "DU · novelty");
    assert_eq!(bands.series.len(), clusters.len(), "{:?}", names(bands));
    let mut finite = 0;
    for s in &bands.series {
        for v in s.y.iter().filter(|v| v.is_finite()) {
            assert!((0.0..=1.0).contains(v), "{}: {v}", s.name);
            finite += 1;
        }
    }
    assert!(finite > 0);
}

/// The replay beside the plots keeps its controls, every fingertip and both traces inside
/// its tile, at both window sizes: the fingertips wrap onto another row rather than run
/// past its edge, and where the tile is too short the column scrolls to each, the traces'
/// plots at least 80 points tall (never squeezed flat or cut at the tile's bottom).
#[test]
fn the_replay_tile_keeps_its_controls_and_fingertips_inside() {
    use tactile_workbench::app::View;
    use tactile_workbench::app::views::{Pane, layout_key};
    for (w, hgt) in [(1400.0, 900.0), (1000.0, 700.0)] {
        let mut h = common::gui::workbench(w, hgt);
        h.get_by_label("Simulated object recognition").click();
        h.run_ok();
        open_compare(&mut h);
        let active = h.state().browser.active;
        h.state_mut().commands.push(Command::Focus {
            session: active,
            grasp: 0,
        });
        settle(&mut h);
        h.run_steps(2);
        let layout = &h.state().layouts[&layout_key(View::Compare)];
        let id = layout
            .tree
            .tiles
            .find_pane(&Pane::Replay)
            .expect("a replay tile");
        let tile = layout.tree.tiles.rect(id).expect("shown");
        // Where the tile is too short for the whole replay, each is scrolled to first.
        let mut inside = Vec::new();
        let mut traces = Vec::new();
        let labels = [
            "Show the recognition as the hand closes",
            "(12 taxels)",
            "Step forward",
            "Joint encoders trace",
            "Per-finger feature trace",
        ];
        for label in labels {
            let n = h.get_all_by_label_contains(label).count();
            for k in 0..n {
                h.get_all_by_label_contains(label)
                    .nth(k)
                    .unwrap()
                    .scroll_to_me();
                h.run_ok();
                let r = h.get_all_by_label_contains(label).nth(k).unwrap().rect();
                if label.ends_with("trace") {
                    traces.push(r);
                } else {
                    inside.push(r);
                }
            }
        }
        let slider = h.get_by_role_and_label(Role::Slider, "frame");
        slider.scroll_to_me();
        h.run_ok();
        inside.push(h.get_by_role_and_label(Role::Slider, "frame").rect());
        assert_eq!(inside.len(), 8, "five fingertips and three controls");
        assert_eq!(traces.len(), 2, "the joint and finger traces");
        for r in &traces {
            // Room for three y ticks at the charts' 36-point spacing.
            assert!(r.height() >= 80.0, "a trace squeezed to {r:?} in {w}×{hgt}");
        }
        for r in inside.into_iter().chain(traces) {
            assert!(
                r.right() <= tile.right() + 1.0 && r.bottom() <= tile.bottom() + 1.0,
                "{r:?} runs past the replay tile {tile:?} in {w}×{hgt}"
            );
        }
    }
}
