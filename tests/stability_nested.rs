//! Nested cross validation of the grid search: a planted leak (every label of one outer test
//! fold flipped) leaves that fold's selection untouched, while the other folds, whose
//! training grasps hold the flipped labels, do see it.

mod common;

use tactile_workbench::experiments::stability::{
    CvScheme, DataOptions, GridSpec, PipelineSettings, StabilityData, nested_cv_on,
};
use tactile_workbench::jobs::Progress;

#[test]
fn selection_never_sees_the_outer_test_fold() {
    let session =
        tactile_workbench::session::load(&common::sample("grasp-stability.json")).unwrap();
    let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
    let spec = GridSpec {
        num_bases: vec![4, 10],
        beta: vec![1.0],
        gamma: vec![0.25, 1.0],
    };
    let settings = PipelineSettings::default();
    for protocol in [
        CvScheme::KFold { k: 5 },
        CvScheme::LeaveObjectsOut { folds: Some(4) },
    ] {
        let outer = protocol.folds(&data, 0).unwrap();
        let clean =
            nested_cv_on(&data, &spec, &settings, protocol, &outer, &Progress::new()).unwrap();
        assert_eq!(clean.folds.len(), outer.count);
        let tested: usize = clean.folds.iter().map(|f| f.test).sum();
        assert_eq!(tested, data.grasp_count(), "every grasp tested once");
        let mut leaky = data.clone();
        for g in outer.test_indices(0) {
            leaky.labels[g] = !leaky.labels[g];
        }
        let planted =
            nested_cv_on(&leaky, &spec, &settings, protocol, &outer, &Progress::new()).unwrap();
        let (a, b) = (&clean.folds[0], &planted.folds[0]);
        assert_eq!(
            a.chosen, b.chosen,
            "{protocol:?}: fold 0 chose on its test labels"
        );
        assert_eq!(a.chosen_inner_wsr, b.chosen_inner_wsr, "{protocol:?}");
        assert_eq!((a.best, a.best_inner_wsr), (b.best, b.best_inner_wsr));
        // The plant is where it should show: on fold 0's test score ...
        assert_ne!(a.confusion, b.confusion, "{protocol:?}");
        // ... and in the selection of every fold that trains on those grasps.
        for (c, p) in clean.folds[1..].iter().zip(&planted.folds[1..]) {
            assert_ne!(
                c.chosen_inner_wsr, p.chosen_inner_wsr,
                "{protocol:?}: fold {} trains on the flipped labels",
                c.fold
            );
        }
    }
}
