//! Evaluation of a chosen configuration, the raw baseline, and the model for prediction.

use super::*;

/// A configuration evaluated under both protocols.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Evaluation {
    pub config: Config,
    pub dictionary_objective: f64,
    pub dictionary_iterations: usize,
    pub dictionary_secs: f64,
    pub sparsity: f64,
    pub active_bases_per_patch: f64,
    pub kfold: CvResult,
    pub objects: CvResult,
}

/// The pipeline's model trained on every grasp, for predicting new grasps: the session's
/// scaling, the dictionary, gamma and the SVM on the concatenated codes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StabilityModel {
    pub config: Config,
    pub scaler: Option<Standardizer>,
    pub sensors: usize,
    pub dim: usize,
    pub dictionary: Dictionary,
    /// What the SVM reads (older results, without the field, read codes).
    #[serde(default)]
    pub inputs: PipelineInputs,
    pub svm: LinearSvm,
}

impl StabilityModel {
    /// Train on all grasps of `data` with a given dictionary.
    pub fn train(
        data: &StabilityData,
        config: Config,
        dictionary: Dictionary,
        settings: &PipelineSettings,
    ) -> Result<Self, StabilityError> {
        let codes = dictionary
            .encode(data.x.view(), config.gamma)
            .map_err(StabilityError::sparse)?;
        let features = data.features(codes, settings.inputs);
        let svm = settings
            .svm
            .fit(features.view(), &data.labels)
            .map_err(StabilityError::svm)?;
        Ok(StabilityModel {
            config,
            scaler: data.patches.scaler.clone(),
            sensors: data.sensor_count(),
            dim: data.dim(),
            dictionary,
            inputs: settings.inputs,
            svm,
        })
    }

    /// Predict failure (true) from a grasp's key-frame pressures, sensors side by side,
    /// scaled exactly as the training session was.
    pub fn predict_failure(&self, pressures: ArrayView1<f64>) -> Result<bool, StabilityError> {
        let expected = self.sensors * self.dim;
        if pressures.len() != expected {
            return Err(StabilityError::data(format!(
                "{} pressures where the model expects {expected}",
                pressures.len()
            )));
        }
        let mut img = vec![0.0; expected];
        match &self.scaler {
            Some(s) => s.transform_into(pressures, &mut img),
            None => img
                .iter_mut()
                .zip(pressures.iter())
                .for_each(|(o, v)| *o = *v),
        }
        let patches = ArrayView2::from_shape((self.sensors, self.dim), &img)
            .map_err(|e| StabilityError::Method(e.into()))?;
        let codes = self
            .dictionary
            .encode(patches, self.config.gamma)
            .map_err(StabilityError::sparse)?;
        let features = self.inputs.features(codes, patches, self.sensors);
        Ok(self.svm.predict(features.row(0)))
    }
}

/// Learn the dictionary of `config` and evaluate it under k-fold and leave-objects-out.
pub fn evaluate_config(
    data: &StabilityData,
    config: Config,
    settings: &PipelineSettings,
    kfold: CvScheme,
    objects: CvScheme,
    dictionary: Option<Dictionary>,
    progress: &Progress,
) -> Result<(Evaluation, Dictionary), StabilityError> {
    let t0 = Instant::now();
    let (dict, objective, iterations) = match dictionary {
        Some(d) => {
            let codes = d
                .encode(data.x.view(), config.beta)
                .map_err(StabilityError::sparse)?;
            let f = crate::sparse::objective(
                data.x.view(),
                d.atoms.view(),
                codes.view(),
                crate::sparse::CodePenalty::L1,
                config.beta,
            );
            (d, f, 0)
        }
        None => {
            let params = DictionaryParams {
                num_bases: config.num_bases,
                beta: config.beta,
                ..settings.dictionary.clone()
            };
            let fit = params
                .fit_within(data.x.view(), progress)
                .map_err(StabilityError::sparse)?;
            (fit.dictionary, fit.objective, fit.iterations)
        }
    };
    let dictionary_secs = t0.elapsed().as_secs_f64();
    progress.checkpoint()?;
    let kf = kfold.folds(data, settings.cv_seed)?;
    let ScoredCodes {
        features,
        sparsity: (sparsity, active),
        cv: kcv,
        ..
    } = score_codes(data, &dict, config.gamma, &kf, settings)?;
    let of = objects.folds(data, settings.cv_seed)?;
    let ocv = cross_validate(features.view(), &data.labels, &of, &settings.svm)
        .map_err(StabilityError::svm)?;
    Ok((
        Evaluation {
            config,
            dictionary_objective: objective,
            dictionary_iterations: iterations,
            dictionary_secs,
            sparsity,
            active_bases_per_patch: active,
            kfold: kcv,
            objects: ocv,
        },
        dict,
    ))
}

/// The baseline: the linear SVM on the scaled raw key-frame values (every taxel of
/// every sensor), under both protocols.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Baseline {
    pub features: usize,
    pub kfold: CvResult,
    pub objects: CvResult,
}

pub fn baseline(
    data: &StabilityData,
    settings: &PipelineSettings,
    kfold: CvScheme,
    objects: CvScheme,
) -> Result<Baseline, StabilityError> {
    let x = data.images();
    let kf = kfold.folds(data, settings.cv_seed)?;
    let of = objects.folds(data, settings.cv_seed)?;
    Ok(Baseline {
        features: x.ncols(),
        kfold: cross_validate(x.view(), &data.labels, &kf, &settings.svm)
            .map_err(StabilityError::svm)?,
        objects: cross_validate(x.view(), &data.labels, &of, &settings.svm)
            .map_err(StabilityError::svm)?,
    })
}
