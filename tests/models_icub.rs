//! Models that leave their session, on the iCub set: DS and GS taught trials 1–7, saved,
//! and taught trials 8–15 from the file reach, on trials 16–20 they never saw, the accuracy
//! of experts taught trials 1–15 in one run; a model of the BTS3 v2 palm-45 training file
//! scores above chance on its held-out test objects.

mod common;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::recognition::RecognitionParams;
use tactile_workbench::experiments::stability::{PipelineInputs, StabilityData, StabilityOptions};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::jobs::Progress;
use tactile_workbench::models::{self, Calibration, HeldOutScores, ModelFile, SequenceFitOptions};
use tactile_workbench::session::{Session, SubsetSpec, import_bts3, import_icub, subset};

fn trials(s: &Session, t: std::ops::RangeInclusive<u32>) -> Session {
    let spec = SubsetSpec {
        trials: t.into(),
        ..Default::default()
    };
    subset(s, &spec, "part").unwrap()
}

fn accuracy(file: &ModelFile, test: &Session) -> f64 {
    match models::evaluate(file, test, Calibration::None)
        .unwrap()
        .scores
    {
        HeldOutScores::Recognition { accuracy, .. } => accuracy,
        _ => panic!("a recognition result"),
    }
}

#[test]
fn experts_taught_further_from_a_file_reach_the_one_run_accuracy() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    let icub = import_icub(&dir).unwrap();
    let (first, second, test) = (
        trials(&icub, 1..=7),
        trials(&icub, 8..=15),
        trials(&icub, 16..=20),
    );
    let defaults = RecognitionParams::default();
    for method in [MethodId::Ds, MethodId::Gs] {
        let opts = SequenceFitOptions {
            method,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            seed: 0,
            ds: defaults.ds.clone(),
            gs: defaults.gs.clone(),
        };
        let (a, _) = models::fit_sequences(&first, &opts).unwrap();
        let saved = ModelFile::from_json(
            &models::sequence_file(a, &first, 0.0, Default::default(), None).to_json(),
            "a.json",
        )
        .unwrap();
        let models::Model::Sequences(m) = &saved.model else {
            panic!("a sequence model")
        };
        let (continued, _) = models::continue_sequences(m, &second).unwrap();
        let continued = models::sequence_file(continued, &second, 0.0, Default::default(), None);
        let (at_once, _) = models::fit_sequences(&trials(&icub, 1..=15), &opts).unwrap();
        let at_once = models::sequence_file(at_once, &icub, 0.0, Default::default(), None);
        let (c, o) = (accuracy(&continued, &test), accuracy(&at_once, &test));
        // Table II of the paper: DS and GS above 0.95 on iCub; taught in two parts, within
        // two of the 50 test grasps of the one-run experts.
        assert!(o >= 0.9, "{method:?} one run {o}");
        assert!(
            c >= o - 0.04,
            "{method:?} continued {c} against one run {o}"
        );
    }
}

#[test]
fn a_stability_model_scores_above_chance_on_new_objects() {
    let (Some(train), Some(test)) = (
        common::dataset("bts3v2/bts3v2_palm_45.csv"),
        common::dataset("bts3v2/bts3v2_palm_45_test.csv"),
    ) else {
        return;
    };
    let (train, test) = (import_bts3(&train).unwrap(), import_bts3(&test).unwrap());
    let data = StabilityData::from_session(&train, &Default::default()).unwrap();
    let wsr_of = |method, inputs, c| {
        let mut opts = StabilityOptions::default();
        opts.settings.inputs = inputs;
        let fit = models::fit_stability(method, &train, &data, &opts, &Progress::new()).unwrap();
        match models::evaluate(&fit.into_file(&train, &data), &test, c)
            .unwrap()
            .scores
        {
            HeldOutScores::Stability {
                weighted_success_rate,
                ..
            } => weighted_success_rate,
            _ => panic!("a stability result"),
        }
    };
    let wsr = |method, c| wsr_of(method, PipelineInputs::Codes, c);
    // The measurements with scikit-learn's linear SVM on the raw electrodes: 0.76
    // uncalibrated, 0.73 with per-session statistics; chance is 0.5. Ours within 3 points
    // of those, and the sparse pipeline with the default calibration well above chance.
    let raw_none = wsr(MethodId::RawSvm, Calibration::None);
    let raw_session = wsr(MethodId::RawSvm, Calibration::Session);
    assert!((raw_none - 0.76).abs() < 0.03, "raw none {raw_none}");
    assert!(
        (raw_session - 0.73).abs() < 0.03,
        "raw session {raw_session}"
    );
    let sparse = wsr(MethodId::SparseSvm, Calibration::default());
    assert!(sparse > 0.7, "sparse, session {sparse}");
    // With the values beside the codes, the pipeline reaches the bars for the raw
    // SVM under both calibrations (docs/held-out.md: 0.813 and 0.771).
    for (c, bar) in [(Calibration::None, 0.76), (Calibration::Session, 0.73)] {
        let both = wsr_of(MethodId::SparseSvm, PipelineInputs::CodesAndRaw, c);
        assert!(both >= bar, "codes+raw, {c}: {both} against {bar}");
    }
}
