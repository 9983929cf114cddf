//! What a model says about a session, as signals and groups: a recognition model's class
//! probabilities after every step of every grasp (with the decided class, so that a
//! comparison can plot how a model became sure and group grasps by correct and wrong), a
//! stability model's SVM decision value at each grasp's key frame, and a clustering
//! model's clusters and its novelty of each grasp so far after every step.

use super::align::Event;
use super::groups::Groups;
use super::signal::StepOutputs;
use crate::models::clustering::cluster_name;
use crate::models::{
    Calibration, ClusterModel, Model, ModelError, ModelFile, SequenceModel, StabilityClassifier,
};
use crate::session::Session;

/// What one model says about every grasp of a session.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelReading {
    /// The model in a few words ("DS").
    pub model: String,
    pub outputs: Vec<StepOutputs>,
    pub classes: Vec<String>,
    /// Each grasp's true class among the model's classes (None where the session lacks
    /// the model's label set or the class).
    pub truth: Vec<Option<usize>>,
    /// The class decided from the whole grasp.
    pub predicted: Vec<Option<usize>>,
    /// The model's clusters of the session's grasps (a clustering model).
    pub clusters: Option<Groups>,
}

/// What model `file` (called `model`, e.g. "DS") says about `session`: DS/GS class
/// probabilities after every step, a stability model's decision value, DU/GU clusters and
/// novelty after every step.
pub fn read_model(
    model: &str,
    file: &ModelFile,
    session: &Session,
) -> Result<ModelReading, ModelError> {
    match &file.model {
        Model::Sequences(m) => read_sequences(model, m, session),
        Model::Stability(c) => read_stability(model, file, c, session),
        Model::Clusters(m) => read_clusters(model, m, session),
        Model::TableOne(_) | Model::Classifier(_) => Err(ModelError::Mismatch(format!(
            "{model} has no output per step, decision value or clusters to compare"
        ))),
    }
}

/// A stability model's SVM decision value (positive: failure) of every grasp, at its key
/// frame (the frame the model reads), by the models' own prediction path.
fn read_stability(
    model: &str,
    file: &ModelFile,
    c: &StabilityClassifier,
    session: &Session,
) -> Result<ModelReading, ModelError> {
    let rows = crate::models::predict(file, session, Calibration::None)?;
    let classes = vec![c.success_class.clone(), c.failure_class.clone()];
    let index = |name: &str| classes.iter().position(|k| k == name);
    let mut per_grasp: Vec<Vec<f64>> = (session.grasps.iter())
        .map(|g| vec![f64::NAN; g.frames.len()])
        .collect();
    for r in &rows {
        let key = Event::KeyFrame.frame(session, r.grasp);
        if let Some(v) = per_grasp.get_mut(r.grasp).and_then(|v| v.get_mut(key)) {
            *v = r.decision;
        }
    }
    let mut truth = vec![None; session.grasps.len()];
    let mut predicted = vec![None; session.grasps.len()];
    for r in &rows {
        truth[r.grasp] = r.truth.as_deref().and_then(index);
        predicted[r.grasp] = index(&r.predicted);
    }
    Ok(ModelReading {
        model: model.into(),
        outputs: vec![StepOutputs {
            name: format!("{model} · SVM decision value"),
            unit: String::new(),
            per_grasp,
        }],
        classes,
        truth,
        predicted,
        clusters: None,
    })
}

/// A clustering model's cluster of every grasp (the experts are not changed), as groups
/// named as predictions name them ("cluster 3"), only the clusters some grasp is in.
fn read_clusters(
    model: &str,
    m: &ClusterModel,
    session: &Session,
) -> Result<ModelReading, ModelError> {
    let assigned = m.assign(session, Calibration::None)?;
    let mut used = assigned.clone();
    used.sort_unstable();
    used.dedup();
    let of: Vec<Option<usize>> = (assigned.iter())
        .map(|c| used.binary_search(c).ok())
        .collect();
    let names = used.iter().map(|&c| cluster_name(c)).collect();
    let novelty = StepOutputs {
        name: format!("{model} · novelty"),
        unit: String::new(),
        per_grasp: m.novelty_steps(session, Calibration::None)?,
    };
    Ok(ModelReading {
        model: model.into(),
        outputs: vec![novelty],
        classes: Vec::new(),
        truth: vec![None; session.grasps.len()],
        predicted: vec![None; session.grasps.len()],
        clusters: Some(Groups::assigned(&format!("cluster ({model})"), names, &of)),
    })
}

/// DS or GS experts `m` (called `model`) on `session`, normalised as they were trained.
pub fn read_sequences(
    model: &str,
    m: &SequenceModel,
    session: &Session,
) -> Result<ModelReading, ModelError> {
    let predictions = m.predict(session, Calibration::None)?;
    let set = session.label_set(&m.label_set);
    let truth: Vec<Option<usize>> = (session.grasps.iter())
        .map(|g| {
            let set = set?;
            let name = &session.label_sets[set].classes.get(*g.labels.get(set)?)?;
            m.classes.iter().position(|c| c == *name)
        })
        .collect();
    let probability = |class: &dyn Fn(usize) -> Option<usize>| -> Vec<Vec<f64>> {
        (predictions.iter().enumerate())
            .map(|(g, p)| match class(g) {
                Some(c) if c < p.distributions.ncols() => p.distributions.column(c).to_vec(),
                _ => Vec::new(),
            })
            .collect()
    };
    let mut outputs = vec![StepOutputs {
        name: format!("{model} · true class probability"),
        unit: String::new(),
        per_grasp: probability(&|g| truth[g]),
    }];
    for (c, name) in m.classes.iter().enumerate() {
        outputs.push(StepOutputs {
            name: format!("{model} · probability of {name}"),
            unit: String::new(),
            per_grasp: probability(&|_| Some(c)),
        });
    }
    Ok(ModelReading {
        model: model.into(),
        outputs,
        classes: m.classes.clone(),
        truth,
        predicted: predictions.iter().map(|p| Some(p.class)).collect(),
        clusters: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalogue::MethodId;
    use crate::experiments::clustering::{ClusteringParams, UnsupervisedLearner};
    use crate::experiments::stability::{Config, DataOptions, StabilityData, StabilityOptions};
    use crate::features::FeatureSet;
    use crate::jobs::Progress;
    use crate::models::{ClusterFitOptions, cluster_file, fit_clusters, fit_stability};
    use crate::session::{SubsetSpec, simulate, subset};

    #[test]
    fn a_stability_models_decision_value_is_its_own_at_each_key_frame() {
        let session = simulate::grasp_stability(0);
        let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
        let opts = StabilityOptions {
            single: Config {
                num_bases: 8,
                beta: 1.0,
                gamma: 1.0,
            },
            ..Default::default()
        };
        let fit = fit_stability(MethodId::RawSvm, &session, &data, &opts, &Progress::new());
        let file = fit.unwrap().into_file(&session, &data);
        let Model::Stability(c) = &file.model else {
            panic!("a stability model")
        };
        let want = c.decisions(&session, Calibration::None).unwrap();
        let r = read_model("raw SVM", &file, &session).unwrap();
        assert_eq!(r.outputs.len(), 1);
        assert_eq!(r.outputs[0].name, "raw SVM · SVM decision value");
        assert_eq!(
            r.classes,
            [c.success_class.clone(), c.failure_class.clone()]
        );
        let set = session.label_set(&c.label_set).unwrap();
        for (g, grasp) in session.grasps.iter().enumerate() {
            let v = &r.outputs[0].per_grasp[g];
            assert_eq!(v.len(), grasp.frames.len());
            // The decision, bit for bit, at the key frame; nothing at the other frames.
            let key = grasp.key_frame.min(v.len() - 1);
            assert_eq!(v[key].to_bits(), want[g].to_bits(), "grasp {g}");
            assert!((v.iter().enumerate()).all(|(k, x)| k == key || x.is_nan()));
            assert_eq!(
                r.predicted[g],
                Some(usize::from(want[g] > 0.0)),
                "grasp {g}"
            );
            let truth = &session.label_sets[set].classes[grasp.labels[set]];
            assert_eq!(r.truth[g].map(|t| &r.classes[t]), Some(truth));
        }
    }

    #[test]
    fn a_clustering_models_clusters_are_groups_named_as_its_predictions() {
        let session = simulate::object_recognition(1);
        let spec = SubsetSpec {
            objects: session.objects()[..3].to_vec(),
            trials: (1..=5).into(),
            labels: Vec::new(),
        };
        let part = subset(&session, &spec, "part").unwrap();
        let opts = ClusterFitOptions {
            method: MethodId::Du,
            features: FeatureSet::ALL,
            label_set: "object".into(),
            threshold: 0.4,
            seed: 2,
            params: ClusteringParams::for_learner(UnsupervisedLearner::Du),
        };
        let (model, _) = fit_clusters(&part, &opts).unwrap();
        let file = cluster_file(model, &part, 0.0, None);
        let r = read_model("DU", &file, &part).unwrap();
        let groups = r.clusters.expect("clusters");
        let predicted = crate::models::predict(&file, &part, Calibration::None).unwrap();
        assert_eq!(groups.title, "cluster (DU)");
        for p in &predicted {
            let g = groups.of[p.grasp].expect("every grasp in a cluster");
            assert_eq!(groups.names[g], p.predicted);
        }
        // Only clusters some grasp is in, each once.
        assert!(groups.sizes().iter().all(|&n| n > 0));
        assert!(r.classes.is_empty());
        // The novelty of each grasp so far after every step: the last step's is the whole
        // grasp's assessment, bit for bit.
        assert_eq!(r.outputs.len(), 1);
        assert_eq!(r.outputs[0].name, "DU · novelty");
        let Model::Clusters(m) = &file.model else {
            panic!("a clustering")
        };
        let feats = m.inputs.read(&part, Some(Calibration::None)).unwrap();
        let crate::models::clustering::Clusterer::Du(du) = &m.clusterer else {
            panic!("DU")
        };
        for (g, grasp) in part.grasps.iter().enumerate() {
            let v = &r.outputs[0].per_grasp[g];
            assert_eq!(v.len(), grasp.frames.len(), "grasp {g}");
            use crate::learners::{Du, NoveltyLearner};
            let a = du.clone().assess(feats.sequences[g].view()).unwrap();
            let whole = <Du as NoveltyLearner>::novelty(&a);
            assert_eq!(v.last().unwrap().to_bits(), whole.to_bits(), "grasp {g}");
        }
        let mut names = groups.names.clone();
        names.dedup();
        assert_eq!(names.len(), groups.names.len());
    }
}
