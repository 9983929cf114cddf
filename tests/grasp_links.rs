//! From every number to the grasps behind it, on the bundled samples: confusion cells hold
//! exactly the grasps with their true and predicted labels (as many as the map counts),
//! basis images list the grasps whose codes use the basis, strongest first, each grasp's
//! code reconstructs its patch and its decision value agrees with its prediction, and the
//! contingency cells partition the grasps. The bars come from the session's own labels, an
//! independent coding of the patches and the counts the experiments keep.

mod common;

use tactile_workbench::experiments::clustering::report::clustering_report;
use tactile_workbench::experiments::clustering::{
    ClusteringParams, UnsupervisedLearner, run_clustering,
};
use tactile_workbench::experiments::figure_id::FigureId;
use tactile_workbench::experiments::recognition::report::recognition_report;
use tactile_workbench::experiments::recognition::{
    RecognitionParams, SupervisedLearner, run_recognition,
};
use tactile_workbench::experiments::result::{AnalysisResult, GraspLinks};
use tactile_workbench::experiments::stability::report::stability_report;
use tactile_workbench::experiments::stability::{
    self, Config, DataOptions, PipelineSettings, StabilityData, StabilityOptions, StabilityReport,
};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::figures::{FigureKind, Heatmap, ImageGrid};
use tactile_workbench::jobs::Progress;
use tactile_workbench::project::Project;
use tactile_workbench::session::Session;
use tactile_workbench::sparse::DictionaryParams;
use tactile_workbench::svm::CvResult;

fn heatmap(r: &AnalysisResult, name: FigureId) -> &Heatmap {
    let f = r.figure(name).unwrap();
    let FigureKind::Heatmap(h) = &f.kind else {
        panic!("{name} is a heatmap");
    };
    h
}

fn images(r: &AnalysisResult, name: FigureId) -> &ImageGrid {
    let f = r.figure(name).unwrap();
    let FigureKind::ImageGrid(g) = &f.kind else {
        panic!("{name} is an image grid");
    };
    g
}

/// The class name of every grasp of `session` under label set `set`, read from the session.
fn class_names(session: &Session, set: &str) -> Vec<String> {
    let i = session.label_set(set).unwrap();
    let classes = &session.label_sets[i].classes;
    session
        .grasps
        .iter()
        .map(|g| classes[g.labels[i]].clone())
        .collect()
}

/// Every grasp listed once at most, across the items of `links`.
fn listed_once(links: &GraspLinks) -> Vec<usize> {
    let mut all: Vec<usize> = links
        .items
        .iter()
        .flat_map(|i| i.grasps.iter().copied())
        .collect();
    all.sort_unstable();
    let n = all.len();
    all.dedup();
    assert_eq!(all.len(), n, "{}: a grasp is listed twice", links.figure);
    all
}

fn stability_run() -> (Session, StabilityData, StabilityReport, AnalysisResult) {
    let session =
        tactile_workbench::session::open(&common::sample("grasp-stability.json")).unwrap();
    let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
    let opts = StabilityOptions {
        settings: PipelineSettings {
            dictionary: DictionaryParams {
                max_iter: 30,
                ..Default::default()
            },
            ..Default::default()
        },
        single: Config {
            num_bases: 12,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    };
    let r = stability::run(&data, &opts, &Progress::new()).unwrap();
    let result = stability_report(&r);
    (session, data, r, result)
}

fn check_confusion(
    result: &AnalysisResult,
    name: FigureId,
    cv: &CvResult,
    truth: &[String],
    ok: &str,
    bad: &str,
) {
    let h = heatmap(result, name);
    let links = result.links_of(name, None).unwrap();
    let n = truth.len();
    assert_eq!(listed_once(links), (0..n).collect::<Vec<_>>());
    for item in &links.items {
        let [row, col] = item.at;
        for &g in &item.grasps {
            assert_eq!(
                truth[g], h.rows[row],
                "{name} {:?}: grasp {g}'s truth",
                item.at
            );
            let predicted = if cv.predictions[g] { bad } else { ok };
            assert_eq!(
                predicted, h.columns[col],
                "{name} {:?}: grasp {g}'s prediction",
                item.at
            );
        }
        // The map shows the cell's share of its row; the counts come from the pooled
        // confusion of the cross validation.
        let row_total: usize = cv.confusion.matrix[row].iter().sum();
        assert_eq!(
            item.grasps.len(),
            cv.confusion.matrix[row][col],
            "{name} {:?}",
            item.at
        );
        let share = item.grasps.len() as f64 / row_total as f64;
        assert!(
            (h.values[row][col] - share).abs() < 1e-12,
            "{name} {:?}",
            item.at
        );
        assert!(
            item.text.contains(&format!("{} grasp", item.grasps.len())),
            "{}",
            item.text
        );
    }
}

#[test]
fn stability_numbers_lead_to_their_grasps() {
    let (session, data, r, result) = stability_run();
    let n = session.grasps.len();
    let truth = class_names(&session, &r.label_set);
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    check_confusion(
        &result,
        FigureId::ConfusionKfold,
        &r.parsimonious.kfold,
        &truth,
        ok,
        bad,
    );
    check_confusion(
        &result,
        FigureId::ConfusionObjects,
        &r.parsimonious.objects,
        &truth,
        ok,
        bad,
    );

    // Codes made here, independently of the report, with the model's dictionary.
    let dict = &r.model.dictionary;
    let s = data.sensor_count();
    let codes = dict
        .encode(data.x.view(), r.parsimonious.config.gamma)
        .unwrap();
    let strength = |g: usize, b: usize| {
        (0..s)
            .map(|sn| codes[[g * s + sn, b]].abs())
            .fold(0.0, f64::max)
    };
    for name in [FigureId::BasesRaw, FigureId::BasesFiltered] {
        let grid = images(&result, name);
        let links = result.links_of(name, None).unwrap();
        assert!(!links.items.is_empty());
        for item in &links.items {
            let caption = &grid.images[item.at[0]].caption;
            let b: usize = caption
                .strip_prefix("basis ")
                .unwrap()
                .parse::<usize>()
                .unwrap()
                - 1;
            assert_eq!(item.at[1], 0);
            let users: Vec<usize> = (0..n).filter(|&g| strength(g, b) > 0.0).collect();
            let mut listed = item.grasps.clone();
            listed.sort_unstable();
            assert_eq!(listed, users, "{name} {caption}: the grasps using it");
            for w in item.grasps.windows(2) {
                assert!(
                    strength(w[0], b) >= strength(w[1], b),
                    "{name} {caption}: order"
                );
            }
            assert_eq!(
                item.text,
                format!("{caption}: {} grasps use it", users.len())
            );
        }
    }

    // Every grasp's code: its patches, a reconstruction that is the sum of its terms, and a
    // decision value whose sign is its prediction.
    assert_eq!(result.grasp_codes.len(), n);
    for g in 0..n {
        let c = result.grasp_code(g).unwrap();
        assert_eq!(c.truth, truth[g]);
        let predicted = r.parsimonious.kfold.predictions[g];
        assert_eq!(c.predicted, if predicted { bad } else { ok });
        assert_eq!(
            c.decision > 0.0,
            c.predicted == bad,
            "grasp {g}: decision {}",
            c.decision
        );
        assert_eq!(c.patches.len(), s);
        for (sn, p) in c.patches.iter().enumerate() {
            assert_eq!(p.sensor, sn);
            assert_eq!(p.patch, data.x.row(g * s + sn).to_vec());
            let mut sum = vec![0.0; p.patch.len()];
            for &(b, coef) in &p.terms {
                assert_eq!(coef, codes[[g * s + sn, b]]);
                for (v, a) in sum.iter_mut().zip(&r.analyses.basis_images[b].values) {
                    *v += coef * a;
                }
            }
            let used = (0..dict.num_bases())
                .filter(|&b| codes[[g * s + sn, b]] != 0.0)
                .count();
            assert_eq!(p.terms.len(), used);
            for w in p.terms.windows(2) {
                assert!(w[0].1.abs() >= w[1].1.abs());
            }
            for (a, b) in sum.iter().zip(&p.reconstruction) {
                assert!((a - b).abs() < 1e-9, "grasp {g} sensor {sn}: {a} vs {b}");
            }
        }
    }

    // A saved project keeps the links and codes.
    let dir = common::temp_dir("grasp-links");
    let path = dir.join("p.json");
    Project::new(vec!["sample".into()], vec![result.clone()])
        .save(&path)
        .unwrap();
    let back = Project::load(&path).unwrap();
    assert_eq!(back.results[0].links, result.links);
    assert_eq!(back.results[0].grasp_codes, result.grasp_codes);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn recognition_confusion_cells_lead_to_their_grasps() {
    let session =
        tactile_workbench::session::open(&common::sample("object-recognition.json")).unwrap();
    let params = RecognitionParams {
        learner: SupervisedLearner::Ds,
        features: FeatureSet::MOMENTS,
        reps: 2,
        seed: 5,
        ..Default::default()
    };
    let r = run_recognition(&session, &params, &Progress::new()).unwrap();
    let result = recognition_report(&session.meta.name, &r);
    let truth = class_names(&session, &params.label_set);
    let h = heatmap(&result, FigureId::Confusion);
    let links = result.links_of(FigureId::Confusion, None).unwrap();
    listed_once_per_row(links);
    let mut cells = 0;
    for item in &links.items {
        let [row, col] = item.at;
        // How often each listed grasp was predicted into this cell, over the repetitions.
        let times: Vec<usize> = item
            .grasps
            .iter()
            .map(|&g| {
                r.repetitions
                    .iter()
                    .flat_map(|rep| &rep.predictions)
                    .filter(|p| p.grasp == g && p.truth == row && p.predicted == col)
                    .count()
            })
            .collect();
        for (&g, &t) in item.grasps.iter().zip(&times) {
            assert_eq!(truth[g], h.rows[row], "{:?}: grasp {g}'s truth", item.at);
            assert!(
                t > 0,
                "{:?}: grasp {g} was never predicted {}",
                item.at,
                h.columns[col]
            );
        }
        assert!(
            times.windows(2).all(|w| w[0] >= w[1]),
            "most frequent first"
        );
        // The experiment's own counts and the map's shares.
        let count: usize = times.iter().sum();
        assert_eq!(count, r.summary.confusion[row][col], "{:?}", item.at);
        let row_total: usize = r.summary.confusion[row].iter().sum();
        assert!((h.values[row][col] - count as f64 / row_total as f64).abs() < 1e-12);
        cells += 1;
    }
    let nonzero = r
        .summary
        .confusion
        .iter()
        .flatten()
        .filter(|&&c| c > 0)
        .count();
    assert_eq!(cells, nonzero, "every counted cell has its grasps");
}

/// A grasp belongs to one true class: it appears in one row of the confusion only.
fn listed_once_per_row(links: &GraspLinks) {
    for a in &links.items {
        for b in &links.items {
            if a.at[0] != b.at[0] {
                assert!(a.grasps.iter().all(|g| !b.grasps.contains(g)));
            }
        }
        let mut g = a.grasps.clone();
        g.sort_unstable();
        g.dedup();
        assert_eq!(g.len(), a.grasps.len(), "no duplicates");
    }
}

#[test]
fn contingency_cells_partition_the_grasps() {
    let session =
        tactile_workbench::session::open(&common::sample("object-recognition.json")).unwrap();
    let params = ClusteringParams {
        learner: UnsupervisedLearner::Du,
        features: FeatureSet::MOMENTS,
        thresholds: vec![0.4, 0.7],
        reps: 1,
        baseline_max_k: 0,
        ..ClusteringParams::default()
    };
    let r = run_clustering(&session, &params, &Progress::new()).unwrap();
    let result = clustering_report(&session.meta.name, &r);
    let truth = class_names(&session, &params.label_set);
    let n = session.grasps.len();
    let details = result.details_of(FigureId::ScoresVsThreshold).unwrap();
    assert_eq!(details.items.len(), 2);
    for (i, (threshold, f)) in details.items.iter().enumerate() {
        let FigureKind::Heatmap(h) = &f.kind else {
            panic!("a heatmap");
        };
        let run = r
            .runs
            .iter()
            .find(|x| x.threshold == *threshold && x.rep == 0)
            .unwrap();
        let assignment = run.assignment.as_ref().unwrap();
        let links = result
            .links_of(FigureId::ScoresVsThreshold, Some(i))
            .unwrap();
        assert_eq!(
            listed_once(links),
            (0..n).collect::<Vec<_>>(),
            "a partition"
        );
        for item in &links.items {
            let [row, col] = item.at;
            for &g in &item.grasps {
                assert_eq!(truth[g], h.rows[row]);
                assert_eq!(
                    (assignment[g] + 1).to_string(),
                    h.columns[col],
                    "grasp {g}'s cluster"
                );
            }
            assert_eq!(item.grasps.len() as f64, h.values[row][col]);
        }
    }
    assert!(
        result
            .links_of(FigureId::ScoresVsThreshold, Some(2))
            .is_none()
    );
}
