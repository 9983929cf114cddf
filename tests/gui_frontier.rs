//! The Speed vs accuracy view's frontiers: a frontier computed from the form becomes the
//! model size the Recognition view uses by default (and its result says so); clicking a
//! size on the frontier chart trains that model, and clicking it again opens the result.
#![cfg(feature = "gui")]

mod common;

use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::{View, WorkbenchApp, figure_view};
use tactile_workbench::experiments::frontier::report::frontier_figures;
use tactile_workbench::experiments::frontier::{self, Frontier, FrontierParams};
use tactile_workbench::experiments::result::{AnalysisResult, SizeReason};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::figures::FigureKind;

fn wait_for_jobs(h: &mut Harness<'static, WorkbenchApp>) {
    common::gui::wait_for_jobs(h, Duration::from_secs(300));
}

/// Click the marker of size `k` of frontier `f` of `frontiers` (the active session's, in
/// order) on the prediction-time chart, where the frontier pane drew it in the last frame.
fn click_size(
    h: &mut Harness<'static, WorkbenchApp>,
    frontiers: &[Frontier],
    f: usize,
    k: usize,
    says: &str,
) {
    h.get_by_label("prediction time per step or sample").click();
    h.run_ok();
    let figs = frontier_figures(frontiers);
    let (_, fig) = figs
        .iter()
        .find(|(name, _)| name == "frontier-prediction")
        .expect("a prediction-time frontier");
    let FigureKind::Chart(chart) = &fig.kind else {
        panic!("the frontier is a chart");
    };
    let series = chart
        .series
        .iter()
        .position(|s| s.name == frontiers[f].short_label())
        .expect("the frontier's line");
    let pos = figure_view::marker_position(&h.ctx, "frontier", chart, series, k)
        .expect("the frontier chart was drawn");
    h.hover_at(pos);
    h.run_ok();
    // The pane tells what is under the pointer before it is clicked.
    h.get_by_label_contains(says);
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_ok();
}

/// Choose `method` (its title) in the frontier form.
fn choose_method(h: &mut Harness<'static, WorkbenchApp>, method: &str) {
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Frontier method")
        .click();
    h.run_ok();
    // The list scrolls: the registry's methods come last.
    h.get_by_label(method).scroll_to_me();
    h.run_ok();
    h.get_by_label(method).click();
    h.run_ok();
    assert_eq!(h.state().rooms.speed.frontier.method.title(), method);
}

/// Set the frontier form to `method` (its first method: DS) with the knob lists `knobs`
/// (field label, text), two repetitions, and compute it.
fn compute_frontier(
    h: &mut Harness<'static, WorkbenchApp>,
    method: Option<&str>,
    knobs: &[(&str, &str)],
) {
    if let Some(method) = method {
        choose_method(h, method);
    }
    for (field, text) in knobs {
        h.get_by_label(field).set_text_value_accesskit(text);
        h.run_ok();
    }
    h.get_by_label("frontier repetitions")
        .set_value_accesskit(2.0);
    h.run_ok();
    h.get_by_label("Compute frontier").click();
    h.step();
    wait_for_jobs(h);
}

/// The results so far, asserting there are `n` of them (the app's messages say why not).
fn results_now<'h>(h: &'h Harness<'static, WorkbenchApp>, n: usize) -> &'h [AnalysisResult] {
    let results = &h.state().analyses.results;
    assert_eq!(
        results.len(),
        n,
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
    results
}

#[test]
fn a_frontier_sets_the_default_size_and_its_points_train_and_open_models() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    assert_eq!(h.state().view, View::SpeedAccuracy);
    h.get_by_label_contains("No frontier for «Simulated object recognition» yet");

    // DS on all features (the form's default method), four sizes, two repetitions.
    compute_frontier(&mut h, None, &[("capacities", "5, 20"), ("taus", "1, 5")]);
    let frontier = h
        .state()
        .analyses
        .frontiers
        .first()
        .unwrap_or_else(|| panic!("messages: {:?}", h.state().analyses.notes.texts()))
        .clone();
    assert_eq!(frontier.points.len(), 4);
    let rec = &frontier.points[frontier.recommended];
    let (capacity, tau) = (rec.knob("capacity").unwrap(), rec.knob("tau").unwrap());
    h.get_by_label_contains("Recommended DS, all features: capacity");

    // The Recognition view, on the frontier's features (its default is `auto`, which a
    // frontier on `all` does not speak for), now trains the recommended size by default,
    // and says so.
    h.state_mut().rooms.recognition.form.features = FeatureSet::ALL;
    h.get_by_label("Recognition").click();
    h.run_ok();
    h.get_by_label("Model size (recommended):");
    h.get_by_label_contains(&format!(
        "Run: DS on all features, capacity {capacity}, tau {tau} (recommended)"
    ));
    assert_eq!(
        h.get_by_label("capacity").value().as_deref(),
        Some(format!("capacity {capacity}").as_str())
    );
    assert_eq!(
        h.get_by_label("tau").value().as_deref(),
        Some(format!("tau {tau}").as_str())
    );

    // A size that is not the recommended one, clicked on the chart, is trained in its view.
    let other = (0..frontier.points.len())
        .find(|&k| k != frontier.recommended)
        .unwrap();
    let p = &frontier.points[other];
    let knobs = format!(
        "capacity {}, tau {}",
        p.knob("capacity").unwrap(),
        p.knob("tau").unwrap()
    );
    let frontiers = std::slice::from_ref(&frontier);
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    click_size(&mut h, frontiers, 0, other, "click to open or train");
    assert_eq!(h.state().view, View::Recognition);
    wait_for_jobs(&mut h);
    let results = results_now(&h, 1);
    let size = results[0].model_size.clone().expect("a recognition size");
    assert_eq!(size.knobs, knobs);
    assert_eq!(size.reason, SizeReason::User);
    assert!(results[0].label.starts_with("DS"), "{}", results[0].label);

    // Clicking that size again opens the model rather than training it twice.
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    click_size(&mut h, frontiers, 0, other, "click to open or train");
    wait_for_jobs(&mut h);
    assert_eq!(h.state().view, View::Recognition);
    assert_eq!(h.state().analyses.results.len(), 1);
}

/// A clusterer's size (a GU novelty threshold) clicked on its frontier is trained in the
/// Clustering view at that threshold; once a sweep holds it, a click opens the sweep with
/// the marker at that threshold. A k-means size is run by the Baselines view with that k.
#[test]
fn clusterer_sizes_train_in_their_views() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    compute_frontier(&mut h, Some("GU"), &[("novelty thresholds", "0.05, 0.1")]);
    let frontiers = h.state().analyses.frontiers.clone();
    assert_eq!(
        frontiers.len(),
        1,
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
    let threshold = frontiers[0].points[1].knob("threshold").unwrap();
    assert_eq!(threshold, 0.1);

    click_size(&mut h, &frontiers, 0, 1, "click to open or train");
    assert_eq!(h.state().view, View::Clustering);
    wait_for_jobs(&mut h);
    let results = results_now(&h, 1);
    assert_eq!(results[0].parameters["learner"], "GU");
    let details = &results[0].details;
    assert!(!details.is_empty());
    for d in details {
        let keys: Vec<f64> = d.items.iter().map(|(t, _)| *t).collect();
        assert_eq!(
            keys,
            [0.1],
            "{} is trained at the threshold clicked alone",
            d.figure
        );
    }

    // A sweep over both thresholds in the Clustering view; a size clicked then opens it,
    // with the marker at that threshold rather than at the one chosen without labels.
    h.get_by_label("from").set_value_accesskit(0.05);
    h.run_ok();
    h.get_by_label("to").set_value_accesskit(0.1);
    h.run_ok();
    h.get_by_label("step").set_value_accesskit(0.05);
    h.run_ok();
    h.get_by_label("Run").click();
    h.step();
    wait_for_jobs(&mut h);
    results_now(&h, 2);
    let chosen = h.state().analyses.results[1]
        .score("threshold chosen without labels")
        .expect("a label-free choice");
    let k = frontiers[0]
        .points
        .iter()
        .position(|p| p.knob("threshold") != Some(chosen))
        .unwrap();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    click_size(&mut h, &frontiers, 0, k, "click to open or train");
    wait_for_jobs(&mut h);
    assert_eq!(h.state().view, View::Clustering);
    assert_eq!(
        h.state().analyses.results.len(),
        2,
        "opened, not trained again"
    );
    let marked = &h.state().analyses.selected;
    for d in &h.state().analyses.results[1].details {
        assert_eq!(marked.get(&(1, d.figure)), Some(&k), "{}", d.figure);
    }

    // k-means sizes: the Baselines view runs the one clicked (its SVM left out here).
    h.get_by_label("Baselines").click();
    h.run_ok();
    h.get_by_label("RBF SVM (5-fold)").click();
    h.run_ok();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    compute_frontier(
        &mut h,
        Some("k-means"),
        &[("numbers of clusters k", "4, 7")],
    );
    let frontiers = h.state().analyses.frontiers.clone();
    assert_eq!(frontiers.len(), 2);
    let kmeans = frontiers
        .iter()
        .position(|f| f.short_label().starts_with("k-means"))
        .expect("the k-means frontier");
    click_size(&mut h, &frontiers, kmeans, 1, "click to open or train");
    assert_eq!(h.state().view, View::Baselines);
    wait_for_jobs(&mut h);
    let results = results_now(&h, 3);
    assert_eq!(results[2].parameters["k"], "7");
}

/// One knob field of a method's frontier form: its label, the values it shows at first, a
/// list typed into it and where the parameters must hold that list.
struct KnobField {
    label: &'static str,
    default: &'static str,
    typed: &'static str,
    values: &'static [f64],
    param: fn(&FrontierParams) -> Vec<f64>,
}

fn counts(v: &[usize]) -> Vec<f64> {
    v.iter().map(|&v| v as f64).collect()
}

/// Knob `k` of a registered method's sizes.
fn knob_of_sizes(p: &FrontierParams, k: usize) -> Vec<f64> {
    FrontierParams::lists_of_sizes(&p.sizes)[k].clone()
}

/// Every method's knob fields as the form must show them: the labels it has always shown,
/// each method's own default values (DU's thresholds: its own list, not GU's).
fn knob_fields() -> Vec<(&'static str, Vec<KnobField>)> {
    let capacities = || KnobField {
        label: "capacities",
        default: "2, 5, 10, 20, 50, 100",
        typed: "3, 7",
        values: &[3.0, 7.0],
        param: |p| counts(&p.capacities),
    };
    let taus = || KnobField {
        label: "taus",
        default: "1, 2, 5, 15, 30",
        typed: "4",
        values: &[4.0],
        param: |p| counts(&p.taus),
    };
    let ks = || KnobField {
        label: "numbers of clusters k",
        default: "2, 4, 6, 8, 10, 12, 16, 20",
        typed: "3 5",
        values: &[3.0, 5.0],
        param: |p| counts(&p.ks),
    };
    vec![
        (
            "sparse coding + SVM",
            vec![KnobField {
                label: "numbers of bases (each with its best β, γ)",
                default: "2, 3, 5, 10, 15, 20, 29, 40, 60",
                typed: "4, 8",
                values: &[4.0, 8.0],
                param: |p| counts(&p.num_bases),
            }],
        ),
        ("DS", vec![capacities(), taus()]),
        ("GS", vec![capacities(), taus()]),
        (
            "DU",
            vec![KnobField {
                label: "novelty thresholds",
                default: "0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8",
                typed: "0.35, 0.45",
                values: &[0.35, 0.45],
                param: |p| p.thresholds.clone(),
            }],
        ),
        (
            "GU",
            vec![KnobField {
                label: "novelty thresholds",
                default: "0.05, 0.08, 0.1, 0.12, 0.15, 0.2, 0.3",
                typed: "0.07",
                values: &[0.07],
                param: |p| p.thresholds.clone(),
            }],
        ),
        ("k-means", vec![ks()]),
        ("SOM", vec![ks()]),
        (
            "RBF SVM",
            vec![
                KnobField {
                    label: "penalties C",
                    default: "1, 10, 100, 1000",
                    typed: "5, 50",
                    values: &[5.0, 50.0],
                    param: |p| p.svm_c.clone(),
                },
                KnobField {
                    label: "kernel widths γ",
                    default: "0.001, 0.003, 0.01, 0.03, 0.1",
                    typed: "0.02",
                    values: &[0.02],
                    param: |p| p.svm_gamma.clone(),
                },
            ],
        ),
        (
            "temporal-feature SVM",
            vec![KnobField {
                label: "c: box constraint of each one-vs-rest machine",
                default: "0.01, 0.1, 1, 10, 100",
                typed: "0.5, 2",
                values: &[0.5, 2.0],
                param: |p| knob_of_sizes(p, 0),
            }],
        ),
        (
            "DTW k-NN",
            vec![
                KnobField {
                    label: "k: neighbours that vote",
                    default: "1, 3, 5",
                    typed: "1, 7",
                    values: &[1.0, 7.0],
                    param: |p| knob_of_sizes(p, 0),
                },
                KnobField {
                    label: "band: Sakoe–Chiba band: steps a path may stray from the diagonal",
                    default: "0, 5, 15",
                    typed: "2",
                    values: &[2.0],
                    param: |p| knob_of_sizes(p, 1),
                },
            ],
        ),
    ]
}

/// Every frontier method's form has a field for each of its knobs, with the method's own
/// values, and a list typed there reaches that knob's parameters (what Compute frontier
/// runs); a list that is not numbers, or that the method refuses, is named under the form.
#[test]
fn every_methods_knob_fields_reach_their_parameters() {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    let fields = knob_fields();
    let titles: Vec<&str> = fields.iter().map(|(m, _)| *m).collect();
    let offered: Vec<&str> = frontier::methods().map(|m| m.title()).collect();
    assert_eq!(titles, offered, "a knob table for every frontier method");
    for (method, knobs) in &fields {
        choose_method(&mut h, method);
        let form = &h.state().rooms.speed.frontier;
        assert_eq!(
            frontier::size_knobs(form.method).len(),
            knobs.len(),
            "{method}'s fields"
        );
        for k in knobs {
            assert_eq!(
                h.get_by_label(k.label).value().as_deref(),
                Some(k.default),
                "{method}: {}",
                k.label
            );
            h.get_by_label(k.label).set_text_value_accesskit(k.typed);
            h.run_ok();
        }
        let p = h.state().rooms.speed.frontier.params();
        let p = p.unwrap_or_else(|e| panic!("{method}: {e}"));
        for k in knobs {
            assert_eq!((k.param)(&p), k.values, "{method}: {}", k.label);
        }
    }

    // Typed values stay with their method; bad ones are named under the form.
    choose_method(&mut h, "DS");
    assert_eq!(
        h.get_by_label("capacities").value().as_deref(),
        Some("3, 7")
    );
    for (typed, says) in [
        ("5, 2.5", "capacities: `5, 2.5` is not a list of numbers"),
        (" ,", "capacities: give at least one value"),
        (
            "0, 5",
            "invalid parameter `capacities`: capacity and tau must be ≥ 1",
        ),
    ] {
        h.get_by_label("capacities").set_text_value_accesskit(typed);
        h.run_ok();
        h.get_by_label(says);
    }
    choose_method(&mut h, "GU");
    h.get_by_label("novelty thresholds")
        .set_text_value_accesskit("0.1, 1.5");
    h.run_ok();
    h.get_by_label("invalid parameter `thresholds`: 1.5 is not in [0, 1]");
}
