//! The registered methods on the real iCub dataset: stratified 10-fold cross validation of
//! each at its default size and inputs. Bar from issue #42: accuracy ≥ 0.90 (ten objects:
//! chance is 0.10).

mod common;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::classifier::{cv_repetition, prepare_classifier};
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::import_icub;

fn ten_fold(key: &str) -> Option<f64> {
    let dir = common::dataset("icub-grasp")?;
    let session = import_icub(&dir).expect("the iCub dataset imports");
    let method = key.parse::<MethodId>().unwrap().classifier().unwrap();
    let prep = prepare_classifier(&session, method.features(), "object").unwrap();
    let t0 = std::time::Instant::now();
    let s = cv_repetition(
        method,
        &method.default_size(),
        &prep,
        10,
        0,
        0,
        &Progress::new(),
    )
    .unwrap();
    eprintln!(
        "{key}: 10-fold accuracy {:.3} ({:.1} s)",
        s.accuracy,
        t0.elapsed().as_secs_f64()
    );
    Some(s.accuracy)
}

#[test]
fn temporal_svm_ten_fold() {
    let Some(acc) = ten_fold("temporal-svm") else {
        return;
    };
    assert!(acc >= 0.90, "temporal-feature SVM 10-fold accuracy {acc}");
}

#[test]
fn dtw_knn_ten_fold() {
    let Some(acc) = ten_fold("dtw-knn") else {
        return;
    };
    assert!(acc >= 0.90, "DTW k-NN 10-fold accuracy {acc}");
}
