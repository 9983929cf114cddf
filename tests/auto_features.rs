//! `--features auto`: the input family chosen by cross validation on the training session.
//! The sessions here are built so that exactly one family carries the class and the others
//! are noise, so the right answer is known from the construction, not from the code.

mod common;

use std::process::Command;

use tactile_workbench::catalogue::{ClassifierId, MethodId};
use tactile_workbench::experiments::classifier::ClassifierScorer;
use tactile_workbench::experiments::feature_choice::{FeatureChoice, choose_features};
use tactile_workbench::experiments::recognition::{
    ExpertsScorer, RecognitionParams, SupervisedLearner,
};
use tactile_workbench::features::{Family, FeatureSet};
use tactile_workbench::jobs::Progress;
use tactile_workbench::models::{
    self, ClassifierFitOptions, ModelFile, choose_classifier_features, classifier_file,
    fit_classifier,
};
use tactile_workbench::rng::Rng;
use tactile_workbench::session::{Session, ValueTransform, save, simulate};

const CLASSES: usize = 3;
/// Chance is 1/3; a family that carries no class must stay well below the carrier.
const NOISE_BAR: f64 = 1.0 / 3.0 + 0.25;

/// Three objects × 20 grasps of 10 frames whose every reading is seeded uniform noise,
/// except the family `carrier`, which tells the object:
/// - `Raw`: on fingertip k, taxel (object + k) mod 12 reads 5 more than the noise. Every
///   fingertip has exactly one such taxel whatever the object and the noise of every taxel
///   is drawn alike, so each fingertip's pressures are the same multiset in distribution:
///   its moments (mean, sd, skewness, max, min) carry nothing, and neither does the change
///   from the first frame (the offset cancels). Only where the pressure is tells the object.
/// - `Encoders`: encoders j with j mod 3 = object read 5 more than the noise; the taxels
///   are noise only.
fn planted(carrier: Family, seed: u64) -> Session {
    let mut s = simulate::object_recognition(1);
    let object = s.label_set("object").unwrap();
    s.label_sets[object].classes.truncate(CLASSES);
    s.grasps.retain(|g| g.labels[object] < CLASSES);
    for sensor in &mut s.sensors {
        sensor.transform = ValueTransform::Identity;
    }
    let mut rng = Rng::stream(seed, 0);
    for g in &mut s.grasps {
        let class = g.labels[object];
        g.frames.resize(10, g.frames[0].clone());
        for (t, f) in g.frames.iter_mut().enumerate() {
            f.t = 0.1 * t as f64;
            for (k, taxels) in f.taxels.iter_mut().enumerate() {
                let n = taxels.len();
                for (i, v) in taxels.iter_mut().enumerate() {
                    *v = rng.uniform();
                    if carrier == Family::Raw && i == (class + k) % n {
                        *v += 5.0;
                    }
                }
            }
            for (j, e) in f.encoders.iter_mut().enumerate() {
                *e = rng.uniform();
                if carrier == Family::Encoders && j % CLASSES == class {
                    *e += 5.0;
                }
            }
        }
        g.key_frame = g.key_frame.min(9);
    }
    s
}

fn temporal_svm_choice(s: &Session, seed: u64) -> FeatureChoice {
    let method = ClassifierId::TemporalSvm.method();
    let size = method.default_size();
    let scorer = ClassifierScorer {
        method,
        size: &size,
    };
    choose_features(s, &scorer, "object", 5, seed, &Progress::new()).unwrap()
}

fn score(c: &FeatureChoice, f: FeatureSet) -> f64 {
    c.candidates
        .iter()
        .find(|x| x.features == f)
        .unwrap_or_else(|| panic!("{f} not scored: {}", c.text()))
        .score
}

#[test]
fn auto_picks_the_family_that_carries_the_class_and_not_the_noise() {
    let s = planted(Family::Raw, 1);
    let c = temporal_svm_choice(&s, 0);
    assert_eq!(c.chosen, FeatureSet::RAW, "{}", c.text());
    assert!(score(&c, FeatureSet::RAW) >= 0.9, "{}", c.text());
    for noise in [
        FeatureSet::ALL,
        FeatureSet::MOMENTS,
        FeatureSet::ENCODERS,
        FeatureSet::CHANGE,
    ] {
        assert!(score(&c, noise) <= NOISE_BAR, "{noise}: {}", c.text());
    }
    assert_eq!(c.scored_by, MethodId::Classifier(ClassifierId::TemporalSvm));
    assert!(c.text().contains("auto chose raw"), "{}", c.text());
}

#[test]
fn of_families_within_one_se_of_the_best_auto_takes_the_fewest_features() {
    // The encoders carry the class; `all` holds them too (and 25 moments of noise).
    let s = planted(Family::Encoders, 2);
    let c = temporal_svm_choice(&s, 0);
    assert!(score(&c, FeatureSet::ENCODERS) >= 0.9, "{}", c.text());
    assert!(score(&c, FeatureSet::RAW) <= NOISE_BAR, "{}", c.text());
    assert_eq!(
        c.chosen,
        FeatureSet::ENCODERS,
        "9 features, not 34: {}",
        c.text()
    );
}

#[test]
fn the_experts_choose_by_their_own_cross_validation() {
    let s = planted(Family::Raw, 3);
    let mut p = RecognitionParams::default();
    for gp in [&mut p.ds.gp, &mut p.gs.gp] {
        gp.capacity = 5;
        gp.tau = 2;
    }
    let scorer = ExpertsScorer {
        learner: SupervisedLearner::Ds,
        ds: &p.ds,
        gs: &p.gs,
    };
    let c = choose_features(&s, &scorer, "object", 3, 0, &Progress::new()).unwrap();
    assert_eq!(c.scored_by, MethodId::Ds);
    assert_eq!(c.chosen, FeatureSet::RAW, "{}", c.text());
    assert!(score(&c, FeatureSet::MOMENTS) <= NOISE_BAR, "{}", c.text());
}

#[test]
fn the_same_seed_gives_the_same_choice_and_scores() {
    let s = planted(Family::Raw, 4);
    let (a, b) = (temporal_svm_choice(&s, 7), temporal_svm_choice(&s, 7));
    assert_eq!(a.chosen, b.chosen);
    assert_eq!(a.candidates, b.candidates);
    // Another seed folds the grasps otherwise: the scores move, the choice does not.
    let other = temporal_svm_choice(&s, 8);
    assert_ne!(a.candidates, other.candidates);
    assert_eq!(other.chosen, FeatureSet::RAW);
}

#[test]
fn the_model_file_says_what_auto_chose_and_why() {
    let s = planted(Family::Raw, 5);
    let opts = ClassifierFitOptions {
        method: MethodId::Classifier(ClassifierId::TemporalSvm),
        features: Some(FeatureSet::AUTO),
        size: None,
        label_set: "object".into(),
        seed: 0,
    };
    let progress = Progress::new();
    let (opts, choice) = choose_classifier_features(&s, &opts, &progress).unwrap();
    assert_eq!(opts.features, Some(FeatureSet::RAW));
    let (model, secs) = fit_classifier(&s, &opts, &progress).unwrap();
    let mut file = classifier_file(model, &s, secs, Default::default());
    file.provenance.feature_choice = choice.clone();
    let back = ModelFile::from_json(&file.to_json(), "m.json").unwrap();
    assert_eq!(back.provenance.feature_choice, choice);
    assert!(choice.is_some());

    // The command line's `fit` chooses by default and keeps the choice in the file.
    let dir = common::temp_dir("auto-features");
    let (path, out) = (dir.join("planted.json"), dir.join("model.json"));
    save(&s, &path).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args(["fit", "temporal-svm"])
        .arg(&path)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("auto chose raw"), "{stdout}");
    let saved = models::load(&out).unwrap();
    let c = saved.provenance.feature_choice.expect("the choice is kept");
    assert_eq!(c.chosen, FeatureSet::RAW);
    assert_eq!(c.candidates.len(), 5, "all, moments, encoders, raw, change");
}
