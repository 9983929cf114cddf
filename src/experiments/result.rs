//! What an analysis leaves behind, independent of the method: its parameters, its scores,
//! its timings and its figures. The workbench keeps these per session and saves them in
//! a project file, so re-opening a project shows the same figures without re-training;
//! the speed-against-accuracy chart and "export all" read them too.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::figure_id::FigureId;
pub use super::links::{GraspCode, GraspLinks, LinkedItem, PatchCode};
use crate::features::sequence::FeatureSet;
use crate::figures::{
    ErrorDisplay, ErrorRange, Figure, FigureEntry, FigureSet, Series, SeriesStyle,
};

/// Which analysis produced a result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AnalysisKind {
    /// Sparse coding + linear SVM grasp-stability pipeline (first paper).
    Stability,
    /// Supervised OIESGP recognition, DS or GS (second paper).
    Recognition,
    /// Unsupervised OIESGP clustering, DU or GU, with k-means and SOM (second paper).
    Clustering,
    /// Offline baselines (k-means, SOM, RBF SVM on the Table I features).
    Baselines,
    /// Where the methods fail: score against perturbation strength, with break points.
    Robustness,
}

impl AnalysisKind {
    pub fn title(self) -> &'static str {
        match self {
            AnalysisKind::Stability => "Grasp stability",
            AnalysisKind::Recognition => "Object recognition",
            AnalysisKind::Clustering => "Clustering",
            AnalysisKind::Baselines => "Baselines",
            AnalysisKind::Robustness => "Robustness",
        }
    }
}

/// One trained model or experiment, as data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnalysisResult {
    pub kind: AnalysisKind,
    /// The method and its key parameters in a few words, e.g. "DS, all features".
    pub label: String,
    /// Name of the session it was computed on.
    pub session: String,
    pub parameters: BTreeMap<String, String>,
    /// Named scores (as in the papers: "weighted success rate", "accuracy (all)", ...).
    pub scores: Vec<(String, f64)>,
    /// The score the speed-against-accuracy chart uses, with its name.
    pub headline: Option<(String, f64)>,
    /// Training time in seconds (whole fit), and prediction time per sample.
    pub train_seconds: f64,
    pub predict_seconds_per_sample: Option<f64>,
    /// Seconds since the Unix epoch when it was computed.
    pub created: u64,
    pub figures: Vec<(FigureId, Figure)>,
    /// Figures a view shows on demand when the user selects part of a figure.
    #[serde(default)]
    pub details: Vec<FigureDetails>,
    /// The grasps behind the parts of figures and detail figures (confusion cells, basis
    /// images, contingency cells).
    #[serde(default)]
    pub links: Vec<GraspLinks>,
    /// Grasp stability: the model's view of every grasp of the session.
    #[serde(default)]
    pub grasp_codes: Vec<GraspCode>,
    /// The model size used and why (None for results without a size, and in projects
    /// saved before sizes were recorded).
    #[serde(default)]
    pub model_size: Option<ModelSize>,
    /// Scores of a model on a session it did not train on (None: within one session).
    /// Such scores are never compared with cross-validated ones as if they were alike.
    #[serde(default)]
    pub held_out: Option<HeldOut>,
    /// The catalogue's methods the result trained, so that the window finds a result by
    /// method rather than by a parameter's text (results saved before have none).
    #[serde(default)]
    pub methods: Vec<crate::catalogue::MethodId>,
}

/// Where a held-out result's model trained and how the tested session was calibrated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldOut {
    pub trained_on: String,
    pub trained_grasps: usize,
    pub tested_on: String,
    pub tested_grasps: usize,
    pub calibration: String,
}

impl HeldOut {
    /// "trained on A (n grasps), tested on B (m grasps), calibration session".
    pub fn text(&self) -> String {
        format!(
            "trained on {} ({} grasps), tested on {} ({} grasps), calibration {}",
            self.trained_on,
            self.trained_grasps,
            self.tested_on,
            self.tested_grasps,
            self.calibration
        )
    }
}

/// Why a model has its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SizeReason {
    /// The cheapest size within one standard error of the best on the session (a frontier
    /// or the grid search's one-standard-error rule).
    Recommended,
    /// The paper's size.
    #[default]
    PaperDefault,
    /// Set by the user.
    User,
    /// A registered method's own default.
    MethodDefault,
}

impl SizeReason {
    /// Why a model has `size`: it is the recommended one, else the paper's, else the user's
    /// (a size is named by what it is, whoever set it).
    pub fn of<T: PartialEq>(size: &T, recommended: Option<&T>, paper: &T) -> SizeReason {
        if recommended == Some(size) {
            SizeReason::Recommended
        } else if size == paper {
            SizeReason::PaperDefault
        } else {
            SizeReason::User
        }
    }

    pub fn text(self) -> &'static str {
        match self {
            SizeReason::Recommended => "recommended",
            SizeReason::PaperDefault => "paper default",
            SizeReason::User => "user's",
            SizeReason::MethodDefault => "method's default",
        }
    }
}

/// A model's size knobs in words ("capacity 5, tau 1") and why they were used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelSize {
    pub knobs: String,
    pub reason: SizeReason,
}

impl ModelSize {
    /// "capacity 5, tau 1 (recommended)".
    pub fn text(&self) -> String {
        format!("{} ({})", self.knobs, self.reason.text())
    }
}

/// Detail figures selected by interacting with one of a result's figures: a click on an
/// image of an image grid (key = the image's index), or the marker dragged along a
/// chart's x axis (key = the x value; the nearest key is shown).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FigureDetails {
    /// The figure (in `AnalysisResult::figures`) whose interaction selects.
    pub figure: FigureId,
    /// What is selected, in words, e.g. "basis" or "novelty threshold".
    pub selector: String,
    pub items: Vec<(f64, Figure)>,
}

impl FigureDetails {
    /// Index of the item whose key is `key` (up to rounding of the key's decimal text).
    pub fn at(&self, key: f64) -> Option<usize> {
        self.items.iter().position(|(k, _)| (k - key).abs() < 1e-9)
    }

    /// Index of the item whose key is nearest to `key`.
    pub fn nearest(&self, key: f64) -> Option<usize> {
        (0..self.items.len()).min_by(|&a, &b| {
            (self.items[a].0 - key)
                .abs()
                .total_cmp(&(self.items[b].0 - key).abs())
        })
    }
}

impl AnalysisResult {
    pub fn score(&self, name: &str) -> Option<f64> {
        self.scores.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// The figure `id` of this result, if it has it.
    pub fn figure(&self, id: FigureId) -> Option<&Figure> {
        self.figures.iter().find(|(n, _)| *n == id).map(|(_, f)| f)
    }

    /// The detail figures selected through figure `id`, if it has any.
    pub fn details_of(&self, id: FigureId) -> Option<&FigureDetails> {
        self.details.iter().find(|d| d.figure == id)
    }

    /// The links of figure `id` (`detail`: of that item of its detail figures).
    pub fn links_of(&self, id: FigureId, detail: Option<usize>) -> Option<&GraspLinks> {
        self.links
            .iter()
            .find(|l| l.figure == id && l.detail == detail)
    }

    /// The grasp-stability model's view of session grasp `grasp`.
    pub fn grasp_code(&self, grasp: usize) -> Option<&GraspCode> {
        self.grasp_codes.iter().find(|c| c.grasp == grasp)
    }

    /// Whether every link names a figure (or detail item) of this result and a part it has.
    pub(crate) fn check_links(&self) -> Result<(), super::links::LinkError> {
        for l in &self.links {
            let figure = match l.detail {
                None => self.figure(l.figure),
                Some(i) => self
                    .details_of(l.figure)
                    .and_then(|d| d.items.get(i))
                    .map(|(_, f)| f),
            };
            let Some(figure) = figure else {
                return Err(super::links::LinkError::NoFigure {
                    figure: l.figure,
                    detail: l.detail,
                });
            };
            l.check_against(figure)?;
        }
        Ok(())
    }
}

pub fn now_unix() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}

/// A UTC date "YYYY-MM-DD hh:mm" from Unix seconds (civil-from-days, no time-zone data).
pub fn date_text(unix: u64) -> String {
    let days = (unix / 86_400) as i64;
    let secs = unix % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}",
        secs / 3600,
        secs / 60 % 60
    )
}

/// The distinct values, ascending: the axes of a grid-search map.
pub fn distinct_sorted(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for v in values {
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// A name for files and folders: lower-case ASCII letters and digits, every other run of
/// characters one dash ("BTS3 (palm down)" → "bts3-palm-down").
pub fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_matches('-').to_string()
}

/// The file name (without extension) of figure `figure` of result `r`, the `i`-th result:
/// `<number>-<label>[-<size>]-<figure>`. One name whether the figure is exported alone or
/// with every other, and two results of one method that differ only in size say so.
pub fn export_name(i: usize, r: &AnalysisResult, figure: FigureId) -> String {
    let label = slug(&r.label);
    let size = r
        .model_size
        .as_ref()
        .map(|m| slug(&m.knobs))
        .filter(|k| !k.is_empty() && !label.contains(k.as_str()))
        .map_or(String::new(), |k| format!("-{k}"));
    format!("{:02}-{label}{size}-{}", i + 1, slug(figure.key()))
}

/// Every figure of `results`, named for export by [`export_name`].
pub fn figure_set(results: &[AnalysisResult]) -> FigureSet {
    let mut entries: Vec<FigureEntry> = Vec::new();
    for (i, r) in results.iter().enumerate() {
        for (name, figure) in &r.figures {
            let mut parameters = r.parameters.clone();
            parameters.insert("method".into(), r.label.clone());
            entries.push(FigureEntry {
                name: export_name(i, r, *name),
                figure: figure.clone(),
                parameters,
                session: r.session.clone(),
                date: date_text(r.created),
            });
        }
    }
    FigureSet { entries }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TimeAxis {
    /// The whole fit.
    #[default]
    Training,
    /// One prediction (a time step for the online learners).
    Prediction,
}

impl TimeAxis {
    fn seconds(self, r: &AnalysisResult) -> Option<f64> {
        match self {
            TimeAxis::Training => Some(r.train_seconds),
            TimeAxis::Prediction => r.predict_seconds_per_sample,
        }
    }
}

/// (time, score, score name) of a result the chart can place: its headline, or for a
/// held-out result its first score (weighted success rate, accuracy or purity).
fn charted(r: &AnalysisResult, axis: TimeAxis) -> Option<(f64, f64, &str)> {
    let (name, score) = match (&r.headline, &r.held_out) {
        (Some((n, v)), _) => (n.as_str(), *v),
        (None, Some(_)) => r.scores.first().map(|(n, v)| (n.as_str(), *v))?,
        (None, None) => return None,
    };
    let t = axis.seconds(r)?;
    (t > 0.0 && t.is_finite() && score.is_finite()).then_some((t, score, name))
}

/// The speed-against-accuracy chart and, for each of its series, the results its points
/// stand for (none for a front).
pub struct SpeedChart {
    pub figure: Figure,
    pub sources: Vec<Vec<usize>>,
}

/// Speed against accuracy: every result with a headline score and a time on `axis` (log
/// scale), each point labelled with its method. Only like is compared with like: each
/// score kind of each session is a series with its own Pareto front, and held-out scores
/// (a model tested on a session it did not train on) are series of their own, never
/// joined to a front.
pub fn speed_accuracy(results: &[AnalysisResult], axis: TimeAxis) -> Option<SpeedChart> {
    speed_chart(results, axis, None)
}

/// One score of one session: what one speed chart compares (accuracy and a weighted
/// success rate, or two sessions' accuracies, are not one axis).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScoreKind {
    pub session: String,
    pub score: String,
}

impl ScoreKind {
    pub fn text(&self) -> String {
        format!("{} · {}", self.score, self.session)
    }
}

/// The score kinds `results` can chart on `axis`, in order of first appearance.
pub fn score_kinds(results: &[AnalysisResult], axis: TimeAxis) -> Vec<ScoreKind> {
    let mut kinds: Vec<ScoreKind> = Vec::new();
    for r in results {
        if let Some((_, _, score)) = charted(r, axis)
            && !kinds
                .iter()
                .any(|k| k.session == r.session && k.score == score)
        {
            kinds.push(ScoreKind {
                session: r.session.clone(),
                score: score.to_string(),
            });
        }
    }
    kinds
}

/// Speed against accuracy of one score kind: its trained models' front and its held-out
/// results, the score on the y axis and the session in the title.
pub fn speed_accuracy_of(
    results: &[AnalysisResult],
    axis: TimeAxis,
    kind: &ScoreKind,
) -> Option<SpeedChart> {
    speed_chart(results, axis, Some(kind))
}

fn speed_chart(
    results: &[AnalysisResult],
    axis: TimeAxis,
    kind: Option<&ScoreKind>,
) -> Option<SpeedChart> {
    use crate::figures::{Axis, Series, pareto_front, series_color};
    /// Points that may share a front: (session, score name, held out).
    type Group<'a> = (&'a str, &'a str, bool);
    // Each group's result indices, in order of first appearance.
    let mut groups: Vec<(Group, Vec<usize>)> = Vec::new();
    for (i, r) in results.iter().enumerate() {
        let Some((_, _, name)) = charted(r, axis) else {
            continue;
        };
        if kind.is_some_and(|k| k.session != r.session || k.score != name) {
            continue;
        }
        let key = (r.session.as_str(), name, r.held_out.is_some());
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, members)) => members.push(i),
            None => groups.push((key, vec![i])),
        }
    }
    if groups.is_empty() {
        return None;
    }
    let sessions: std::collections::BTreeSet<&str> =
        groups.iter().map(|((s, _, _), _)| *s).collect();
    // Times in the unit their longest reads best in (µs for a per-step prediction).
    let longest = (groups.iter().flat_map(|(_, m)| m))
        .filter_map(|&i| charted(&results[i], axis).map(|(t, _, _)| t))
        .fold(0.0, f64::max);
    let (unit, per_second) = crate::figures::legibility::time_unit(longest);
    let mut series = Vec::new();
    let mut sources = Vec::new();
    for (g, ((session, score, held_out), members)) in groups.iter().enumerate() {
        let mut name = if *held_out {
            format!("{score}, held out")
        } else {
            score.to_string()
        };
        if sessions.len() > 1 {
            name = format!("{name} · {session}");
        }
        let color = series_color(g);
        let points: Vec<(f64, f64)> = members
            .iter()
            .filter_map(|&i| charted(&results[i], axis).map(|(t, v, _)| (t * per_second, v)))
            .collect();
        let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        if !held_out && members.len() > 1 {
            let front = pareto_front(&x, &y);
            series.push(
                Series::new(
                    format!("{name}: Pareto front"),
                    front.iter().map(|&i| x[i]).collect(),
                    front.iter().map(|&i| y[i]).collect(),
                )
                .color(color)
                .part_of(name.clone()),
            );
            sources.push(Vec::new());
        }
        // Each point says what it is: method, size (two runs of one method differ by it)
        // and, held out, where its model trained.
        let labels = members
            .iter()
            .map(|&i| {
                let r = &results[i];
                let mut text = r.label.clone();
                if let Some(m) = &r.model_size {
                    text = format!("{text}, {}", m.knobs);
                }
                match &r.held_out {
                    Some(h) => format!("{text} (trained on {})", h.trained_on),
                    None => text,
                }
            })
            .collect();
        series.push(
            Series::new(name, x, y)
                .style(SeriesStyle::Markers)
                .color(color)
                .labels(labels),
        );
        sources.push(members.clone());
    }
    let (title, x, subtitle) = match axis {
        TimeAxis::Training => (
            "Speed against accuracy",
            Axis::new("training time", unit),
            "each model's headline score; a front per score and session, held-out scores apart",
        ),
        TimeAxis::Prediction => (
            "Prediction speed against accuracy",
            Axis::new("prediction time per step or sample", unit),
            "models that time their predictions; a front per score and session, held-out \
             scores apart",
        ),
    };
    let (title, y) = match kind {
        Some(k) => (format!("{title} · {}", k.session), Axis::new(&k.score, "")),
        None => (title.to_string(), Axis::new("score", "")),
    };
    Some(SpeedChart {
        figure: Figure::chart(title, x.log(), y, series).subtitle(subtitle),
        sources,
    })
}

/// The speed-against-accuracy charts that have points, one per time axis and score kind,
/// with their figure names.
pub fn speed_accuracy_figures(results: &[AnalysisResult]) -> Vec<(String, Figure)> {
    let mut out = Vec::new();
    for (axis, name) in [
        (TimeAxis::Training, "speed-against-accuracy"),
        (TimeAxis::Prediction, "prediction-speed-against-accuracy"),
    ] {
        for k in score_kinds(results, axis) {
            if let Some(c) = speed_accuracy_of(results, axis, &k) {
                let file = format!("{name}-{}-{}", slug(&k.session), slug(&k.score));
                out.push((file, c.figure));
            }
        }
    }
    out
}

/// Mean and (population) standard deviation over repetitions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeanSd {
    pub mean: f64,
    pub sd: f64,
}

impl MeanSd {
    pub fn of(v: impl IntoIterator<Item = f64>) -> MeanSd {
        let v: Vec<f64> = v.into_iter().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return MeanSd { mean: 0.0, sd: 0.0 };
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        MeanSd {
            mean,
            sd: var.sqrt(),
        }
    }
}

/// A series of means with a band of ± one standard deviation.
pub fn with_band(name: &str, x: Vec<f64>, stats: &[&MeanSd]) -> Series {
    let y = stats.iter().map(|s| s.mean).collect();
    let mut s = Series::new(name, x, y).style(SeriesStyle::LineMarkers);
    s.error = Some(ErrorRange {
        display: ErrorDisplay::Band,
        lower: stats.iter().map(|s| s.mean - s.sd).collect(),
        upper: stats.iter().map(|s| s.mean + s.sd).collect(),
    });
    s
}

/// The parameters every OIESGP result lists.
pub fn common_parameters(
    learner: &str,
    features: FeatureSet,
    reps: usize,
    seed: u64,
) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("learner".to_string(), learner.to_string()),
        ("features".to_string(), features_text(features)),
        ("repetitions".to_string(), reps.to_string()),
        ("seed".to_string(), seed.to_string()),
    ])
}

/// How results and their cards name the features; the paper's three sets keep the words
/// saved results already hold ("tactile features"), others read "raw+encoders features".
pub fn features_text(f: FeatureSet) -> String {
    match f {
        FeatureSet::MOMENTS => "tactile features".into(),
        FeatureSet::ENCODERS => "encoder features".into(),
        f => format!("{f} features"),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::figures::{Axis, Series};

    #[test]
    fn slugs_keep_words_and_drop_the_rest() {
        assert_eq!(
            slug("Simulated grasp stability"),
            "simulated-grasp-stability"
        );
        assert_eq!(slug("BTS3 (palm down), 2 × 5"), "bts3-palm-down-2-5");
    }

    pub(crate) fn result() -> AnalysisResult {
        AnalysisResult {
            held_out: None,
            methods: vec![crate::catalogue::MethodId::Ds],
            kind: AnalysisKind::Recognition,
            label: "DS, all features".into(),
            session: "iCub".into(),
            parameters: BTreeMap::from([("reps".to_string(), "5".to_string())]),
            scores: vec![("accuracy (all)".into(), 0.99)],
            headline: Some(("accuracy (all)".into(), 0.99)),
            train_seconds: 1.5,
            predict_seconds_per_sample: Some(1e-4),
            created: 1_795_000_000,
            figures: vec![(
                FigureId::AccuracyByTrials,
                Figure::chart(
                    "Accuracy as trials progress",
                    Axis::new("trial", ""),
                    Axis::new("accuracy", ""),
                    vec![Series::new("DS", vec![1.0, 2.0], vec![0.5, f64::NAN])],
                ),
            )],
            details: Vec::new(),
            links: Vec::new(),
            grasp_codes: Vec::new(),
            model_size: None,
        }
    }

    #[test]
    fn export_names_say_the_size_and_agree_alone_and_with_every_figure() {
        let sized = |knobs: &str| {
            let mut r = result();
            r.model_size = Some(ModelSize {
                knobs: knobs.into(),
                reason: SizeReason::PaperDefault,
            });
            r
        };
        let results = vec![sized("capacity 5, tau 1"), sized("capacity 50, tau 15")];
        let names: Vec<String> = figure_set(&results)
            .entries
            .into_iter()
            .map(|e| e.name)
            .collect();
        assert_eq!(
            names,
            [
                "01-ds-all-features-capacity-5-tau-1-accuracy-by-trials",
                "02-ds-all-features-capacity-50-tau-15-accuracy-by-trials"
            ]
        );
        assert_eq!(
            export_name(1, &results[1], FigureId::AccuracyByTrials),
            names[1]
        );
        // A size the label already gives is not said twice.
        let mut k = sized("k 10");
        k.label = "baselines, k 10".into();
        assert_eq!(
            export_name(0, &k, FigureId::Scores),
            "01-baselines-k-10-scores"
        );
    }

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(date_text(0), "1970-01-01 00:00");
        assert_eq!(date_text(951_782_400), "2000-02-29 00:00");
        assert_eq!(
            date_text(1_795_000_000 - 1_795_000_000 % 60),
            "2026-11-18 11:06"
        );
    }

    /// Every point's series name and result index, read from a chart and its sources.
    fn placed(chart: &SpeedChart) -> Vec<(String, usize)> {
        let crate::figures::FigureKind::Chart(c) = &chart.figure.kind else {
            panic!("a chart");
        };
        assert_eq!(c.series.len(), chart.sources.len());
        c.series
            .iter()
            .zip(&chart.sources)
            .flat_map(|(s, src)| {
                assert!(src.is_empty() || src.len() == s.x.len(), "{}", s.name);
                src.iter().map(|&i| (s.name.clone(), i))
            })
            .collect()
    }

    #[test]
    fn speed_accuracy_places_timed_scored_results_and_names_their_sources() {
        let mut untimed = result();
        untimed.train_seconds = 0.0;
        let mut headless = result();
        headless.headline = None;
        let results = vec![untimed, result(), headless, result()];
        let chart = speed_accuracy(&results, TimeAxis::Training).unwrap();
        assert_eq!(
            placed(&chart),
            [
                ("accuracy (all)".to_string(), 1),
                ("accuracy (all)".into(), 3)
            ]
        );
        let mut untimed_prediction = result();
        untimed_prediction.predict_seconds_per_sample = None;
        let mixed = vec![untimed_prediction, result()];
        let on = |axis| -> Vec<usize> {
            placed(&speed_accuracy(&mixed, axis).unwrap())
                .into_iter()
                .map(|(_, i)| i)
                .collect()
        };
        assert_eq!(on(TimeAxis::Prediction), [1]);
        assert_eq!(on(TimeAxis::Training), [0, 1]);
        assert_eq!(speed_accuracy_figures(&mixed).len(), 2);
        assert_eq!(speed_accuracy_figures(&results[2..3]).len(), 0);
    }

    #[test]
    fn speed_accuracy_fronts_join_only_like_scores_and_never_held_out_ones() {
        let at = |session: &str, score: &str, secs: f64, value: f64| {
            let mut r = result();
            r.session = session.into();
            r.headline = Some((score.into(), value));
            r.scores = vec![(score.into(), value)];
            r.train_seconds = secs;
            r
        };
        let mut held = at("BTS3 test", "weighted success rate", 0.2, 0.77);
        held.headline = None;
        held.held_out = Some(HeldOut {
            trained_on: "BTS3 train".into(),
            trained_grasps: 2133,
            tested_on: "BTS3 test".into(),
            tested_grasps: 511,
            calibration: "none".into(),
        });
        held.model_size = Some(ModelSize {
            knobs: "num_bases 29".into(),
            reason: SizeReason::PaperDefault,
        });
        let mut held_later = held.clone();
        held_later.train_seconds = 0.4;
        let results = vec![
            at("iCub", "accuracy (all)", 1.0, 0.9),
            at("BTS3 train", "weighted success rate", 2.0, 0.88),
            at("iCub", "accuracy (all)", 4.0, 0.99),
            held,
            held_later,
            // Faster and better than every held-out and BTS3 point: on a front of its own.
            at("iCub", "accuracy (all)", 0.1, 1.0),
        ];
        let chart = speed_accuracy(&results, TimeAxis::Training).unwrap();
        let crate::figures::FigureKind::Chart(c) = &chart.figure.kind else {
            panic!("a chart");
        };
        let names: Vec<&str> = c.series.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "accuracy (all) · iCub: Pareto front",
                "accuracy (all) · iCub",
                "weighted success rate · BTS3 train",
                "weighted success rate, held out · BTS3 test",
            ]
        );
        // iCub's front: the 0.1 s model dominates the others.
        assert_eq!(
            (c.series[0].x.clone(), c.series[0].y.clone()),
            (vec![0.1], vec![1.0])
        );
        assert_eq!(chart.sources, [vec![], vec![0, 2, 5], vec![1], vec![3, 4]]);
        // The held-out point is labelled with where its model trained.
        assert_eq!(
            c.series[3].point_labels,
            ["DS, all features, num_bases 29 (trained on BTS3 train)"; 2]
        );
        // One chart per score and session: its own points and front, the score on its axis.
        let kinds = score_kinds(&results, TimeAxis::Training);
        let texts: Vec<String> = kinds.iter().map(ScoreKind::text).collect();
        assert_eq!(
            texts,
            [
                "accuracy (all) · iCub",
                "weighted success rate · BTS3 train",
                "weighted success rate · BTS3 test"
            ]
        );
        let icub = speed_accuracy_of(&results, TimeAxis::Training, &kinds[0]).unwrap();
        assert_eq!(icub.sources, [vec![], vec![0, 2, 5]]);
        let crate::figures::FigureKind::Chart(c) = &icub.figure.kind else {
            panic!("a chart");
        };
        assert_eq!(c.y.title, "accuracy (all)");
        assert_eq!(icub.figure.title, "Speed against accuracy · iCub");
        // Held out alone: no front.
        let test = speed_accuracy_of(&results, TimeAxis::Training, &kinds[2]).unwrap();
        assert_eq!(test.sources, [vec![3, 4]]);
        // Exported: one figure per kind on the training axis (none on prediction here).
        let exported = speed_accuracy_figures(&results);
        assert_eq!(
            exported.len(),
            3 + score_kinds(&results, TimeAxis::Prediction).len()
        );
        assert_eq!(exported[0].0, "speed-against-accuracy-icub-accuracy-all");
    }
}
