//! The novelty threshold chosen without labels (agreement of the clusterings across random
//! orders) on the simulated recognition sample: 10 objects × 20 grasps.

mod common;

use tactile_workbench::cluster::normalized_mutual_info;
use tactile_workbench::experiments::clustering::report::clustering_report;
use tactile_workbench::experiments::clustering::{
    ClusteringParams, ClusteringResult, UnsupervisedLearner, run_clustering,
};
use tactile_workbench::experiments::figure_id::FigureId;
use tactile_workbench::figures::{FigureKind, Orientation};
use tactile_workbench::jobs::Progress;
use tactile_workbench::rng::Rng;
use tactile_workbench::session::Session;

fn sample() -> Session {
    tactile_workbench::session::open(&common::sample("object-recognition.json")).unwrap()
}

fn params() -> ClusteringParams {
    ClusteringParams {
        learner: UnsupervisedLearner::Gu,
        thresholds: vec![0.01, 0.02, 0.05, 0.1, 0.3],
        reps: 5,
        seed: 4,
        baseline_max_k: 0,
        ..ClusteringParams::default()
    }
}

fn run(session: &Session) -> ClusteringResult {
    run_clustering(session, &params(), &Progress::new()).unwrap()
}

/// The session with its object labels shuffled among the grasps.
fn shuffled_labels(session: &Session) -> Session {
    let mut s = session.clone();
    let set = s.label_set("object").unwrap();
    let order = Rng::new(77).permutation(s.grasps.len());
    let labels: Vec<usize> = order
        .iter()
        .map(|&g| session.grasps[g].labels[set])
        .collect();
    for (g, l) in s.grasps.iter_mut().zip(labels) {
        g.labels[set] = l;
    }
    s
}

/// Chance for NMI: the chosen first-order clustering against the labels shuffled at random
/// (mean over 20 shuffles); ARI is 0 by chance by construction.
fn chance_nmi(labels: &[usize], pred: &[usize]) -> f64 {
    (0..20)
        .map(|i| {
            let order = Rng::new(i).permutation(labels.len());
            let shuffled: Vec<usize> = order.iter().map(|&g| labels[g]).collect();
            normalized_mutual_info(&shuffled, pred)
        })
        .sum::<f64>()
        / 20.0
}

/// On 10 objects the choice keeps 8–15 effective clusters (no fewer than 80% of the objects
/// and at most half again as many, the range docs/oiesgp-clustering.md gives), and its clustering is far above chance: ARI at least 0.5 (chance
/// 0) and NMI at least 0.3 above the NMI of the same clustering against shuffled labels.
/// The same seed gives the same choice, and shuffling the labels changes every score but not
/// the choice: the criterion never reads them.
#[test]
fn the_label_free_threshold_finds_the_objects_and_never_reads_the_labels() {
    let session = sample();
    let r = run(&session);
    let c = r.threshold_choice.clone().expect("a threshold is chosen");
    let at = r.at_choice().unwrap();
    eprintln!("{:?}\n{:?}", c.curve, r.sweep);
    assert!(
        (8.0..=15.0).contains(&at.effective.mean),
        "{} effective clusters at {}",
        at.effective.mean,
        c.threshold
    );
    let first = r
        .runs
        .iter()
        .find(|x| x.threshold == c.threshold && x.rep == 0)
        .unwrap();
    let chance = chance_nmi(&r.labels, first.assignment.as_ref().unwrap());
    assert!(at.ari.mean >= 0.5, "ARI {}", at.ari.mean);
    assert!(
        at.nmi.mean >= chance + 0.3,
        "NMI {} against chance {chance}",
        at.nmi.mean
    );

    let again = run(&session);
    assert_eq!(again.threshold_choice, r.threshold_choice);

    let blind = run(&shuffled_labels(&session));
    assert_eq!(blind.threshold_choice, r.threshold_choice);
    assert!(
        blind
            .sweep
            .iter()
            .zip(&r.sweep)
            .all(|(a, b)| a.nmi.mean < b.nmi.mean),
        "the shuffled labels must change the scores"
    );

    // The choice is marked on both threshold charts.
    let report = clustering_report("sample", &r);
    for name in [FigureId::ScoresVsThreshold, FigureId::ClustersVsThreshold] {
        let f = &report.figures.iter().find(|(n, _)| *n == name).unwrap().1;
        let FigureKind::Chart(chart) = &f.kind else {
            panic!("{name}: a chart");
        };
        assert!(
            chart
                .ref_lines
                .iter()
                .any(|l| l.orientation == Orientation::Vertical && l.value == c.threshold),
            "{name}"
        );
        assert!(f.validate().is_ok());
    }
    assert_eq!(
        report.score("threshold chosen without labels"),
        Some(c.threshold)
    );
}
