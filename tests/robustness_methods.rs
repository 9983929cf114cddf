//! Each method's clean robustness score is the score of its own experiment's protocol on
//! the same seed (repetition r of a sweep uses stream r of the seed): DS and GS are the
//! supervised protocol's "final 20 %", DU and GU the clustering run at their threshold,
//! sparse coding + SVM and the raw SVM the stability experiment's pooled 10-fold weighted
//! success rate, k-means and the SOM the NMI of their clusters of the z-scored Table I
//! features. A method answered by another's object fails here.

use std::path::Path;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::cluster::{SequentialKMeansParams, scores};
use tactile_workbench::experiments::clustering::{
    ClusteringParams, UnsupervisedLearner, run_clustering, som_setup,
};
use tactile_workbench::experiments::labels::session_labels;
use tactile_workbench::experiments::recognition::{
    RecognitionParams, SupervisedLearner, run_recognition,
};
use tactile_workbench::experiments::robustness::{
    CLUSTER_STREAM, Family, Perturbation, RobustnessParams, RobustnessResult, Sweep, run_robustness,
};
use tactile_workbench::experiments::stability::{
    CvScheme, PipelineSettings, StabilityData, baseline, evaluate_config,
};
use tactile_workbench::features::table_one::session_features;
use tactile_workbench::features::{FeatureSet, Normalisation, Normaliser};
use tactile_workbench::jobs::Progress;
use tactile_workbench::rng::Rng;
use tactile_workbench::session::Session;

const SEED: u64 = 3;

fn sample(name: &str) -> Session {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample-sessions")
        .join(name);
    tactile_workbench::session::load(&path).unwrap()
}

/// The clean protocol once (one gain strength stands for the sweep a run needs).
fn clean_run(s: &Session, mut p: RobustnessParams, methods: Vec<MethodId>) -> RobustnessResult {
    p.methods = methods;
    p.reps = 1;
    p.seed = SEED;
    p.sweeps = vec![Sweep {
        perturbation: Perturbation::Gain,
        strengths: vec![1.0],
    }];
    run_robustness(s, &p, &Progress::new()).unwrap()
}

#[test]
fn supervised_and_unsupervised_scores_are_their_protocols() {
    let s = sample("object-recognition.json");
    let mut p = RobustnessParams::defaults(Family::Recognition);
    p.recognition.features = FeatureSet::MOMENTS;
    let rc = p.recognition.clone();
    let r = clean_run(
        &s,
        p,
        vec![MethodId::Ds, MethodId::Gs, MethodId::Du, MethodId::Gu],
    );
    for (m, learner) in [
        (MethodId::Ds, SupervisedLearner::Ds),
        (MethodId::Gs, SupervisedLearner::Gs),
    ] {
        let direct = run_recognition(
            &s,
            &RecognitionParams {
                learner,
                features: rc.features,
                reps: 1,
                seed: SEED,
                ..Default::default()
            },
            &Progress::new(),
        )
        .unwrap();
        assert_eq!(r.clean_score(m), Some(direct.summary.final_20.mean), "{m}");
    }
    for (m, learner, threshold) in [
        (MethodId::Du, UnsupervisedLearner::Du, rc.du_threshold),
        (MethodId::Gu, UnsupervisedLearner::Gu, rc.gu_threshold),
    ] {
        let direct = run_clustering(
            &s,
            &ClusteringParams {
                learner,
                features: rc.features,
                thresholds: vec![threshold],
                reps: 1,
                seed: SEED,
                gu_min_grasps: rc.gu_min_grasps,
                baseline_max_k: 0,
                choose_threshold: None,
                ..ClusteringParams::default()
            },
            &Progress::new(),
        )
        .unwrap();
        assert_eq!(r.clean_score(m), Some(direct.runs[0].nmi), "{m}");
    }
}

#[test]
fn stability_scores_are_the_stability_experiments() {
    let s = sample("grasp-stability.json");
    let mut p = RobustnessParams::defaults(Family::Stability);
    p.stability.folds = 5;
    p.stability.config.num_bases = 10;
    let st = p.stability.clone();
    let r = clean_run(&s, p, vec![MethodId::SparseSvm, MethodId::RawSvm]);
    let data = StabilityData::from_session(&s, &st.data).unwrap();
    let settings = PipelineSettings {
        cv_seed: Rng::stream(SEED, 0).next_u64(),
        ..st.settings.clone()
    };
    let kfold = CvScheme::KFold { k: st.folds };
    let objects = CvScheme::LeaveObjectsOut { folds: None };
    let (sparse, _) = evaluate_config(
        &data,
        st.config,
        &settings,
        kfold,
        objects,
        None,
        &Progress::new(),
    )
    .unwrap();
    let raw = baseline(&data, &settings, kfold, objects).unwrap();
    let sparse = sparse.kfold.weighted_success_rate;
    let raw = raw.kfold.weighted_success_rate;
    assert_ne!(
        sparse, raw,
        "the two pipelines must differ for this check to bite"
    );
    assert_eq!(r.clean_score(MethodId::SparseSvm), Some(sparse));
    assert_eq!(r.clean_score(MethodId::RawSvm), Some(raw));
}

#[test]
fn k_means_and_som_scores_are_their_clusters_of_the_table_one_features() {
    let s = sample("object-recognition.json");
    let p = RobustnessParams::defaults(Family::Recognition);
    let r = clean_run(&s, p, vec![MethodId::KMeans, MethodId::Som]);
    // The clean repetition clusters every grasp's z-scored Table I row into as many
    // clusters as there are objects.
    let raw = session_features(&s).unwrap();
    let z = Normaliser::fit(Normalisation::ZScore, raw.view())
        .and_then(|n| n.transform(raw.view()))
        .unwrap();
    let (labels, classes) = session_labels(&s, "object").unwrap();
    let (k, seed) = (classes.len(), Rng::stream(SEED, CLUSTER_STREAM).next_u64());
    let kmeans = SequentialKMeansParams { k, passes: 1, seed }
        .fit(z.view())
        .and_then(|m| m.assign(z.view()))
        .unwrap();
    let som = som_setup(k, seed)
        .fit(z.view())
        .and_then(|m| m.assign(z.view()))
        .unwrap();
    let (kmeans, som) = (scores(&labels, &kmeans).nmi, scores(&labels, &som).nmi);
    assert_ne!(kmeans, som, "the two must differ for this check to bite");
    assert_eq!(r.clean_score(MethodId::KMeans), Some(kmeans));
    assert_eq!(r.clean_score(MethodId::Som), Some(som));
}
