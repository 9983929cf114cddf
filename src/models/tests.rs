//! Model files on the grasp-stability sample: a saved model predicts as the one in memory,
//! calibration undoes a planted drift, and bad files and sessions get errors naming what
//! differs.

use super::*;
use crate::catalogue::MethodId;
use crate::experiments::stability::{self, Config, DataOptions, StabilityData, StabilityOptions};
use crate::jobs::Progress;
use crate::session::{Session, ValueTransform, simulate};

fn sample() -> (Session, StabilityData) {
    let session = simulate::grasp_stability(0);
    let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
    (session, data)
}

fn small() -> StabilityOptions {
    StabilityOptions {
        single: Config {
            num_bases: 8,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    }
}

fn fitted(method: MethodId) -> (Session, ModelFile) {
    let (session, data) = sample();
    let fit = fit_stability(method, &session, &data, &small(), &Progress::new()).unwrap();
    let file = fit.into_file(&session, &data);
    (session, file)
}

fn wsr(r: &HeldOutResult) -> f64 {
    match r.scores {
        HeldOutScores::Stability {
            weighted_success_rate,
            ..
        } => weighted_success_rate,
        _ => panic!("a stability result"),
    }
}

#[test]
fn a_saved_model_predicts_bit_for_bit_as_the_model_in_memory() {
    let (session, data) = sample();
    let report = stability::run(&data, &small(), &Progress::new()).unwrap();
    let classifier = StabilityClassifier::from_sparse(&report.model, &data, &session);
    let file = super::stability::StabilityFit::from_report(&session, &data, &small(), &report)
        .into_file(&session, &data);
    let loaded = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
    assert_eq!(loaded, file);
    let Model::Stability(back) = &loaded.model else {
        panic!("a stability model")
    };
    let before = classifier.decisions(&session, Calibration::None).unwrap();
    let after = back.decisions(&session, Calibration::None).unwrap();
    let bits = |v: &[f64]| v.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&before), bits(&after));
    // The analyses' model, one grasp at a time, decides as the batched decision values.
    let images = data.patches.pressures.view();
    for (g, d) in after.iter().enumerate() {
        let failure = report.model.predict_failure(images.row(g)).unwrap();
        assert_eq!(failure, *d > 0.0, "grasp {g}");
    }
}

#[test]
fn codes_and_raw_give_the_svm_what_the_codes_drop() {
    use crate::experiments::stability::PipelineInputs;
    let (session, data) = sample();
    // A coding penalty past every |dᵀx| codes every patch as zero: the codes carry nothing.
    let mut opts = small();
    opts.single.gamma = 1e9;
    let fit = |opts: &StabilityOptions| {
        fit_stability(MethodId::SparseSvm, &session, &data, opts, &Progress::new())
            .unwrap()
            .into_file(&session, &data)
    };
    let codes = fit(&opts);
    opts.settings.inputs = PipelineInputs::CodesAndRaw;
    let both = fit(&opts);
    let score = |f: &ModelFile| wsr(&evaluate(f, &session, Calibration::None).unwrap());
    // Chance is 0.5: all-zero codes put every grasp on one side; the values beside them
    // separate the sample's outcomes as the raw SVM does.
    assert!(score(&codes) <= 0.5 + 1e-12, "codes {}", score(&codes));
    assert!(score(&both) > 0.7, "codes+raw {}", score(&both));
    // The summary (the Models list, held-out cards) tells the two apart.
    assert!(
        both.provenance
            .summary()
            .contains("(num_bases 8, codes+raw)")
    );
    assert!(codes.provenance.summary().contains("(num_bases 8)"));
    // The inputs travel with the file, and a file without them reads codes.
    let loaded = ModelFile::from_json(&both.to_json(), "m.json").unwrap();
    assert_eq!(loaded, both);
    let mut old: serde_json::Value = serde_json::from_str(&codes.to_json()).unwrap();
    let removed = old["model"]["codes"]
        .as_object_mut()
        .and_then(|c| c.remove("inputs"));
    assert_eq!(removed, Some(serde_json::json!("codes")));
    assert_eq!(
        ModelFile::from_json(&old.to_string(), "old.json").unwrap(),
        codes
    );
}

/// The session with every taxel's pressure raised by `shift`.
fn shifted(session: &Session, shift: f64) -> Session {
    let mut s = session.clone();
    for (i, sensor) in s.sensors.iter().enumerate() {
        // Raw readings move against pressure for the reversed transforms.
        let raw_shift = match sensor.transform {
            ValueTransform::Identity => shift,
            _ => -shift,
        };
        for g in &mut s.grasps {
            for f in &mut g.frames {
                f.taxels[i].iter_mut().for_each(|v| *v += raw_shift);
            }
        }
    }
    s
}

#[test]
fn a_drifted_session_needs_its_own_statistics() {
    for method in [MethodId::RawSvm, MethodId::SparseSvm] {
        let (session, file) = fitted(method);
        let Model::Stability(c) = &file.model else {
            panic!("a stability model")
        };
        // Five times the widest taxel's spread: a baseline drift as between recording days.
        let spread = c.taxel_stats.sd.iter().fold(0.0f64, |a, b| a.max(*b));
        let drifted = shifted(&session, 5.0 * spread);
        let none = evaluate(&file, &drifted, Calibration::None).unwrap();
        let own = evaluate(&file, &drifted, Calibration::Session).unwrap();
        // Chance is 0.5: uncalibrated, the drift puts every grasp on one side; with the
        // session's own statistics the model reads the grasps as before.
        assert!(wsr(&none) < 0.6, "{method:?} none {}", wsr(&none));
        assert!(wsr(&own) > 0.7, "{method:?} session {}", wsr(&own));
    }
}

#[test]
fn first_k_reads_only_the_first_grasps_statistics() {
    let (session, file) = fitted(MethodId::RawSvm);
    let k = 40;
    let mut later_changed = session.clone();
    // Grasps after the first K do not move the statistics of first:K ...
    for g in &mut later_changed.grasps[k..] {
        for f in &mut g.frames {
            f.taxels[0].iter_mut().for_each(|v| *v *= 1.5);
        }
    }
    let c = Calibration::First { grasps: k };
    let a = predict(&file, &session, c).unwrap();
    let b = predict(&file, &later_changed, c).unwrap();
    assert_eq!(a[..k], b[..k]);
    // ... but they move those of the whole session.
    let a = predict(&file, &session, Calibration::Session).unwrap();
    let b = predict(&file, &later_changed, Calibration::Session).unwrap();
    assert_ne!(a[..k], b[..k]);
}

#[test]
fn bad_model_files_name_the_field() {
    let (_, file) = fitted(MethodId::SparseSvm);
    let good: serde_json::Value = serde_json::from_str(&file.to_json()).unwrap();
    type Break = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(&str, Break)> = vec![
        ("format", Box::new(|v| v["format"] = "a-session".into())),
        ("version 2", Box::new(|v| v["version"] = 2.into())),
        (
            "svm.weights",
            Box::new(|v| {
                let w = v["model"]["svm"]["weights"]["data"].as_array_mut().unwrap();
                w.pop();
                let n = w.len();
                v["model"]["svm"]["weights"]["dim"] = serde_json::json!([n]);
            }),
        ),
        (
            "taxel_stats",
            Box::new(|v| {
                v["model"]["taxel_stats"]["sd"]
                    .as_array_mut()
                    .unwrap()
                    .pop();
            }),
        ),
        (
            "codes.dictionary.atoms",
            Box::new(|v| {
                let atoms = &mut v["model"]["codes"]["dictionary"]["atoms"];
                let dim = atoms["dim"][1].as_u64().unwrap() as usize;
                let rows = atoms["dim"][0].as_u64().unwrap() as usize;
                atoms["dim"] = serde_json::json!([rows * dim / 2, 2]);
            }),
        ),
        (
            "provenance.method",
            Box::new(|v| v["provenance"]["method"] = "raw_svm".into()),
        ),
        (
            "trained_at",
            Box::new(|v| v["provenance"]["trained_at"] = "yesterday".into()),
        ),
        (
            "failure_class",
            Box::new(|v| v["model"]["failure_class"] = v["model"]["success_class"].clone()),
        ),
    ];
    for (field, break_it) in cases {
        let mut v = good.clone();
        break_it(&mut v);
        let e = ModelFile::from_json(&v.to_string(), "bad-model.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad-model.json"), "{field}: {e}");
        assert!(e.contains(field), "{field}: {e}");
    }
    let e = ModelFile::from_json("{\"format\": 1", "m.json").unwrap_err();
    assert!(e.to_string().contains("not JSON"), "{e}");
}

#[test]
fn a_session_of_other_sensors_or_classes_is_refused_by_name() {
    let (session, file) = fitted(MethodId::RawSvm);
    let other = simulate::object_recognition(0);
    let e = evaluate(&file, &other, Calibration::Session)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sensors") && e.contains(&session.sensors[0].name),
        "{e}"
    );
    let Model::Stability(c) = &file.model else {
        panic!("a stability model")
    };
    let mut renamed = session.clone();
    let i = renamed.label_set(&c.label_set).unwrap();
    let set = &mut renamed.label_sets[i];
    let old = set.classes[1].clone();
    set.classes[1] = "wobbly".into();
    let e = evaluate(&file, &renamed, Calibration::Session)
        .unwrap_err()
        .to_string();
    assert!(e.contains("wobbly") && e.contains(&old), "{e}");
}

/// The window's check reads one grasp, and refuses what `evaluate` refuses: a session
/// without the model's label set, or of other sensors.
#[test]
fn check_readable_answers_as_evaluate_does() {
    let (session, file) = fitted(MethodId::RawSvm);
    assert!(check_readable(&file, &session).is_ok());
    let Model::Stability(c) = &file.model else {
        panic!("a stability model")
    };
    let mut other = simulate::object_recognition(0);
    let e = check_readable(&file, &other).unwrap_err().to_string();
    assert!(e.contains("label set") && e.contains(&c.label_set), "{e}");
    // Given the label set, the sensors still differ.
    let mut set = other.label_sets[0].clone();
    set.name = c.label_set.clone();
    other.label_sets.push(set);
    for g in &mut other.grasps {
        let l = g.labels[0];
        g.labels.push(l);
    }
    let e = check_readable(&file, &other).unwrap_err().to_string();
    assert!(e.contains("sensors"), "{e}");
    assert!(evaluate(&file, &other, Calibration::None).is_err());
}

mod sequences {
    use super::*;
    use crate::features::FeatureSet;
    use crate::session::{SubsetSpec, subset};

    fn part(
        session: &Session,
        trials: std::ops::RangeInclusive<u32>,
        objects: &[String],
    ) -> Session {
        let spec = SubsetSpec {
            objects: objects.to_vec(),
            trials: trials.into(),
            labels: Vec::new(),
        };
        subset(session, &spec, "part").unwrap()
    }

    fn options(method: MethodId) -> SequenceFitOptions {
        let defaults = crate::experiments::recognition::RecognitionParams::default();
        let (ds, gs) = (defaults.ds, defaults.gs);
        SequenceFitOptions {
            method,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            seed: 3,
            ds,
            gs,
        }
    }

    fn accuracy(r: &HeldOutResult) -> f64 {
        match r.scores {
            HeldOutScores::Recognition { accuracy, .. } => accuracy,
            _ => panic!("a recognition result"),
        }
    }

    #[test]
    fn a_model_taught_further_from_its_file_equals_one_taught_in_one_run() {
        let session = simulate::object_recognition(1);
        let objects = session.objects();
        let a = part(&session, 1..=3, &objects);
        let b = part(&session, 4..=6, &objects);
        let test = part(&session, 7..=10, &objects);
        for method in [MethodId::Ds, MethodId::Gs] {
            let (model, secs) = fit_sequences(&a, &options(method)).unwrap();
            let file = sequence_file(model.clone(), &a, secs, Default::default(), None);
            let loaded = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
            let Model::Sequences(saved) = &loaded.model else {
                panic!("a sequence model")
            };
            // Before teaching: the experts on file decide as those in memory, bit for bit.
            let bits = |m: &SequenceModel| -> Vec<u64> {
                m.predict(&test, Calibration::None)
                    .unwrap()
                    .iter()
                    .flat_map(|p| {
                        p.distributions
                            .iter()
                            .map(|v| v.to_bits())
                            .collect::<Vec<_>>()
                    })
                    .collect()
            };
            assert_eq!(bits(&model), bits(saved), "{method:?}");
            // Taught the next trials from the file and in one run alike.
            let (from_file, _) = continue_sequences(saved, &b).unwrap();
            let (one_run, _) = continue_sequences(&model, &b).unwrap();
            assert_eq!(from_file, one_run, "{method:?}");
            assert_eq!(bits(&from_file), bits(&one_run), "{method:?}");
            // Ten objects, chance 0.1: on trials they never saw, the experts taught twice
            // tell them apart as well as experts taught both parts at once (within 4 of
            // the 40 test grasps).
            let taught = sequence_file(
                from_file,
                &b,
                0.0,
                Default::default(),
                Some(&file.provenance),
            );
            let (at_once, _) =
                fit_sequences(&part(&session, 1..=6, &objects), &options(method)).unwrap();
            let at_once = sequence_file(at_once, &session, 0.0, Default::default(), None);
            let continued = accuracy(&evaluate(&taught, &test, Calibration::None).unwrap());
            let reference = accuracy(&evaluate(&at_once, &test, Calibration::None).unwrap());
            assert!(reference > 0.6, "{method:?} at once {reference}");
            assert!(
                continued >= reference - 0.1,
                "{method:?} {continued} against {reference}"
            );
        }
    }

    #[test]
    fn a_model_of_sparse_codes_codes_new_sessions_on_its_own_dictionaries() {
        let session = simulate::object_recognition(1);
        let objects = session.objects();
        let (train, test) = (
            part(&session, 1..=5, &objects),
            part(&session, 6..=10, &objects),
        );
        let opts = SequenceFitOptions {
            features: FeatureSet::CODES,
            ..options(MethodId::Gs)
        };
        let (model, secs) = fit_sequences(&train, &opts).unwrap();
        let book = model
            .inputs
            .codes
            .clone()
            .expect("the training dictionaries");
        let file = sequence_file(model.clone(), &train, secs, Default::default(), None);
        let loaded = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
        let Model::Sequences(saved) = &loaded.model else {
            panic!("a sequence model")
        };
        assert_eq!(saved.inputs.codes.as_ref(), Some(&book));
        // Unseen trials, coded on the training atoms: well above the 1-in-10 chance.
        let r = evaluate(&loaded, &test, Calibration::None).unwrap();
        assert!(accuracy(&r) > 0.6, "{}", accuracy(&r));
        assert_eq!(
            accuracy(&r),
            accuracy(&evaluate(&file, &test, Calibration::None).unwrap())
        );
        // A file whose dictionaries are gone names the field.
        let mut json: serde_json::Value = serde_json::from_str(&file.to_json()).unwrap();
        json["model"]
            .as_object_mut()
            .unwrap()
            .remove("codes")
            .expect("the codes are saved beside the range");
        let e = ModelFile::from_json(&json.to_string(), "m.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("model.codes"), "{e}");
    }

    #[test]
    fn a_class_without_an_expert_is_named() {
        let session = simulate::object_recognition(1);
        let objects = session.objects();
        let a = part(&session, 1..=4, &objects[..3]);
        let (model, _) = fit_sequences(&a, &options(MethodId::Ds)).unwrap();
        assert_eq!(model.classes, objects[..3].to_vec());
        let file = sequence_file(model, &a, 0.0, Default::default(), None);
        let e = evaluate(
            &file,
            &part(&session, 5..=6, &objects[..4]),
            Calibration::None,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains(&objects[3]) && e.contains("--from"), "{e}");
        // Taught a session with the new object, the model gets an expert for it.
        let Model::Sequences(m) = &file.model else {
            panic!("a sequence model")
        };
        let (taught, _) = continue_sequences(m, &part(&session, 1..=4, &objects[2..4])).unwrap();
        assert_eq!(taught.classes, objects[..4].to_vec());
    }
}

mod clusters {
    use super::*;
    use crate::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use crate::features::FeatureSet;
    use crate::session::{SubsetSpec, subset};

    #[test]
    fn clusters_learned_further_from_the_file_equal_those_learned_in_one_run() {
        let session = simulate::object_recognition(1);
        let objects = session.objects();
        let part = |objects: &[String]| {
            let spec = SubsetSpec {
                objects: objects.to_vec(),
                trials: (1..=5).into(),
                labels: Vec::new(),
            };
            subset(&session, &spec, "part").unwrap()
        };
        let (a, b) = (part(&objects[..3]), part(&objects[3..6]));
        for (method, learner, threshold) in [
            (MethodId::Du, UnsupervisedLearner::Du, 0.4),
            (MethodId::Gu, UnsupervisedLearner::Gu, 0.2),
        ] {
            let opts = ClusterFitOptions {
                method,
                features: FeatureSet::ALL,
                label_set: "object".into(),
                threshold,
                seed: 2,
                params: ClusteringParams::for_learner(learner),
            };
            let (model, _) = fit_clusters(&a, &opts).unwrap();
            let file = cluster_file(model.clone(), &a, 0.0, None);
            let loaded = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
            let Model::Clusters(saved) = &loaded.model else {
                panic!("a cluster model")
            };
            assert_eq!(
                saved.assign(&b, Calibration::None).unwrap(),
                model.assign(&b, Calibration::None).unwrap()
            );
            let (from_file, _) = continue_clusters(saved, &b).unwrap();
            let (one_run, _) = continue_clusters(&model, &b).unwrap();
            assert_eq!(from_file, one_run, "{method:?}");
            // Three objects it never saw: novel grasps open clusters.
            assert!(from_file.clusters() > model.clusters(), "{method:?}");
            let r = evaluate(
                &cluster_file(from_file, &b, 0.0, None),
                &b,
                Calibration::None,
            )
            .unwrap();
            let HeldOutScores::Clustering { purity, .. } = r.scores else {
                panic!("a clustering result")
            };
            // Three objects: chance purity is about 1/3.
            assert!(purity > 0.6, "{method:?} purity {purity}");
        }
    }
}

mod table_one {
    use super::*;
    use crate::session::{SubsetSpec, subset};

    #[test]
    fn the_table_one_baselines_predict_from_their_files_as_in_memory() {
        let session = simulate::object_recognition(1);
        let part = |trials: std::ops::RangeInclusive<u32>| {
            let spec = SubsetSpec {
                trials: trials.into(),
                ..Default::default()
            };
            subset(&session, &spec, "part").unwrap()
        };
        let (train, test) = (part(1..=6), part(7..=10));
        for method in [MethodId::KMeans, MethodId::Som, MethodId::RbfSvm] {
            let opts = TableOneFitOptions::new(method, "object", 10, 4);
            let (model, fit) = fit_table_one(&train, &opts, None).unwrap();
            let file = table_one_file(model.clone(), &train, fit);
            let loaded = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
            let Model::TableOne(saved) = &loaded.model else {
                panic!("a Table I model")
            };
            assert_eq!(
                saved.assign(&test, Calibration::None).unwrap(),
                model.assign(&test, Calibration::None).unwrap(),
                "{method:?}"
            );
            // Ten objects on trials never seen: chance accuracy 0.1, chance purity about
            // 0.1 for ten balanced objects.
            match evaluate(&loaded, &test, Calibration::None).unwrap().scores {
                HeldOutScores::Recognition { accuracy, .. } => {
                    assert!(accuracy > 0.6, "{method:?} accuracy {accuracy}")
                }
                HeldOutScores::Clustering { purity, .. } => {
                    assert!(purity > 0.4, "{method:?} purity {purity}")
                }
                HeldOutScores::Stability { .. } => panic!("not a stability model"),
            }
        }
    }
}
