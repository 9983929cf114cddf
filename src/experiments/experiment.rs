//! An experiment as units of work: the items (in the single-machine order), what every
//! item shares, one item, and the result assembled from the items' outputs; and the one
//! loop that computes items in parallel with progress and cancellation. The single-machine
//! functions (`stability::grid_search`, `run_robustness`, `run_clustering`,
//! `run_recognition`, `run_frontier`) and every shard of a sweep (`crate::sweep`) compute
//! the same items through one loop (`parallel::compute_items`), so a merged sweep equals the local run for the same
//! seeds.

use std::time::Instant;

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::ExperimentError;
use super::clustering::report::clustering_report;
use super::clustering::{
    ClusteringItem, ClusteringOutput, ClusteringParams, ClusteringPrep, assemble_clustering,
    clustering_item, clustering_items, prepare_clustering,
};
use super::frontier::{
    Frontier, FrontierItem, FrontierOutput, FrontierParams, FrontierPrep, assemble_frontier,
    frontier_item, frontier_items, prepare_frontier,
};
use super::recognition::report::recognition_report;
use super::recognition::{
    RecognitionParams, RecognitionPrep, RepetitionResult, assemble_recognition,
    prepare_recognition, recognition_repetition,
};
use super::result::AnalysisResult;
use super::robustness::report::robustness_report;
use super::robustness::{
    self, RobustnessParams, Task, TaskScores, assemble_robustness, robustness_task,
    robustness_tasks,
};
use super::stability::report::stability_report;
use super::stability::{
    self, DataOptions, GridTask, GridTaskOutput, StabilityData, StabilityOptions,
};
use crate::jobs::Progress;
use crate::session::Session;
use crate::svm::Folds;

/// Timings of the shards a merge gathers.
#[derive(Clone, Copy, Debug)]
pub struct WorkTime {
    /// Seconds of the shards' work, summed (the single-machine run's wall time on one
    /// machine, roughly, when the shards ran one after another).
    pub seconds: f64,
    /// Worker threads of the shards (the largest).
    pub threads: usize,
}

/// An experiment as units of work: implement this for its parameters to make it
/// shardable, and add a variant to [`crate::sweep::Experiment`] (and a line to its
/// dispatch macro).
pub trait Experiment: Serialize + DeserializeOwned + Clone + Sync {
    type Item: Serialize + DeserializeOwned + Clone + Send + Sync;
    type Prep: Sync;
    type Output: Serialize + DeserializeOwned + Send;
    type Result: Serialize;

    /// A short name for logs and the Slurm job ("stability", ...).
    fn name(&self) -> &'static str;
    /// Every item, in the order the single-machine run assembles them. Checks the
    /// parameters against the session.
    fn items(&self, session: &Session) -> Result<Vec<Self::Item>, ExperimentError>;
    /// Relative cost of an item (to balance shards and estimate their time), in
    /// CPU-seconds on a reference core for this session.
    fn cost(&self, session: &Session, item: &Self::Item) -> f64;
    /// What every item shares (computed once per shard).
    fn prepare(
        &self,
        session: &Session,
        progress: &Progress,
    ) -> Result<Self::Prep, ExperimentError>;
    fn compute(
        &self,
        session: &Session,
        prep: &Self::Prep,
        item: &Self::Item,
        progress: &Progress,
    ) -> Result<Self::Output, ExperimentError>;
    /// The single-machine result from every item's output (in item order).
    fn assemble(
        &self,
        session: &Session,
        items: &[Self::Item],
        outputs: Vec<Self::Output>,
        time: WorkTime,
        progress: &Progress,
    ) -> Result<Self::Result, ExperimentError>;
    /// The result as the workbench keeps it (for a project file); None when it is kept as
    /// its own file (frontiers: the `frontier --json` list).
    fn analysis(&self, session: &Session, result: &Self::Result) -> Option<AnalysisResult>;
}

/// Readings in a session (grasps × frames × taxels): the size the cost models scale with.
fn readings(session: &Session) -> f64 {
    let taxels: usize = session.sensors.iter().map(|s| s.layout.taxel_count()).sum();
    let frames = session.total_frames();
    (taxels.max(1) * frames.max(1)) as f64
}

/// Patches of the stability pipeline (grasps × sensors) times the taxels of a patch.
fn patch_values(session: &Session) -> f64 {
    let taxels: usize = session.sensors.iter().map(|s| s.layout.taxel_count()).sum();
    (session.grasps.len().max(1) * taxels.max(1)) as f64
}

// Cost constants: CPU-seconds per unit of work on a 2-core desktop, from the default grid
// on BTS3 (1,276 grasps × 72 taxels: about 520 CPU-s; docs/cluster.md), its robustness
// sweep with 10 repetitions (about 2,100 CPU-s over some 460 tasks) and DU's sweep on iCub
// (about 1,100 CPU-s over 900 runs on some 156,000 readings). Rough: the time limit adds a
// wide margin, and flags override it.
/// Stability: per (patch value × basis × gamma) of a grid task.
const STABILITY_COST: f64 = 1.2e-7;
/// Robustness: per task and reading.
const ROBUSTNESS_COST: f64 = 5.0e-5;
/// Clustering: per learning run and reading; a baseline run costs a tenth of it.
const CLUSTERING_COST: f64 = 8.0e-6;
/// Recognition: per repetition and reading (a repetition teaches and predicts every grasp).
const RECOGNITION_COST: f64 = 1.6e-5;
/// The baselines of the frontier (k-means, SOM, RBF SVM): per run and grasp.
const TABLE_COST: f64 = 1.0e-4;

/// The grasp-stability grid search and the pipeline after it.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct StabilitySweep {
    pub data: DataOptions,
    /// Must hold a grid: its tasks are the items.
    pub options: StabilityOptions,
}

pub struct StabilityPrep {
    data: StabilityData,
    folds: Folds,
}

impl StabilitySweep {
    fn spec(&self) -> Result<&stability::GridSpec, ExperimentError> {
        self.options.grid.as_ref().ok_or_else(|| {
            ExperimentError::param(
                "grid",
                "a stability sweep needs a grid (one configuration is one item)",
            )
        })
    }
}

impl Experiment for StabilitySweep {
    type Item = GridTask;
    type Prep = StabilityPrep;
    type Output = GridTaskOutput;
    type Result = stability::StabilityReport;

    fn name(&self) -> &'static str {
        "stability"
    }

    fn items(&self, session: &Session) -> Result<Vec<GridTask>, ExperimentError> {
        let spec = self.spec()?;
        let data = StabilityData::from_session(session, &self.data)?;
        stability::grid_folds(
            &data,
            spec,
            &self.options.settings,
            self.options.selection_cv,
        )?;
        Ok(spec.tasks())
    }

    fn cost(&self, session: &Session, item: &GridTask) -> f64 {
        let gammas = self.options.grid.as_ref().map_or(1, |g| g.gamma.len());
        STABILITY_COST * patch_values(session) * item.num_bases as f64 * gammas as f64
    }

    fn prepare(
        &self,
        session: &Session,
        _progress: &Progress,
    ) -> Result<StabilityPrep, ExperimentError> {
        let data = StabilityData::from_session(session, &self.data)?;
        let folds = stability::grid_folds(
            &data,
            self.spec()?,
            &self.options.settings,
            self.options.selection_cv,
        )?;
        Ok(StabilityPrep { data, folds })
    }

    fn compute(
        &self,
        _session: &Session,
        prep: &StabilityPrep,
        item: &GridTask,
        progress: &Progress,
    ) -> Result<GridTaskOutput, ExperimentError> {
        Ok(stability::grid_task(
            &prep.data,
            &self.spec()?.gamma,
            &prep.folds,
            &self.options.settings,
            *item,
            progress,
            &|_| {},
        )?)
    }

    fn assemble(
        &self,
        session: &Session,
        items: &[GridTask],
        outputs: Vec<GridTaskOutput>,
        time: WorkTime,
        progress: &Progress,
    ) -> Result<stability::StabilityReport, ExperimentError> {
        let start = Instant::now();
        let data = StabilityData::from_session(session, &self.data)?;
        let grid = stability::assemble_grid(
            self.spec()?,
            self.options.selection_cv,
            items,
            outputs,
            time.seconds,
            time.threads,
        );
        Ok(stability::finish(
            &data,
            &self.options,
            Some(grid),
            start,
            progress,
        )?)
    }

    fn analysis(
        &self,
        _session: &Session,
        r: &stability::StabilityReport,
    ) -> Option<AnalysisResult> {
        Some(stability_report(r))
    }
}

impl Experiment for RobustnessParams {
    type Item = Task;
    type Prep = robustness::Prepared;
    type Output = TaskScores;
    type Result = robustness::RobustnessResult;

    fn name(&self) -> &'static str {
        "robustness"
    }

    fn items(&self, session: &Session) -> Result<Vec<Task>, ExperimentError> {
        robustness_tasks(session, self)
    }

    fn cost(&self, session: &Session, _item: &Task) -> f64 {
        ROBUSTNESS_COST * readings(session)
    }

    fn prepare(
        &self,
        session: &Session,
        progress: &Progress,
    ) -> Result<Self::Prep, ExperimentError> {
        robustness::prepare(session, self, progress)
    }

    fn compute(
        &self,
        session: &Session,
        prep: &Self::Prep,
        item: &Task,
        progress: &Progress,
    ) -> Result<TaskScores, ExperimentError> {
        progress.checkpoint()?;
        robustness_task(session, self, prep, *item)
    }

    fn assemble(
        &self,
        session: &Session,
        items: &[Task],
        outputs: Vec<TaskScores>,
        time: WorkTime,
        _progress: &Progress,
    ) -> Result<Self::Result, ExperimentError> {
        // The shards' setup time is inside their seconds; the merge prepares nothing.
        Ok(assemble_robustness(
            session,
            self,
            items,
            &outputs,
            0.0,
            time.seconds,
            time.threads,
        ))
    }

    fn analysis(&self, session: &Session, r: &Self::Result) -> Option<AnalysisResult> {
        Some(robustness_report(&session.meta.name, r))
    }
}

impl Experiment for ClusteringParams {
    type Item = ClusteringItem;
    type Prep = ClusteringPrep;
    type Output = ClusteringOutput;
    type Result = crate::experiments::clustering::ClusteringResult;

    fn name(&self) -> &'static str {
        "clustering"
    }

    fn items(&self, session: &Session) -> Result<Vec<ClusteringItem>, ExperimentError> {
        self.validate()?;
        Ok(clustering_items(self, session.grasps.len()))
    }

    fn cost(&self, session: &Session, item: &ClusteringItem) -> f64 {
        let share = match item {
            // At most a run per threshold: the thresholds share their early learning.
            ClusteringItem::Order { .. } => self.thresholds.len() as f64,
            ClusteringItem::Baseline { .. } => 0.1,
        };
        CLUSTERING_COST * share * readings(session)
    }

    fn prepare(
        &self,
        session: &Session,
        _progress: &Progress,
    ) -> Result<ClusteringPrep, ExperimentError> {
        prepare_clustering(session, self)
    }

    fn compute(
        &self,
        _session: &Session,
        prep: &ClusteringPrep,
        item: &ClusteringItem,
        progress: &Progress,
    ) -> Result<ClusteringOutput, ExperimentError> {
        progress.checkpoint()?;
        clustering_item(self, prep, *item, progress)
    }

    fn assemble(
        &self,
        session: &Session,
        _items: &[ClusteringItem],
        outputs: Vec<ClusteringOutput>,
        time: WorkTime,
        _progress: &Progress,
    ) -> Result<Self::Result, ExperimentError> {
        let prep = prepare_clustering(session, self)?;
        Ok(assemble_clustering(self, prep, outputs, time.seconds))
    }

    fn analysis(&self, session: &Session, r: &Self::Result) -> Option<AnalysisResult> {
        Some(clustering_report(&session.meta.name, r))
    }
}

impl Experiment for RecognitionParams {
    type Item = usize;
    type Prep = RecognitionPrep;
    type Output = RepetitionResult;
    type Result = crate::experiments::recognition::RecognitionResult;

    fn name(&self) -> &'static str {
        "recognition"
    }

    fn items(&self, _session: &Session) -> Result<Vec<usize>, ExperimentError> {
        self.validate()?;
        Ok((0..self.reps).collect())
    }

    fn cost(&self, session: &Session, _item: &usize) -> f64 {
        RECOGNITION_COST * readings(session)
    }

    fn prepare(
        &self,
        session: &Session,
        _progress: &Progress,
    ) -> Result<RecognitionPrep, ExperimentError> {
        prepare_recognition(session, self)
    }

    fn compute(
        &self,
        session: &Session,
        prep: &RecognitionPrep,
        rep: &usize,
        progress: &Progress,
    ) -> Result<RepetitionResult, ExperimentError> {
        progress.checkpoint()?;
        recognition_repetition(self, session, prep, *rep, progress)
    }

    fn assemble(
        &self,
        session: &Session,
        _items: &[usize],
        outputs: Vec<RepetitionResult>,
        time: WorkTime,
        _progress: &Progress,
    ) -> Result<Self::Result, ExperimentError> {
        let prep = prepare_recognition(session, self)?;
        Ok(assemble_recognition(
            self,
            prep,
            outputs,
            time.seconds,
            None,
        ))
    }

    fn analysis(&self, session: &Session, r: &Self::Result) -> Option<AnalysisResult> {
        Some(recognition_report(&session.meta.name, r))
    }
}

/// The frontiers of one `frontier` command: the result is its `--json` list.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct FrontierSweep {
    pub frontiers: Vec<FrontierParams>,
}

/// An item of a frontier sweep: which frontier, and its item.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct FrontierSweepItem {
    pub frontier: usize,
    pub item: FrontierItem,
}

impl FrontierSweep {
    fn params(&self, i: usize) -> Result<&FrontierParams, ExperimentError> {
        self.frontiers
            .get(i)
            .ok_or_else(|| ExperimentError::Data(format!("frontier {i} is not in the plan")))
    }
}

impl Experiment for FrontierSweep {
    type Item = FrontierSweepItem;
    type Prep = Vec<FrontierPrep>;
    type Output = FrontierOutput;
    type Result = Vec<Frontier>;

    fn name(&self) -> &'static str {
        "frontier"
    }

    fn items(&self, session: &Session) -> Result<Vec<FrontierSweepItem>, ExperimentError> {
        if self.frontiers.is_empty() {
            return Err(ExperimentError::param(
                "frontiers",
                "a frontier sweep needs at least one method",
            ));
        }
        let mut out = Vec::new();
        for (frontier, p) in self.frontiers.iter().enumerate() {
            prepare_frontier(session, p).map_err(|e| match e {
                ExperimentError::InvalidParameter { name, reason } => {
                    ExperimentError::InvalidParameter {
                        name,
                        reason: format!("{}: {reason}", p.label()),
                    }
                }
                ExperimentError::Cancelled => ExperimentError::Cancelled,
                e => ExperimentError::Within {
                    what: p.label(),
                    source: crate::error::Kept::new(e),
                },
            })?;
            out.extend(
                frontier_items(p)
                    .into_iter()
                    .map(|item| FrontierSweepItem { frontier, item }),
            );
        }
        Ok(out)
    }

    fn cost(&self, session: &Session, it: &FrontierSweepItem) -> f64 {
        let grasps = session.grasps.len().max(1) as f64;
        match it.item {
            // A kernel evaluation costs about capacity × tau; the paper's 50 × 15 is one
            // repetition of `recognition`.
            FrontierItem::Recognition { capacity, tau, .. } => {
                RECOGNITION_COST * readings(session) * ((capacity * tau) as f64 / 750.0).max(0.05)
            }
            FrontierItem::Dictionary { num_bases, .. } => {
                let (gammas, reps) = self
                    .frontiers
                    .get(it.frontier)
                    .map_or((1, 1), |p| (p.gamma.len(), p.reps));
                STABILITY_COST * patch_values(session) * (num_bases * gammas * reps) as f64
            }
            // DU's experts grow as the threshold falls.
            FrontierItem::Threshold { threshold, .. } => {
                CLUSTERING_COST * readings(session) * (1.5 - threshold)
            }
            FrontierItem::Clusters { .. } | FrontierItem::Svm { .. } => TABLE_COST * grasps,
            // A registered method reads every step of every grasp, as the experts do.
            FrontierItem::Classifier { .. } => RECOGNITION_COST * readings(session),
        }
    }

    fn prepare(
        &self,
        session: &Session,
        _progress: &Progress,
    ) -> Result<Vec<FrontierPrep>, ExperimentError> {
        self.frontiers
            .iter()
            .map(|p| prepare_frontier(session, p))
            .collect()
    }

    fn compute(
        &self,
        session: &Session,
        prep: &Self::Prep,
        it: &FrontierSweepItem,
        progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        progress.checkpoint()?;
        let p = self.params(it.frontier)?;
        let prep = prep.get(it.frontier).ok_or_else(|| {
            ExperimentError::Data(format!("frontier {} is not prepared", it.frontier))
        })?;
        frontier_item(session, p, prep, &it.item, progress)
    }

    fn assemble(
        &self,
        session: &Session,
        items: &[FrontierSweepItem],
        outputs: Vec<FrontierOutput>,
        time: WorkTime,
        _progress: &Progress,
    ) -> Result<Vec<Frontier>, ExperimentError> {
        let mut per: Vec<(Vec<FrontierItem>, Vec<FrontierOutput>)> =
            vec![(Vec::new(), Vec::new()); self.frontiers.len()];
        for (it, out) in items.iter().zip(outputs) {
            let slot = per.get_mut(it.frontier).ok_or_else(|| {
                ExperimentError::Data(format!("frontier {} is not in the plan", it.frontier))
            })?;
            slot.0.push(it.item);
            slot.1.push(out);
        }
        // The shards' work is not split by frontier: each gets the sweep's seconds.
        self.frontiers
            .iter()
            .zip(per)
            .map(|(p, (items, outputs))| {
                assemble_frontier(&session.meta.name, p, &items, outputs, time.seconds)
            })
            .collect()
    }

    fn analysis(&self, _session: &Session, _result: &Self::Result) -> Option<AnalysisResult> {
        None
    }
}
