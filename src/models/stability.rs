//! The grasp-stability classifiers as models that leave their session: sparse coding of
//! the key-frame patches + a linear SVM on the concatenated codes (the first paper), and
//! the linear SVM on the key-frame values themselves (its baseline). Both read a grasp's
//! key-frame pressures, put them on the training scale under a [`Calibration`], and give
//! a decision value whose sign is the outcome (positive: failure).

use std::time::Instant;

use ndarray::{Array2, ArrayView2, s};
use serde::{Deserialize, Serialize};

use super::{Calibration, Model, ModelError, ModelFile, Provenance, SelectionScore, SessionRef};
use crate::catalogue::MethodId;
use crate::experiments::result::SizeReason;
use crate::experiments::stability::{
    self, PipelineInputs, StabilityData, StabilityModel, StabilityOptions, StabilityReport,
};
use crate::features::{KeyFramePatches, PatchScaling, Standardizer};
use crate::jobs::Progress;
use crate::session::Session;
use crate::sparse::Dictionary;
use crate::svm::LinearSvm;

/// A sensor as the model read it: its name and taxel count.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SensorShape {
    pub name: String,
    pub taxels: usize,
}

/// The dictionary and the coding penalty of the sparse pipeline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseCodes {
    pub dictionary: Dictionary,
    /// λ when coding (scikit-learn's convention, see `experiments::stability`).
    pub gamma: f64,
    /// What the SVM reads (files without the field read codes).
    #[serde(default)]
    pub inputs: PipelineInputs,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StabilityClassifier {
    pub sensors: Vec<SensorShape>,
    /// How the training session's pressures were scaled before the model read them.
    pub scaling: PatchScaling,
    /// Per-taxel mean and standard deviation of the training session's key frames (the
    /// image's columns: sensors side by side).
    pub taxel_stats: Standardizer,
    /// The dictionary (sparse coding + SVM); None: the SVM reads the scaled values.
    pub codes: Option<SparseCodes>,
    pub svm: LinearSvm,
    pub label_set: String,
    pub success_class: String,
    pub failure_class: String,
}

/// What fitting leaves besides the classifier: the scores it was selected with and its
/// size.
#[derive(Clone, Debug)]
pub struct StabilityFit {
    pub classifier: StabilityClassifier,
    pub selection: Vec<SelectionScore>,
    pub size: Vec<(String, usize)>,
    pub size_reason: SizeReason,
    pub parameters: Vec<(String, String)>,
    pub secs: f64,
}

impl StabilityFit {
    /// The recommended model of a `stability` run, with the scores it was reported with.
    pub fn from_report(
        session: &Session,
        data: &StabilityData,
        opts: &StabilityOptions,
        report: &StabilityReport,
    ) -> StabilityFit {
        let config = report.model.config;
        let e = &report.parsimonious;
        StabilityFit {
            classifier: StabilityClassifier::from_sparse(&report.model, data, session),
            selection: vec![
                pct_score(
                    report.kfold_cv.clone(),
                    "weighted success rate",
                    e.kfold.weighted_success_rate,
                ),
                pct_score(
                    report.objects_cv.clone(),
                    "weighted success rate",
                    e.objects.weighted_success_rate,
                ),
            ],
            size: vec![("num_bases".into(), config.num_bases)],
            size_reason: size_reason(opts, config.num_bases),
            parameters: parameters(opts, Some(config)),
            secs: report.secs,
        }
    }

    /// The model file of this fit on `session`.
    pub fn into_file(self, session: &Session, data: &StabilityData) -> ModelFile {
        let c = &self.classifier;
        let shape = format!("{} sensors × {} taxels", data.sensor_count(), data.dim());
        let features = match &c.codes {
            Some(codes) => format!(
                "key-frame patches ({shape}) coded on {} bases (gamma {}), concatenated{}",
                codes.dictionary.num_bases(),
                codes.gamma,
                match codes.inputs {
                    PipelineInputs::Codes => "",
                    PipelineInputs::CodesAndRaw => ", followed by the scaled key-frame values",
                }
            ),
            None => format!("key-frame values ({shape})"),
        };
        let normalisation = match c.scaling {
            PatchScaling::ZScorePerTaxel => {
                "each taxel z-scored over the training session's key frames (a new session: see its calibration); the SVM's inputs z-scored on its training grasps"
            }
            PatchScaling::None => {
                "pressures as recorded (a new session: see its calibration); the SVM's inputs z-scored on its training grasps"
            }
        };
        let provenance = Provenance {
            method: c.method(),
            parameters: self.parameters,
            size: self.size,
            size_reason: self.size_reason,
            session: SessionRef::of(session),
            features,
            normalisation: normalisation.into(),
            label_set: c.label_set.clone(),
            classes: vec![c.success_class.clone(), c.failure_class.clone()],
            trained_at: Provenance::now(),
            train_seconds: self.secs,
            selection: self.selection,
            feature_choice: None,
        };
        ModelFile::new(provenance, Model::Stability(self.classifier))
    }
}

fn size_reason(opts: &StabilityOptions, num_bases: usize) -> SizeReason {
    match (&opts.grid, opts.size_reason) {
        (Some(_), _) => SizeReason::Recommended,
        (None, Some(reason)) => reason,
        (None, None) => SizeReason::of(
            &num_bases,
            None,
            &StabilityOptions::default().single.num_bases,
        ),
    }
}

fn parameters(opts: &StabilityOptions, config: Option<stability::Config>) -> Vec<(String, String)> {
    let s = &opts.settings;
    let mut out = vec![
        ("svm C".to_string(), s.svm.c.to_string()),
        ("svm loss".to_string(), format!("{:?}", s.svm.loss)),
        ("seed".to_string(), s.cv_seed.to_string()),
    ];
    if let Some(c) = config {
        out.extend([
            ("inputs".to_string(), s.inputs.to_string()),
            ("beta".to_string(), c.beta.to_string()),
            ("gamma".to_string(), c.gamma.to_string()),
            (
                "dictionary penalty".to_string(),
                format!("{:?}", s.dictionary.penalty),
            ),
        ]);
    }
    out
}

impl StabilityClassifier {
    fn new(
        data: &StabilityData,
        session: &Session,
        codes: Option<SparseCodes>,
        svm: LinearSvm,
    ) -> StabilityClassifier {
        StabilityClassifier {
            sensors: sensor_shapes(session),
            scaling: data.patches.scaling,
            taxel_stats: Standardizer::fit(data.patches.pressures.view()),
            codes,
            svm,
            label_set: data.label_set.clone(),
            success_class: data.success_name.clone(),
            failure_class: data.failure_name.clone(),
        }
    }

    /// The sparse pipeline's model trained on every grasp of `data` (from `session`).
    pub fn from_sparse(
        model: &StabilityModel,
        data: &StabilityData,
        session: &Session,
    ) -> StabilityClassifier {
        let codes = SparseCodes {
            dictionary: model.dictionary.clone(),
            gamma: model.config.gamma,
            inputs: model.inputs,
        };
        Self::new(data, session, Some(codes), model.svm.clone())
    }

    pub fn method(&self) -> MethodId {
        match self.codes {
            Some(_) => MethodId::SparseSvm,
            None => MethodId::RawSvm,
        }
    }

    /// Features per grasp: an image's values, or its patches' codes side by side.
    pub fn feature_count(&self) -> usize {
        let values: usize = self.sensors.iter().map(|s| s.taxels).sum();
        match &self.codes {
            Some(c) => {
                let codes = self.sensors.len() * c.dictionary.num_bases();
                match c.inputs {
                    PipelineInputs::Codes => codes,
                    PipelineInputs::CodesAndRaw => codes + values,
                }
            }
            None => values,
        }
    }

    /// Refuse a session with other sensors than the model's.
    pub fn check_session(&self, session: &Session) -> Result<(), ModelError> {
        let found = sensor_shapes(session);
        if found != self.sensors {
            let list = |v: &[SensorShape]| {
                v.iter()
                    .map(|s| format!("{} ({} taxels)", s.name, s.taxels))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            return Err(ModelError::Mismatch(format!(
                "the model reads sensors {}; the session has {}",
                list(&self.sensors),
                list(&found)
            )));
        }
        Ok(())
    }

    /// The scaling the model applies to the session's key-frame pressures (grasps ×
    /// values) under `calibration`: the training statistics, or the new session's mapped
    /// onto them.
    fn scaler(
        &self,
        pressures: ArrayView2<f64>,
        calibration: Calibration,
    ) -> Result<Option<Standardizer>, ModelError> {
        let Some(range) = calibration.grasps(pressures.nrows())? else {
            return Ok(match self.scaling {
                PatchScaling::ZScorePerTaxel => Some(self.taxel_stats.clone()),
                PatchScaling::None => None,
            });
        };
        let new = Standardizer::fit(pressures.slice(s![range, ..]));
        Ok(Some(match self.scaling {
            PatchScaling::ZScorePerTaxel => new,
            // Unscaled models read pressures: move the new statistics onto the training
            // ones, v ↦ (v − m_new) / sd_new · sd_train + m_train.
            PatchScaling::None => {
                let t = &self.taxel_stats;
                Standardizer {
                    mean: (0..new.dim())
                        .map(|j| new.mean[j] - t.mean[j] * new.sd[j] / t.sd[j])
                        .collect(),
                    sd: (0..new.dim()).map(|j| new.sd[j] / t.sd[j]).collect(),
                }
            }
        }))
    }

    /// The SVM's input for every grasp of `session` (grasps × features).
    pub fn features(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Array2<f64>, ModelError> {
        self.check_session(session)?;
        let patches = KeyFramePatches::from_session(session, PatchScaling::None)
            .map_err(stability::StabilityError::from)?;
        let images = match self.scaler(patches.pressures.view(), calibration)? {
            Some(scaler) => scaler.transform(patches.pressures.view()),
            None => patches.pressures,
        };
        let Some(codes) = &self.codes else {
            return Ok(images);
        };
        let sensors = self.sensors.len();
        let rows = images.nrows() * sensors;
        let dim = images.ncols() / sensors;
        let x = images
            .into_shape_with_order((rows, dim))
            .map_err(ModelError::Shape)?;
        let coded = codes
            .dictionary
            .encode(x.view(), codes.gamma)
            .map_err(stability::StabilityError::sparse)?;
        Ok(codes.inputs.features(coded, x.view(), sensors))
    }

    /// The decision value of every grasp (positive: failure).
    pub fn decisions(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<f64>, ModelError> {
        let x = self.features(session, calibration)?;
        Ok(x.rows().into_iter().map(|r| self.svm.decision(r)).collect())
    }

    /// Check a loaded classifier: every length agrees and every value is finite, so that
    /// nothing read from a file fails later.
    pub fn validate(&self) -> Result<(), ModelError> {
        let f = |name: &str| format!("model.{name}");
        if self.sensors.is_empty() {
            return Err(ModelError::field(f("sensors"), "no sensors"));
        }
        if let Some(s) = self.sensors.iter().find(|s| s.taxels == 0) {
            return Err(ModelError::field(
                f("sensors"),
                format!("sensor {:?} has no taxels", s.name),
            ));
        }
        let values: usize = self.sensors.iter().map(|s| s.taxels).sum();
        let stats = &self.taxel_stats;
        if stats.mean.len() != values || stats.sd.len() != values {
            return Err(ModelError::field(
                f("taxel_stats"),
                format!(
                    "{} means and {} deviations where the sensors have {values} taxels",
                    stats.mean.len(),
                    stats.sd.len()
                ),
            ));
        }
        if stats.mean.iter().any(|v| !v.is_finite())
            || stats.sd.iter().any(|v| !(v.is_finite() && *v > 0.0))
        {
            return Err(ModelError::field(
                f("taxel_stats"),
                "means must be finite and deviations finite and positive",
            ));
        }
        if let Some(c) = &self.codes {
            let dim = self.sensors[0].taxels;
            if self.sensors.iter().any(|s| s.taxels != dim) {
                return Err(ModelError::field(
                    f("sensors"),
                    "one dictionary codes every sensor's patch: sensors must share a taxel count",
                ));
            }
            let atoms = &c.dictionary.atoms;
            if atoms.nrows() == 0 || atoms.ncols() != dim {
                return Err(ModelError::field(
                    f("codes.dictionary.atoms"),
                    format!(
                        "{} × {} where at least 1 basis × {dim} taxels is needed",
                        atoms.nrows(),
                        atoms.ncols()
                    ),
                ));
            }
            if atoms.iter().any(|v| !v.is_finite()) {
                return Err(ModelError::field(
                    f("codes.dictionary.atoms"),
                    "values must be finite",
                ));
            }
            if !(c.gamma.is_finite() && c.gamma >= 0.0) {
                return Err(ModelError::field(
                    f("codes.gamma"),
                    "must be finite and ≥ 0",
                ));
            }
        }
        let n = self.feature_count();
        if self.svm.weights.len() != n {
            return Err(ModelError::field(
                f("svm.weights"),
                format!(
                    "{} weights where the model's features are {n}",
                    self.svm.weights.len()
                ),
            ));
        }
        if self.svm.weights.iter().any(|v| !v.is_finite()) || !self.svm.intercept.is_finite() {
            return Err(ModelError::field(
                f("svm"),
                "weights and intercept must be finite",
            ));
        }
        for (name, class) in [
            ("success_class", &self.success_class),
            ("failure_class", &self.failure_class),
        ] {
            if class.is_empty() {
                return Err(ModelError::field(f(name), "is empty"));
            }
        }
        if self.success_class == self.failure_class {
            return Err(ModelError::field(
                f("failure_class"),
                "equals the success class",
            ));
        }
        Ok(())
    }
}

fn sensor_shapes(session: &Session) -> Vec<SensorShape> {
    session
        .sensors
        .iter()
        .map(|s| SensorShape {
            name: s.name.clone(),
            taxels: s.layout.taxel_count(),
        })
        .collect()
}

fn pct_score(protocol: String, name: &str, value: f64) -> SelectionScore {
    SelectionScore {
        protocol,
        name: name.into(),
        value,
    }
}

/// Fit a grasp-stability method on every grasp of `data` (prepared from `session`) with
/// the analyses' options: the grid's parsimonious choice when `opts` has a grid, else its
/// single configuration; scored under both protocols for the provenance.
pub fn fit_stability(
    method: MethodId,
    session: &Session,
    data: &StabilityData,
    opts: &StabilityOptions,
    progress: &Progress,
) -> Result<StabilityFit, ModelError> {
    let t0 = Instant::now();
    let s = &opts.settings;
    let scores = |kfold: &crate::svm::CvResult, objects: &crate::svm::CvResult| {
        vec![
            pct_score(
                opts.kfold.describe(),
                "weighted success rate",
                kfold.weighted_success_rate,
            ),
            pct_score(
                opts.objects.describe(),
                "weighted success rate",
                objects.weighted_success_rate,
            ),
        ]
    };
    match method {
        MethodId::SparseSvm => {
            let (config, dictionary) = match &opts.grid {
                Some(spec) => {
                    let g = stability::grid_search(data, spec, s, opts.selection_cv, progress)?;
                    (g.parsimonious.config, Some(g.parsimonious_dictionary))
                }
                None => (opts.single, None),
            };
            let (evaluation, dictionary) = stability::evaluate_config(
                data,
                config,
                s,
                opts.kfold,
                opts.objects,
                dictionary,
                progress,
            )?;
            let model = StabilityModel::train(data, config, dictionary, s)?;
            Ok(StabilityFit {
                classifier: StabilityClassifier::from_sparse(&model, data, session),
                selection: scores(&evaluation.kfold, &evaluation.objects),
                size: vec![("num_bases".into(), config.num_bases)],
                size_reason: size_reason(opts, config.num_bases),
                parameters: parameters(opts, Some(config)),
                secs: t0.elapsed().as_secs_f64(),
            })
        }
        MethodId::RawSvm => {
            let baseline = stability::baseline(data, s, opts.kfold, opts.objects)?;
            progress
                .checkpoint()
                .map_err(stability::StabilityError::from)?;
            let svm = s
                .svm
                .fit(data.images().view(), &data.labels)
                .map_err(stability::StabilityError::svm)?;
            Ok(StabilityFit {
                classifier: StabilityClassifier::new(data, session, None, svm),
                selection: scores(&baseline.kfold, &baseline.objects),
                size: Vec::new(),
                size_reason: SizeReason::PaperDefault,
                parameters: parameters(opts, None),
                secs: t0.elapsed().as_secs_f64(),
            })
        }
        other @ (MethodId::Ds
        | MethodId::Gs
        | MethodId::Du
        | MethodId::Gu
        | MethodId::KMeans
        | MethodId::Som
        | MethodId::RbfSvm
        | MethodId::Classifier(_)) => Err(ModelError::Param(format!(
            "{} is not a grasp-stability method (sparse-svm, raw-svm)",
            other.key()
        ))),
    }
}
