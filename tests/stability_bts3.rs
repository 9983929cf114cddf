//! The pipeline on the real BTS3 palm-down set (1276 grasps, 3 BioTac SP × 24 electrodes,
//! 3828 patches), z-scored per electrode. Bars (scikit-learn reaches F = 5.3757, the
//! original code 5.40; its 10-fold weighted success rate at K = 29, λ = γ = 1 is 86.2 %;
//! the raw linear SVM 89.0 % / 87.4 %), raised where we beat them:
//!
//! - dictionary learning at K = 29, λ = 1 reaches F ≤ 5.37 (issue bar 5.38);
//! - the pipeline's 10-fold weighted success rate at K = 29, λ = γ = 1 is ≥ 85.5 % (bar 85 %);
//! - the raw-electrode linear SVM reaches ≥ 88.5 % (10-fold) and ≥ 86.5 % (leave one
//!   object out).
//!
//! Skipped, with a line on the terminal, when `../shared/datasets` is absent (a failure
//! under CI).

mod common;

use tactile_workbench::experiments::stability::{
    self, Config, CvScheme, DataOptions, PipelineSettings, StabilityData,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::session;
use tactile_workbench::sparse::DictionaryParams;

fn data() -> Option<StabilityData> {
    let csv = common::dataset("bts3/biotac-palmdown-grasps.csv")?;
    let s = session::import_bts3(&csv).expect("import");
    Some(StabilityData::from_session(&s, &DataOptions::default()).expect("data"))
}

#[test]
fn pipeline_at_k29_meets_the_bars() {
    let Some(d) = data() else {
        return;
    };
    assert_eq!(d.x.dim(), (3828, 24));
    assert_eq!(d.labels.iter().filter(|l| **l).count(), 609);
    let settings = PipelineSettings::default();
    let cfg = Config {
        num_bases: 29,
        beta: 1.0,
        gamma: 1.0,
    };
    let (e, dict) = stability::evaluate_config(
        &d,
        cfg,
        &settings,
        CvScheme::KFold { k: 10 },
        CvScheme::LeaveObjectsOut { folds: None },
        None,
        &Progress::new(),
    )
    .unwrap();
    println!(
        "K = 29: F = {:.4} in {} iterations; sparsity {:.4}; 10-fold WSR {:.4} FR {:.4}; leave-one-object-out WSR {:.4} FR {:.4}",
        e.dictionary_objective,
        e.dictionary_iterations,
        e.sparsity,
        e.kfold.weighted_success_rate,
        e.kfold.failure_recall,
        e.objects.weighted_success_rate,
        e.objects.failure_recall
    );
    assert!(
        e.dictionary_objective <= 5.37,
        "F = {}",
        e.dictionary_objective
    );
    assert!(
        e.kfold.weighted_success_rate >= 0.855,
        "WSR {}",
        e.kfold.weighted_success_rate
    );
    assert!(e.sparsity > 0.8);
    for row in dict.atoms.rows() {
        assert!(row.dot(&row) <= 1.0 + 1e-9);
    }
    // The default start is seeded: a second fit gives the same dictionary.
    let again = DictionaryParams {
        num_bases: 29,
        beta: 1.0,
        ..settings.dictionary.clone()
    }
    .fit(d.x.view(), &Progress::new())
    .unwrap();
    assert_eq!(again.dictionary, dict);
}

#[test]
fn raw_electrode_baseline_meets_the_bars() {
    let Some(d) = data() else {
        return;
    };
    let b = stability::baseline(
        &d,
        &PipelineSettings::default(),
        CvScheme::KFold { k: 10 },
        CvScheme::LeaveObjectsOut { folds: None },
    )
    .unwrap();
    println!(
        "raw linear SVM: 10-fold WSR {:.4} FR {:.4}; leave-one-object-out WSR {:.4} FR {:.4}",
        b.kfold.weighted_success_rate,
        b.kfold.failure_recall,
        b.objects.weighted_success_rate,
        b.objects.failure_recall
    );
    assert_eq!(b.features, 72);
    assert!(b.kfold.weighted_success_rate >= 0.885);
    assert!(b.objects.weighted_success_rate >= 0.865);
    // Leave-objects-out folds: 41 objects, none split.
    assert_eq!(b.objects.folds.len(), 41);
}
