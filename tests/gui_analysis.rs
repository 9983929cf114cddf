//! The analysis views: a job starts from a view, shows progress, can be cancelled, and its
//! result's figures and numbers appear (found by accessible label). The project file's
//! round trip is tested in `experiments::report`.
#![cfg(feature = "gui")]

mod common;

use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use tactile_workbench::app::views::number;
use tactile_workbench::app::{View, WorkbenchApp};
use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::figure_id::FigureId;
use tactile_workbench::figures::FigureKind;

fn harness() -> Harness<'static, WorkbenchApp> {
    let mut h = common::gui::workbench(1400.0, 1000.0);
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    h
}

use common::gui::wait_for_jobs;

/// Press Run, see the job running in the background, and wait for it (bounded).
fn run_job(h: &mut Harness<'static, WorkbenchApp>) {
    h.get_by_label("Run").click();
    h.step();
    h.step();
    assert!(h.state().analyses.busy());
    wait_for_jobs(h, Duration::from_secs(300));
}

/// The app holds `n` results; otherwise the jobs' messages say why.
fn assert_result_count(h: &Harness<'static, WorkbenchApp>, n: usize) {
    assert_eq!(
        h.state().analyses.results.len(),
        n,
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
}

#[test]
fn baselines_run_in_the_background_and_show_their_figures() {
    let mut h = harness();
    h.get_by_label("Baselines").click();
    h.run_ok();
    h.get_by_label_contains("No results yet");
    h.get_by_label("orders").set_value_accesskit(2.0);
    h.run_ok();
    h.get_by_label("RBF SVM (5-fold)").click();
    h.run_ok();
    assert_eq!(h.state().rooms.baselines.form.orders, 2);
    assert!(!h.state().rooms.baselines.form.with_svm);
    h.get_by_label("Run").click();
    h.step();
    h.step();
    assert!(h.state().analyses.busy(), "the job runs in the background");
    h.get_by_label("Cancel");
    wait_for_jobs(&mut h, Duration::from_secs(120));
    assert!(!h.state().analyses.busy());
    assert_result_count(&h, 1);
    h.get_by_label("Clustering scores at k = 10");
    h.get_by_label("NMI against effective clusters");
    h.get_by_label("All numbers").click();
    h.run_ok();
    h.get_by_label("k-means NMI");
    let nmi = h.state().analyses.results[0].score("k-means NMI").unwrap();
    h.get_by_label(&format!("{nmi:.4}"));
    assert!((0.0..=1.0).contains(&nmi));

    // The result appears on the speed-against-accuracy chart.
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    assert_eq!(h.state().view, View::SpeedAccuracy);
    // The pane's heading, and the chart of one score of one session.
    h.get_by_label("Speed against accuracy");
    h.get_by_label_contains("Speed against accuracy · ");
    h.get_by_label("Models").click();
    h.run_ok();
    h.get_by_label_contains("baselines, k = 10 ·");

    // File > Export all figures writes every figure and an index, and says how long it took.
    let dir = common::temp_dir("gui-export-all");
    h.state_mut().analyses.export.dir = dir.to_path_buf();
    // The size presets: a page width, then back to the column (the default).
    h.get_by_label("Export settings").click();
    h.run_ok();
    h.get_by_label("Page width (7 in, 300 DPI)").click();
    h.run_ok();
    assert_eq!(h.state().analyses.export.width, 2100);
    h.get_by_label("Column (3.5 in, 300 DPI)").click();
    h.run_ok();
    assert_eq!(
        (
            h.state().analyses.export.width,
            h.state().analyses.export.dpi
        ),
        (1050, 300.0)
    );
    h.get_by_label("File").click();
    h.run_ok();
    h.get_by_label("Export all figures").click();
    h.run_ok();
    // The first export asks for the folder (the data folder's exports by default), then
    // goes ahead; later exports do not ask again.
    h.get_by_label("Export to which folder?");
    assert!(h.state().analyses.jobs.is_empty(), "exported before asking");
    h.get_by_label("Export here").click();
    h.step();
    assert!(h.state().analyses.export.chosen);
    wait_for_jobs(&mut h, Duration::from_secs(60));
    let message = h
        .state()
        .analyses
        .notes
        .texts()
        .last()
        .cloned()
        .unwrap_or_default();
    assert!(
        message.starts_with("exported ") && message.ends_with(" s"),
        "{message}"
    );
    let index = std::fs::read_to_string(dir.join("index.md")).unwrap();
    assert!(index.contains("NMI against effective clusters"), "{index}");
    assert!(index.contains("Speed against accuracy"), "{index}");
    // Every figure as vector PDF too, and the PNGs at the column preset's width.
    let files: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    let with = |ext: &str| {
        files
            .iter()
            .filter(|p| p.extension().is_some_and(|e| e == ext))
            .count()
    };
    assert!(with("png") > 0 && with("pdf") == with("png"), "{files:?}");
    let png = files
        .iter()
        .find(|p| p.extension().is_some_and(|e| e == "png"))
        .unwrap();
    let bytes = std::fs::read(png).unwrap();
    let width = u32::from_be_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]);
    assert_eq!(width, 1050, "{}", png.display());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_cancelled_job_leaves_the_app_usable() {
    let mut h = harness();
    h.get_by_label("Baselines").click();
    h.run_ok();
    h.get_by_label("orders").set_value_accesskit(200.0);
    h.run_ok();
    assert_eq!(h.state().rooms.baselines.form.orders, 200);
    h.get_by_label("Run").click();
    h.step();
    std::thread::sleep(Duration::from_millis(100));
    h.step();
    h.get_by_label("Cancel").click();
    // 200 orders take minutes: the job ends long before, cancelled (the wait only guards
    // against a hang).
    wait_for_jobs(&mut h, Duration::from_secs(120));
    assert!(!h.state().analyses.busy());
    assert!(h.state().analyses.results.is_empty());
    h.get_by_label_contains("cancelled");
    // The replay still works.
    h.get_by_label("Replay").click();
    h.run_ok();
    assert_eq!(h.state().view, View::Replay);
    // (The session's first grasp, sponge #1, is focused since the session was chosen.)
    h.get_by_label_contains("sponge #2 ·").click();
    h.run_ok();
    assert_eq!(h.state().selection.focus, Some((1, 1)));
    h.get_by_label_contains("key frame (full contact)");
}

#[test]
fn recognition_and_clustering_views_show_the_papers_figures() {
    let mut h = harness();
    h.get_by_label("Recognition").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(1.0);
    h.run_ok();
    assert_eq!(h.state().rooms.recognition.form.reps, 1);
    run_job(&mut h);
    assert_result_count(&h, 1);
    for title in [
        "Accuracy as trials progress",
        "Confusion matrix",
        "Early classification",
    ] {
        assert!(h.query_all_by_label(title).count() >= 1, "{title}");
    }
    h.get_by_label("All numbers").click();
    h.run_ok();
    let acc = h.state().analyses.results[0]
        .score("accuracy (final 20%)")
        .unwrap();
    h.get_by_label(&format!("{acc:.4}"));

    // The speed chart puts either training or prediction time on its axis.
    h.get_by_label("Speed vs accuracy").click();
    h.run_ok();
    h.get_by_label("prediction time per step or sample").click();
    h.run_ok();
    h.get_by_label_contains("Prediction speed against accuracy · ");

    h.get_by_label("Clustering").click();
    h.run_ok();
    h.get_by_label("repetitions").set_value_accesskit(1.0);
    h.get_by_label("from").set_value_accesskit(0.2);
    h.get_by_label("to").set_value_accesskit(0.4);
    h.get_by_label("step").set_value_accesskit(0.1);
    h.run_ok();
    assert_eq!(h.state().rooms.clustering.form.reps, 1);
    assert_eq!(
        h.state().rooms.clustering.form.threshold_list(),
        vec![0.2, 0.3, 0.4]
    );
    h.get_by_label("Run").click();
    h.step();
    h.step();
    wait_for_jobs(&mut h, Duration::from_secs(300));
    assert_result_count(&h, 2);
    h.get_by_label("Purity, ARI and NMI against the novelty threshold");
    h.get_by_label("Clusters against the novelty threshold");
    h.get_by_label("NMI vs effective").click();
    h.run_ok();
    h.get_by_label("NMI against effective clusters");

    // Each threshold's clustering counts every grasp once.
    let details = &h.state().analyses.results[1].details[0];
    let grasps = h
        .state()
        .sessions
        .iter()
        .map(|s| s.session.grasps.len() as f64)
        .find(|&n| {
            let tactile_workbench::figures::FigureKind::Heatmap(m) = &details.items[0].1.kind
            else {
                return false;
            };
            m.values.iter().flatten().sum::<f64>() == n
        })
        .expect("the contingency counts a session's grasps");
    assert_eq!(details.items.len(), 3);
    for (_, fig) in &details.items {
        let tactile_workbench::figures::FigureKind::Heatmap(m) = &fig.kind else {
            panic!("a contingency heatmap");
        };
        assert_eq!(m.values.iter().flatten().sum::<f64>(), grasps);
    }

    // The threshold marker shows the clustering at its threshold; the slider moves it.
    h.get_by_label("Scores vs threshold").click();
    h.run_ok();
    h.get_by_label("Clustering at novelty threshold 0.2");
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "novelty threshold")
        .focus();
    h.run_ok();
    h.key_press(egui::Key::ArrowRight);
    h.run_ok();
    h.get_by_label("Clustering at novelty threshold 0.3");
    assert!(
        h.query_by_label("Clustering at novelty threshold 0.2")
            .is_none()
    );

    // A class × cluster cell of the contingency selects exactly the grasps of that class the
    // first order put in that cluster.
    let r = h.state().analyses.results[1].clone();
    let item = r.details[0]
        .items
        .iter()
        .position(|(t, _)| *t == 0.3)
        .unwrap();
    let (label, row, col) = {
        let FigureKind::Heatmap(m) = &r.details[0].items[item].1.kind else {
            panic!("a contingency heatmap");
        };
        let (row, col) = (0..m.rows.len())
            .flat_map(|a| (0..m.columns.len()).map(move |b| (a, b)))
            .find(|&(a, b)| m.values[a][b] > 0.0)
            .expect("a non-empty cell");
        (cell_label(m, row, col), row, col)
    };
    let expected = r
        .links_of(FigureId::ScoresVsThreshold, Some(item))
        .and_then(|l| l.item([row, col]))
        .expect("the cell's grasps")
        .grasps
        .clone();
    h.get_by_label(&label).click();
    h.run_ok();
    let sel = &h.state().selection;
    assert_eq!(sel.grasps, expected);
    let session = &h.state().sessions[sel.session.unwrap()].session;
    let class = &r.details[0].items[item].1;
    let FigureKind::Heatmap(m) = &class.kind else {
        unreachable!()
    };
    let set = session.label_set("object").unwrap();
    for &g in &sel.grasps {
        let c = session.grasps[g].labels[set];
        assert_eq!(
            session.label_sets[set].classes[c], m.rows[row],
            "grasp {g} is of the row's class"
        );
    }
    h.get_by_label_contains(&format!("Selected: {} grasp", expected.len()));
}

/// The accessible name of a heatmap cell, as the figure view gives it.
fn cell_label(m: &tactile_workbench::figures::Heatmap, row: usize, col: usize) -> String {
    format!(
        "{} {} × {} {}",
        m.y.title, m.rows[row], m.x.title, m.columns[col]
    )
}

/// Choosing GU offers its own threshold range and the grasps that keep a cluster, and the
/// result says which it used.
#[test]
fn choosing_gu_offers_its_thresholds_and_cluster_confirmation() {
    let mut h = harness();
    h.get_by_label("Clustering").click();
    h.run_ok();
    assert_eq!(
        h.state().rooms.clustering.form.thresholds,
        [0.1, 0.95, 0.05]
    );
    assert!(h.query_by_label("grasps to keep a cluster:").is_none());
    h.get_by_role_and_label(egui::accesskit::Role::ComboBox, "Learner")
        .click();
    h.run_ok();
    h.get_by_label("GU (generative, EVT novelty)").click();
    h.run_ok();
    assert_eq!(
        h.state().rooms.clustering.form.thresholds,
        [0.02, 0.25, 0.01]
    );
    h.get_by_label("grasps to keep a cluster:");
    h.get_by_label("repetitions").set_value_accesskit(1.0);
    h.get_by_label("from").set_value_accesskit(0.02);
    h.get_by_label("to").set_value_accesskit(0.04);
    h.get_by_label("step").set_value_accesskit(0.02);
    h.get_by_label("grasps to keep a cluster:")
        .set_value_accesskit(2.0);
    h.run_ok();
    assert_eq!(
        h.state().rooms.clustering.form.threshold_list(),
        vec![0.02, 0.04]
    );
    assert_eq!(h.state().rooms.clustering.form.gu_min_grasps, 2);
    run_job(&mut h);
    assert_result_count(&h, 1);
    let label = &h.state().analyses.results[0].label;
    assert!(
        label.contains("GU") && label.contains("kept from 2 grasps"),
        "{label}"
    );
}

/// The grasp-stability sample in the Grasp stability view, its form set to 8 bases.
fn stability_form_at_8_bases() -> Harness<'static, WorkbenchApp> {
    let mut h = harness();
    h.get_by_label("Simulated grasp stability").click();
    h.run_ok();
    h.get_by_label("Grasp stability").click();
    h.run_ok();
    h.get_by_label("num_bases").set_value_accesskit(8.0);
    h.run_ok();
    h
}

#[test]
fn the_stability_form_puts_the_values_beside_the_codes() {
    let mut h = stability_form_at_8_bases();
    h.get_by_label("SVM reads the values beside the codes")
        .click();
    h.run_ok();
    run_job(&mut h);
    assert_result_count(&h, 1);
    let r = &h.state().analyses.results[0];
    assert!(r.label.ends_with(", codes+raw"), "{}", r.label);
    assert_eq!(r.parameters["inputs"], "codes+raw");
    // The run's model reads the values too: its SVM has a weight per code and per taxel.
    let model = h
        .state()
        .analyses
        .models
        .list
        .last()
        .expect("the run's model");
    let tactile_workbench::models::Model::Stability(c) = &model.file.model else {
        panic!("a stability model");
    };
    let taxels: usize = c.sensors.iter().map(|s| s.taxels).sum();
    let codes = c.codes.as_ref().expect("a sparse model");
    assert_eq!(
        c.svm.weights.len(),
        c.sensors.len() * codes.dictionary.num_bases() + taxels
    );
}

#[test]
fn stability_view_shows_the_first_papers_figures() {
    let mut h = stability_form_at_8_bases();
    assert_eq!(h.state().rooms.stability.form.num_bases, 8);
    run_job(&mut h);
    assert_result_count(&h, 1);
    // The basis images, the usage differential and a confusion map show at once; the rest
    // are a tab away.
    h.get_by_label("Basis images");
    h.get_by_label("Basis usage differential");
    h.get_by_label_contains("Confusion map, stratified 10-fold");
    for (tab, title) in [
        ("Basis usage", "Basis usage per label"),
        ("Coefficient differential", "Coefficient differential"),
        ("Reconstruction", "A patch and its reconstruction"),
    ] {
        // The tab strip may scroll in a narrow tile: ask for the tab by name.
        h.get_by_role_and_label(egui::accesskit::Role::Button, tab)
            .click_accesskit();
        h.run_ok();
        assert!(h.query_all_by_label(title).count() >= 1, "{title}");
    }
    h.get_by_label("All numbers").click();
    h.run_ok();
    let wsr = h.state().analyses.results[0]
        .score("weighted success rate (10-fold)")
        .unwrap();
    h.get_by_label(&format!("{wsr:.4}"));
    assert!(wsr > 0.6, "the sample's failures are learnable: {wsr}");

    // A click on a basis image shows that basis's usage by label in its own tile.
    h.get_by_label("Bases raw").click();
    h.run_ok();
    h.get_by_label_contains("Click a basis");
    h.get_all_by_label("show basis 3").next().unwrap().click();
    h.run_ok();
    h.get_by_label("Basis 3: usage by label");
    let usage = &h.state().analyses.results[0].details[0].items[2].1;
    assert_eq!(usage.title, "Basis 3: usage by label");
    // ... and selects the grasps whose codes use it, most first.
    let r = h.state().analyses.results[0].clone();
    let sel = h.state().selection.grasps.clone();
    assert!(!sel.is_empty(), "some grasps use basis 3");
    for &g in &sel {
        let code = r.grasp_code(g).unwrap();
        assert!(
            code.patches
                .iter()
                .any(|p| p.terms.iter().any(|t| t.0 == 2)),
            "grasp {g} uses basis 3"
        );
    }
    let uses = r
        .grasp_codes
        .iter()
        .filter(|c| c.patches.iter().any(|p| p.terms.iter().any(|t| t.0 == 2)))
        .count();
    assert_eq!(sel.len(), uses, "every grasp that uses it");

    // A confusion cell selects exactly its grasps (by the result's predictions), focuses the
    // first, and the focused grasp's tile shows its reconstruction and decision value.
    let FigureKind::Heatmap(m) = &r
        .figures
        .iter()
        .find(|(n, _)| *n == FigureId::ConfusionKfold)
        .unwrap()
        .1
        .kind
    else {
        panic!("a confusion heatmap");
    };
    let (truth, predicted) = (m.rows[1].clone(), m.columns[0].clone());
    let label = cell_label(m, 1, 0);
    let expected: Vec<usize> = r
        .grasp_codes
        .iter()
        .filter(|c| c.truth == truth && c.predicted == predicted)
        .map(|c| c.grasp)
        .collect();
    assert!(
        !expected.is_empty(),
        "some {truth} grasps are predicted {predicted}"
    );
    h.get_by_label(&label).click();
    h.run_ok();
    let mut got = h.state().selection.grasps.clone();
    got.sort_unstable();
    assert_eq!(got, expected);
    let (_, g) = h.state().selection.focus.unwrap();
    assert!(expected.contains(&g));
    let code = h.state().analyses.results[0].grasp_code(g).unwrap();
    h.get_by_label_contains(&format!(
        "decision value {:+.3} (> 0 predicts failure",
        code.decision
    ));
    h.get_by_label(&format!("predicted: {predicted}"));
    assert!(h.query_all_by_label_contains("reconstruction (").count() >= 1);
    h.get_by_label_contains("Selected: ");

    // The selection belongs to its session: choosing another session clears it, and the
    // focused grasp (the one every replay tile plays) moves to the new session.
    h.get_by_label("Simulated object recognition").click();
    h.run_ok();
    assert!(h.state().selection.grasps.is_empty());
    assert_eq!(h.state().selection.session, None);
    assert_eq!(h.state().selection.focus.map(|f| f.0), Some(1));
    assert!(h.query_by_label_contains("Selected: ").is_none());
}

#[test]
fn a_project_on_the_command_line_reopens_its_sessions_and_shows_its_results() {
    use tactile_workbench::experiments::result::{AnalysisKind, AnalysisResult};
    use tactile_workbench::figures::{Axis, Figure, Series};
    use tactile_workbench::project::Project;
    let session = tactile_workbench::session::open(&common::sample("grasp-stability.json"))
        .unwrap()
        .meta
        .name;
    let result = AnalysisResult {
        held_out: None,
        methods: Vec::new(),
        kind: AnalysisKind::Stability,
        label: "saved model".into(),
        session,
        parameters: Default::default(),
        scores: vec![("weighted success rate (10-fold)".into(), 0.8125)],
        headline: Some(("weighted success rate (10-fold)".into(), 0.8125)),
        train_seconds: 2.0,
        predict_seconds_per_sample: None,
        created: 0,
        figures: vec![(
            FigureId::Reconstruction,
            Figure::chart(
                "A saved curve",
                Axis::new("x", ""),
                Axis::new("y", ""),
                vec![Series::new("s", vec![1.0, 2.0], vec![0.5, 0.7])],
            ),
        )],
        details: Vec::new(),
        links: Vec::new(),
        grasp_codes: Vec::new(),
        model_size: None,
    };
    let dir = common::temp_dir("gui-project");
    let path = dir.join("saved.json");
    Project::new(
        vec![
            "sample: object-recognition.json".into(),
            "sample: grasp-stability.json".into(),
        ],
        vec![result],
    )
    .save(&path)
    .unwrap();
    let mut h = common::gui::workbench_opening(vec![path], 1200.0, 900.0);
    h.state_mut().view = View::Stability;
    for _ in 0..10 {
        h.step();
    }
    h.run_ok();
    assert_eq!(h.state().analyses.results.len(), 1);
    h.get_by_label("A saved curve");
    h.get_by_label("0.8125");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn robustness_view_sweeps_a_perturbation_and_charts_it() {
    use tactile_workbench::experiments::robustness::Perturbation;
    let mut h = harness();
    h.get_by_label("Simulated grasp stability").click();
    h.run_ok();
    h.get_by_label("Where methods fail").click();
    h.run_ok();
    // Only what the grasp-stability session supports is offered.
    h.get_by_label("sparse coding + SVM");
    assert!(h.query_by_label("DS").is_none());
    h.get_by_label("new-objects");
    // Only the raw SVM, under noise and truncation, once: ticked and unticked by label.
    let form = h.state().rooms.robustness.form.clone();
    let methods: Vec<MethodId> = MethodId::all()
        .filter(|m| h.query_by_label(m.title()).is_some())
        .collect();
    for &m in &methods {
        if form.methods.contains(&m) != (m == MethodId::RawSvm) {
            h.get_by_label(m.title()).click();
            h.run_ok();
        }
    }
    let wanted = [Perturbation::Noise, Perturbation::Truncation];
    let shown: Vec<Perturbation> = Perturbation::ALL
        .into_iter()
        .filter(|p| h.query_by_label(p.key()).is_some())
        .collect();
    for &p in &shown {
        if form.perturbations.contains(&p) != wanted.contains(&p) {
            h.get_by_label(p.key()).click();
            h.run_ok();
        }
    }
    h.get_by_label("repetitions").set_value_accesskit(1.0);
    h.run_ok();
    let form = &h.state().rooms.robustness.form;
    for m in methods {
        assert_eq!(form.methods.contains(&m), m == MethodId::RawSvm, "{m:?}");
    }
    for p in shown {
        assert_eq!(
            form.perturbations.contains(&p),
            wanted.contains(&p),
            "{p:?}"
        );
    }
    assert_eq!(form.reps, 1);
    run_job(&mut h);
    let r = h.state().analyses.results.last().expect("a result");
    assert!(
        r.label.starts_with("Robustness"),
        "messages: {:?}",
        h.state().analyses.notes.texts()
    );
    let clean = r
        .score("raw linear SVM: clean weighted success rate")
        .unwrap();
    h.get_by_label(&format!("{clean:.4}"));
    h.get_by_label("Robustness to noise");
    h.get_by_label("Robustness to truncation");
    // A click on a point of the noise chart chooses its strength and lists every method's
    // score there.
    let i = h.state().analyses.results.len() - 1;
    let r = h.state().analyses.results[i].clone();
    let (name, fig) = r
        .figures
        .iter()
        .find(|(_, f)| f.title == "Robustness to noise")
        .expect("the noise chart");
    let FigureKind::Chart(chart) = &fig.kind else {
        panic!("a chart");
    };
    let k = chart.series[0].x.len() - 1;
    let (x, y) = (chart.series[0].x[k], chart.series[0].y[k]);
    let heading = format!("At {} {}:", chart.x.title, number(x));
    assert!(h.query_by_label(&heading).is_none());
    let pos = tactile_workbench::app::figure_view::marker_position(
        &h.ctx,
        &format!("{i}-{name}"),
        chart,
        0,
        k,
    )
    .expect("the noise chart was drawn");
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_ok();
    let strength = h.state().selection.strength;
    assert_eq!(strength, Some((i, *name, x)));
    h.get_by_label(&heading);
    h.get_by_label(&format!("{} {}", chart.series[0].name, number(y)));
}
