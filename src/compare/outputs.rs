//! A recognition model's per-step outputs on a session: after every step of every grasp,
//! the true class's probability and each class's, with the decided class, so that a
//! comparison can plot how a model became sure and group grasps by correct and wrong.

use super::signal::StepOutputs;
use crate::models::{Calibration, ModelError, SequenceModel};
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
    })
}
