//! The session as the pipeline reads it: the grasps' scaled key-frame patches, their
//! outcomes and objects ([`StabilityData`]), and what the SVM reads of a grasp
//! ([`PipelineInputs`]).

use super::*;

/// Which labels mean failure, and how patches are scaled.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DataOptions {
    /// Label set holding the grasp outcome (default: the first whose name mentions
    /// outcome, stability, slip, success or failure; else the first).
    pub label_set: Option<String>,
    /// Class meaning a failed grasp (default: the first class whose name mentions fail,
    /// slip, drop, unstable or lost; else the second class).
    pub failure_class: Option<String>,
    pub scaling: PatchScaling,
}

/// A session prepared for the pipeline.
#[derive(Clone, Debug)]
pub struct StabilityData {
    pub session_name: String,
    pub patches: KeyFramePatches,
    /// Scaled patches, one row per (grasp, sensor), grasp-major.
    pub x: Array2<f64>,
    /// true = failure, per grasp.
    pub labels: Vec<bool>,
    /// Object index of every grasp into `object_names`.
    pub objects: Vec<usize>,
    pub object_names: Vec<String>,
    pub label_set: String,
    pub success_name: String,
    pub failure_name: String,
    /// Layout of the first sensor (used to draw basis images).
    pub layout: Option<Layout>,
    /// Index into `Session::grasps` of every grasp.
    pub grasp_ids: Vec<usize>,
}

impl StabilityData {
    pub fn from_session(session: &Session, opts: &DataOptions) -> Result<Self, StabilityError> {
        if session.label_sets.is_empty() {
            return Err(StabilityError::data("the session has no label sets".into()));
        }
        let set = match &opts.label_set {
            Some(name) => session.label_set(name).ok_or_else(|| {
                StabilityError::param(format!(
                    "no label set {name:?}; the session has {:?}",
                    session
                        .label_sets
                        .iter()
                        .map(|l| &l.name)
                        .collect::<Vec<_>>()
                ))
            })?,
            None => session
                .label_sets
                .iter()
                .position(|l| {
                    let n = l.name.to_lowercase();
                    ["outcome", "stab", "slip", "success", "fail"]
                        .iter()
                        .any(|k| n.contains(k))
                })
                .unwrap_or(0),
        };
        let ls = &session.label_sets[set];
        let failure = match &opts.failure_class {
            Some(name) => ls.classes.iter().position(|c| c == name).ok_or_else(|| {
                StabilityError::param(format!(
                    "label set {:?} has no class {name:?} (classes {:?})",
                    ls.name, ls.classes
                ))
            })?,
            None => ls
                .classes
                .iter()
                .position(|c| {
                    let c = c.to_lowercase();
                    ["fail", "slip", "drop", "unstable", "lost"]
                        .iter()
                        .any(|k| c.contains(k))
                })
                .or((ls.classes.len() == 2).then_some(1))
                .ok_or_else(|| {
                    StabilityError::param(format!(
                        "cannot tell which class of {:?} {:?} is the failure: name it",
                        ls.name, ls.classes
                    ))
                })?,
        };
        let mut labels = Vec::with_capacity(session.grasps.len());
        for (g, grasp) in session.grasps.iter().enumerate() {
            let l = *grasp.labels.get(set).ok_or_else(|| {
                StabilityError::data(format!("grasp {g} has no label in set {:?}", ls.name))
            })?;
            labels.push(l == failure);
        }
        let object_names = session.objects();
        let objects = session
            .grasps
            .iter()
            .map(|g| {
                object_names
                    .iter()
                    .position(|o| *o == g.object)
                    .unwrap_or(0)
            })
            .collect();
        let patches = KeyFramePatches::from_session(session, opts.scaling)?;
        let success_name = if ls.classes.len() == 2 {
            ls.classes[1 - failure].clone()
        } else {
            format!("not {}", ls.classes[failure])
        };
        let data = StabilityData {
            session_name: session.meta.name.clone(),
            x: patches.patches(),
            patches,
            labels,
            objects,
            object_names,
            label_set: ls.name.clone(),
            success_name,
            failure_name: ls.classes[failure].clone(),
            layout: session.sensors.first().map(|s| s.layout.clone()),
            grasp_ids: (0..session.grasps.len()).collect(),
        };
        data.check()?;
        Ok(data)
    }

    fn check(&self) -> Result<(), StabilityError> {
        let failures = self.labels.iter().filter(|l| **l).count();
        if failures == 0 || failures == self.labels.len() {
            return Err(StabilityError::data(format!(
                "all {} grasps have the same outcome; the classifier needs both",
                self.labels.len()
            )));
        }
        Ok(())
    }

    /// The same data restricted to some grasps (in the given order); the scaling is
    /// refitted on them. For scaling studies and held-out tests.
    pub fn subset(&self, grasps: &[usize]) -> Result<Self, StabilityError> {
        let pressures = crate::svm::gather(self.patches.pressures.view(), grasps);
        let scaler = match self.patches.scaling {
            PatchScaling::ZScorePerTaxel => Some(Standardizer::fit(pressures.view())),
            PatchScaling::None => None,
        };
        let patches = KeyFramePatches {
            pressures,
            scaler,
            ..self.patches.clone()
        };
        let data = StabilityData {
            x: patches.patches(),
            patches,
            labels: grasps.iter().map(|&g| self.labels[g]).collect(),
            objects: grasps.iter().map(|&g| self.objects[g]).collect(),
            grasp_ids: grasps.iter().map(|&g| self.grasp_ids[g]).collect(),
            ..self.clone()
        };
        data.check()?;
        Ok(data)
    }

    pub fn grasp_count(&self) -> usize {
        self.labels.len()
    }

    pub fn sensor_count(&self) -> usize {
        self.patches.sensor_count()
    }

    pub fn dim(&self) -> usize {
        self.patches.dim
    }

    /// The SVM's features of every grasp from its patches' codes under `inputs`.
    pub fn features(&self, codes: Array2<f64>, inputs: PipelineInputs) -> Array2<f64> {
        inputs.features(codes, self.x.view(), self.sensor_count())
    }

    /// The scaled key-frame images (grasps × sensors·taxels): the raw-electrode baseline's
    /// features.
    pub fn images(&self) -> Array2<f64> {
        self.patches.images()
    }
}

/// What the SVM reads of a grasp.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PipelineInputs {
    /// The patches' sparse codes side by side (the first paper).
    #[default]
    #[serde(rename = "codes")]
    Codes,
    /// The codes followed by the scaled key-frame values they were coded from. The L1
    /// code of a patch keeps a few bases and shrinks them, so a small offset of a taxel can
    /// change which bases it keeps; the values beside it give the SVM the offset's linear
    /// part. Chosen on the training files (10-fold and leave-objects-out, both BioTac
    /// sessions), see docs/held-out.md.
    #[serde(rename = "codes+raw")]
    CodesAndRaw,
}

impl PipelineInputs {
    pub fn name(self) -> &'static str {
        match self {
            PipelineInputs::Codes => "codes",
            PipelineInputs::CodesAndRaw => "codes+raw",
        }
    }

    /// The SVM's features of every grasp from its patches' codes (G·S × K) and the scaled
    /// patches they were coded from (G·S × n).
    pub fn features(
        self,
        codes: Array2<f64>,
        patches: ArrayView2<f64>,
        sensors: usize,
    ) -> Array2<f64> {
        let codes = concatenated_codes(codes, sensors);
        match self {
            PipelineInputs::Codes => codes,
            PipelineInputs::CodesAndRaw => {
                let values = patches
                    .as_standard_layout()
                    .into_owned()
                    .into_shape_with_order((codes.nrows(), sensors * patches.ncols()))
                    .expect("patches hold whole grasps");
                ndarray::concatenate![ndarray::Axis(1), codes, values]
            }
        }
    }
}

impl std::fmt::Display for PipelineInputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A grasp's feature vector: its patches' codes side by side (G·S × K → G × S·K).
pub fn concatenated_codes(codes: Array2<f64>, sensors: usize) -> Array2<f64> {
    let (rows, k) = codes.dim();
    let codes = if codes.is_standard_layout() {
        codes
    } else {
        codes.as_standard_layout().into_owned()
    };
    codes
        .into_shape_with_order((rows / sensors, sensors * k))
        .expect("codes hold whole grasps")
}
