//! What a robustness run sweeps: the perturbations, the methods' set-ups and their validation.

use super::*;

/// One perturbation and its strengths (from mild to severe).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sweep {
    pub perturbation: Perturbation,
    pub strengths: Vec<f64>,
}

/// The grasp-stability pipeline's fixed configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StabilitySetup {
    /// The default is BTS3's recommended (parsimonious) model of the `default` grid
    /// selected by 10-fold (docs/grasp-stability.md): K = 27, beta = gamma = 0.25.
    pub config: Config,
    /// Stratified folds of the protocol (the paper: 10).
    pub folds: usize,
    pub settings: PipelineSettings,
    pub data: DataOptions,
}

impl Default for StabilitySetup {
    fn default() -> Self {
        StabilitySetup {
            config: Config {
                num_bases: 27,
                beta: 0.25,
                gamma: 0.25,
            },
            folds: 10,
            settings: PipelineSettings::default(),
            data: DataOptions::default(),
        }
    }
}

/// The recognition family's settings: DS/GS as [`crate::experiments::recognition::RecognitionParams`],
/// DU/GU as [`crate::experiments::clustering::ClusteringParams`] at one threshold, and the baselines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecognitionSetup {
    pub features: FeatureSet,
    pub test_fraction: f64,
    pub label_set: String,
    pub ds: DsParams,
    pub gs: GsParams,
    /// DU's and GU's novelty thresholds (defaults chosen on the sample iCub session, where
    /// they give the most informative partition of a 0.05–0.95 sweep: DU 0.2, 42
    /// effective clusters, NMI 0.39; GU 0.02, 11.4 effective clusters, NMI 0.83 over 5
    /// orders).
    pub du_threshold: f64,
    pub gu_threshold: f64,
    pub gu_aggregate: GuAggregate,
    /// GU's clusters take part in the re-assignment once trained on this many grasps
    /// (`GuParams::min_grasps`); files saved before it existed kept every cluster.
    #[serde(default = "every_gu_cluster")]
    pub gu_min_grasps: usize,
    /// Clusters / SOM units of k-means and the SOM (None: the number of classes).
    pub clusters: Option<usize>,
    /// The RBF SVM (the baselines' default C = 10, gamma = 0.01 on z-scored features).
    pub svm: KernelSvmParams,
    pub svm_folds: usize,
}

impl Default for RecognitionSetup {
    fn default() -> Self {
        RecognitionSetup {
            features: FeatureSet::ALL,
            test_fraction: 0.2,
            label_set: "object".into(),
            ds: DsParams::default(),
            gs: GsParams::default(),
            du_threshold: 0.2,
            gu_threshold: 0.02,
            gu_aggregate: GuAggregate::Mean,
            gu_min_grasps: GuParams::default().min_grasps,
            clusters: None,
            svm: KernelSvmParams::default(),
            svm_folds: 5,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessParams {
    pub family: Family,
    pub methods: Vec<MethodId>,
    pub sweeps: Vec<Sweep>,
    /// Repetitions per strength (seeded folds / orders / perturbations).
    pub reps: usize,
    /// The break point is where the mean score falls below this share of the clean score.
    pub fraction: f64,
    pub seed: u64,
    /// Clamp perturbed readings to the sensor's raw range.
    pub saturate: bool,
    pub stability: StabilitySetup,
    pub recognition: RecognitionSetup,
}

impl RobustnessParams {
    /// Every method and perturbation of `family` with their default strengths.
    pub fn defaults(family: Family) -> Self {
        RobustnessParams {
            family,
            methods: family.methods(),
            sweeps: Perturbation::ALL
                .iter()
                .filter(|p| family == Family::Stability || **p != Perturbation::NewObjects)
                .map(|&p| Sweep {
                    perturbation: p,
                    strengths: p.default_strengths(family),
                })
                .collect(),
            reps: 5,
            fraction: 0.9,
            seed: 0,
            saturate: true,
            stability: StabilitySetup::default(),
            recognition: RecognitionSetup::default(),
        }
    }

    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.reps == 0 {
            return Err(ExperimentError::param("reps", "must be at least 1"));
        }
        if !(self.fraction > 0.0 && self.fraction <= 1.0) {
            return Err(ExperimentError::param(
                "fraction",
                format!("must lie in (0, 1], got {}", self.fraction),
            ));
        }
        if self.methods.is_empty() {
            return Err(ExperimentError::param(
                "methods",
                "name at least one method",
            ));
        }
        if let Some(m) = self.methods.iter().find(|m| Family::of(**m) != self.family) {
            return Err(ExperimentError::param(
                "methods",
                format!(
                    "{} does not belong to the {:?} family",
                    m.key(),
                    self.family
                ),
            ));
        }
        if self.sweeps.is_empty() {
            return Err(ExperimentError::param(
                "perturbations",
                "name at least one perturbation",
            ));
        }
        for sw in &self.sweeps {
            if sw.strengths.is_empty() {
                return Err(ExperimentError::param(
                    "strengths",
                    format!("{}: no strengths", sw.perturbation.key()),
                ));
            }
            for &s in &sw.strengths {
                match sw.perturbation.session_kind() {
                    Some(kind) => PerturbParams::new(kind, s, 0).validate()?,
                    None => sw.perturbation.check_protocol_strength(s)?,
                }
            }
        }
        let st = &self.stability;
        if st.folds < 2 {
            return Err(ExperimentError::param("folds", "must be at least 2"));
        }
        if st.config.num_bases == 0 {
            return Err(ExperimentError::param("num_bases", "must be at least 1"));
        }
        for (name, v) in [("beta", st.config.beta), ("gamma", st.config.gamma)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(ExperimentError::param(
                    name,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        st.settings
            .svm
            .validate()
            .map_err(|source| ExperimentError::Parameter {
                name: "svm",
                source,
            })?;
        let rc = &self.recognition;
        if !(rc.test_fraction > 0.0 && rc.test_fraction < 1.0) {
            return Err(ExperimentError::param(
                "test_fraction",
                "must lie in (0, 1)",
            ));
        }
        rc.ds.validate()?;
        rc.gs.validate()?;
        for (name, t) in [
            ("du_threshold", rc.du_threshold),
            ("gu_threshold", rc.gu_threshold),
        ] {
            if !(0.0..=1.0).contains(&t) {
                return Err(ExperimentError::param(
                    name,
                    format!("must lie in [0, 1], got {t}"),
                ));
            }
        }
        if rc.gu_min_grasps == 0 {
            return Err(ExperimentError::param(
                "gu_min_grasps",
                "must be at least 1",
            ));
        }
        if rc.clusters == Some(0) {
            return Err(ExperimentError::param("clusters", "must be at least 1"));
        }
        if rc.svm_folds < 2 {
            return Err(ExperimentError::param("svm_folds", "must be at least 2"));
        }
        rc.svm
            .validate()
            .map_err(|source| ExperimentError::KernelSvmParameter {
                name: "svm",
                source,
            })?;
        Ok(())
    }
}
