//! A saved project: the sessions it used, the results computed on them, the frontiers and
//! the models the results trained. It sits above the experiments and the models, so that
//! neither needs to know of the other's kept state.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::catalogue::MethodId;
use crate::experiments::frontier::Frontier;
use crate::experiments::result::{AnalysisKind, AnalysisResult};
use crate::fsutil;
use crate::models::ModelFile;

pub const PROJECT_TAG: &str = "tactile-workbench-project";
pub const PROJECT_VERSION: u32 = 1;

/// A saved project: the sessions it used (as paths or bundled names) and its results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Project {
    pub format: String,
    pub version: u32,
    /// Where each session came from, as the workbench names it.
    pub sessions: Vec<String>,
    pub results: Vec<AnalysisResult>,
    /// Speed–accuracy frontiers computed on the sessions (projects saved before frontiers
    /// were kept have none).
    #[serde(default)]
    pub frontiers: Vec<Frontier>,
    /// The models trained or loaded beside the results, each a whole model file (projects
    /// saved before models were kept have none).
    #[serde(default)]
    pub models: Vec<ModelFile>,
}

/// Why a project file did not open or save: the lower error (I/O, JSON, a figure, the
/// links of a result, a model) is kept as the source.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    #[error("{path}: {message}")]
    Read { path: String, message: String },
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Json {
        path: String,
        #[source]
        source: serde_json::Error,
    },
    #[error(
        "{path}: unsupported project version {found}; this build reads version {PROJECT_VERSION}"
    )]
    Version { path: String, found: u64 },
    /// A figure of a saved result that cannot be drawn.
    #[error("{path}: `results[{index}]` ({label}): {source}")]
    Figure {
        path: String,
        index: usize,
        label: String,
        #[source]
        source: crate::figures::FigureError,
    },
    /// Links of a saved result that name no figure or part of it.
    #[error("{path}: `results[{index}]` ({label}): {source}")]
    Links {
        path: String,
        index: usize,
        label: String,
        #[source]
        source: crate::experiments::links::LinkError,
    },
    /// A kept model that does not check.
    #[error("{path}: `models[{index}]`: {source}")]
    Model {
        path: String,
        index: usize,
        #[source]
        source: crate::models::ModelError,
    },
    #[error("{path}: could not write: {source}")]
    Write {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: could not write: {source}")]
    Serialise {
        path: String,
        #[source]
        source: serde_json::Error,
    },
}

/// Whether `path` starts like a project file (its first field names the project format).
pub fn is_project(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 128];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    String::from_utf8_lossy(&head[..n]).contains(PROJECT_TAG)
}

impl Project {
    pub fn new(sessions: Vec<String>, results: Vec<AnalysisResult>) -> Self {
        Project {
            format: PROJECT_TAG.into(),
            version: PROJECT_VERSION,
            sessions,
            results,
            frontiers: Vec::new(),
            models: Vec::new(),
        }
    }

    pub fn with_models(mut self, models: Vec<ModelFile>) -> Self {
        self.models = models;
        self
    }

    pub fn with_frontiers(mut self, frontiers: Vec<Frontier>) -> Self {
        self.frontiers = frontiers;
        self
    }

    pub fn save(&self, path: &Path) -> Result<(), ProjectError> {
        let text = serde_json::to_string(self).map_err(|source| ProjectError::Serialise {
            path: path.display().to_string(),
            source,
        })?;
        fsutil::write_atomic(path, text.as_bytes()).map_err(|source| ProjectError::Write {
            path: path.display().to_string(),
            source,
        })
    }

    /// Read a project file as it is parsed (at most [`fsutil::max_bytes::PROJECT`]): the
    /// header first, then the whole, checked as [`Project::parse`] checks it.
    pub fn load(path: &Path) -> Result<Project, ProjectError> {
        let open = || {
            fsutil::open_json(path, fsutil::max_bytes::PROJECT, "project file").map_err(|source| {
                ProjectError::Io {
                    path: path.display().to_string(),
                    source,
                }
            })
        };
        check_header(
            serde_json::from_reader(open()?).map_err(json_err(path))?,
            path,
        )?;
        let project = serde_json::from_reader(open()?).map_err(json_err(path))?;
        Project::checked(project, path)
    }

    /// Read a project from the text of the file `path`. Every figure must be drawable, so a
    /// damaged file is an error here and never a broken view later.
    pub fn parse(text: &str, path: &Path) -> Result<Project, ProjectError> {
        let text = fsutil::without_bom(text);
        check_header(serde_json::from_str(text).map_err(json_err(path))?, path)?;
        let project = serde_json::from_str(text).map_err(json_err(path))?;
        Project::checked(project, path)
    }

    /// Older results given their methods, every figure, link and model checked.
    fn checked(mut project: Project, path: &Path) -> Result<Project, ProjectError> {
        let p = || path.display().to_string();
        for r in &mut project.results {
            if r.methods.is_empty() {
                r.methods = older_methods(r);
            }
        }
        for (i, r) in project.results.iter().enumerate() {
            let details = r
                .details
                .iter()
                .flat_map(|d| d.items.iter().map(|(_, f)| f));
            for f in r.figures.iter().map(|(_, f)| f).chain(details) {
                f.validate().map_err(|source| ProjectError::Figure {
                    path: p(),
                    index: i,
                    label: r.label.clone(),
                    source,
                })?;
            }
            r.check_links().map_err(|source| ProjectError::Links {
                path: p(),
                index: i,
                label: r.label.clone(),
                source,
            })?;
        }
        for (i, m) in project.models.iter().enumerate() {
            m.validate().map_err(|source| ProjectError::Model {
                path: p(),
                index: i,
                source,
            })?;
        }
        Ok(project)
    }
}

fn json_err(path: &Path) -> impl FnOnce(serde_json::Error) -> ProjectError + '_ {
    move |source| ProjectError::Json {
        path: path.display().to_string(),
        source,
    }
}

#[derive(Deserialize)]
struct Header {
    format: Option<String>,
    version: Option<u64>,
}

/// The format tag and version, before anything else.
fn check_header(h: Header, path: &Path) -> Result<(), ProjectError> {
    let p = path.display().to_string();
    if h.format.as_deref() != Some(PROJECT_TAG) {
        return Err(ProjectError::Read {
            path: p,
            message: "not a tactile-workbench project file".into(),
        });
    }
    match h.version {
        Some(v) if v == PROJECT_VERSION as u64 => Ok(()),
        Some(found) => Err(ProjectError::Version { path: p, found }),
        None => Err(ProjectError::Read {
            path: p,
            message: "`version`: missing".into(),
        }),
    }
}

/// Folders of the operating system: no session lives there, and a project naming a path
/// into one (`/etc/passwd`, `/proc/self/mem`) is refused rather than followed.
const SYSTEM_FOLDERS: [&str; 10] = [
    "/bin", "/boot", "/dev", "/etc", "/lib", "/lib64", "/proc", "/run", "/sbin", "/sys",
];

/// Why a project may not open `path` as a session, if it may not: it must be a session
/// file (native JSON, a CSV, an MCAP bag) or a dataset folder (the iCub dataset, a ROS 2
/// bag, a folder of trial files), and lie outside the system's folders (links resolved).
/// A missing path is left to the loader, which names it.
pub fn session_path_refusal(path: &Path) -> Option<String> {
    let Ok(real) = std::fs::canonicalize(path) else {
        return None;
    };
    if let Some(dir) = SYSTEM_FOLDERS.iter().find(|d| real.starts_with(d)) {
        return Some(format!(
            "{} is in the system folder {dir}: not a session, not opened",
            path.display()
        ));
    }
    if real.is_dir() {
        if crate::session::icub::is_dataset(&real) || crate::session::needs_spec(&real) {
            return None;
        }
        return Some(format!(
            "{} is a folder but neither the iCub dataset, a ROS 2 bag nor a folder of trial \
             files: not opened",
            path.display()
        ));
    }
    if !real.is_file() {
        return Some(format!(
            "{} is not a file: not a session, not opened",
            path.display()
        ));
    }
    let ext = real
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("csv" | "mcap") => None,
        Some("json") if starts_as_session(&real) => None,
        _ => Some(format!(
            "{} is not a session file (a native .json session, a .csv or an .mcap bag): not \
             opened",
            path.display()
        )),
    }
}

/// Whether the file's first bytes name the native session format.
fn starts_as_session(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 256];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    String::from_utf8_lossy(&head[..n]).contains(crate::session::native::FORMAT_TAG)
}

/// The methods of a result saved before results named them, read from its kind and its
/// `learner` parameter.
fn older_methods(r: &AnalysisResult) -> Vec<MethodId> {
    let learner = r.parameters.get("learner").map(String::as_str);
    match (r.kind, learner) {
        (AnalysisKind::Recognition, Some("DS")) => vec![MethodId::Ds],
        (AnalysisKind::Recognition, Some("GS")) => vec![MethodId::Gs],
        (AnalysisKind::Clustering, Some("DU")) => vec![MethodId::Du],
        (AnalysisKind::Clustering, Some("GU")) => vec![MethodId::Gu],
        (AnalysisKind::Stability, _) if r.held_out.is_none() => vec![MethodId::SparseSvm],
        (AnalysisKind::Baselines, _) => [MethodId::KMeans, MethodId::Som]
            .into_iter()
            .chain(r.score("SVM accuracy").map(|_| MethodId::RbfSvm))
            .collect(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::figure_id::FigureId;
    use crate::experiments::result::tests::result;
    use crate::experiments::result::{FigureDetails, GraspLinks, LinkedItem, figure_set};
    use crate::figures::{Axis, Figure, Series};

    #[test]
    fn projects_round_trip_and_reject_other_versions() {
        let dir = std::env::temp_dir().join(format!("tw-project-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("p.json");
        let project = Project::new(vec!["sample: a.json".into()], vec![result()]);
        project.save(&p).unwrap();
        let back = Project::load(&p).unwrap();
        assert_eq!(back.results.len(), 1);
        assert_eq!(back.results[0].label, "DS, all features");
        assert_eq!(
            back.results[0].figures[0].1.title,
            "Accuracy as trials progress"
        );
        let text = std::fs::read_to_string(&p)
            .unwrap()
            .replace("\"version\":1", "\"version\":9");
        std::fs::write(&p, text).unwrap();
        let e = Project::load(&p).unwrap_err().to_string();
        assert!(e.contains("unsupported project version 9"), "{e}");
        let set = figure_set(&back.results);
        assert_eq!(set.entries[0].name, "01-ds-all-features-accuracy-by-trials");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_project_keeps_its_models_and_names_a_damaged_one() {
        let session = crate::session::simulate::grasp_stability(0);
        let data = crate::experiments::stability::StabilityData::from_session(
            &session,
            &Default::default(),
        )
        .unwrap();
        let file = crate::models::fit_stability(
            crate::catalogue::MethodId::RawSvm,
            &session,
            &data,
            &Default::default(),
            &crate::jobs::Progress::new(),
        )
        .unwrap()
        .into_file(&session, &data);
        let project = Project::new(Vec::new(), vec![result()]).with_models(vec![file.clone()]);
        let text = serde_json::to_string(&project).unwrap();
        let back = Project::parse(&text, Path::new("p.json")).unwrap();
        assert_eq!(back.models, [file]);
        // An older project (no models) loads with none.
        let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
        old.as_object_mut().unwrap().remove("models");
        let back = Project::parse(&old.to_string(), Path::new("p.json")).unwrap();
        assert!(back.models.is_empty());
        // A model that fails its checks is named by its place.
        let mut bad: serde_json::Value = serde_json::from_str(&text).unwrap();
        bad["models"][0]["version"] = 7.into();
        let e = Project::parse(&bad.to_string(), Path::new("p.json"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("p.json: `models[0]`"), "{e}");
    }

    #[test]
    fn older_results_get_their_methods_from_their_learner() {
        let mut r = result();
        r.parameters.insert("learner".into(), "GS".into());
        let text = serde_json::to_string(&Project::new(Vec::new(), vec![r])).unwrap();
        let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
        old["results"][0].as_object_mut().unwrap().remove("methods");
        let back = Project::parse(&old.to_string(), Path::new("p.json")).unwrap();
        assert_eq!(back.results[0].methods, [MethodId::Gs]);
    }

    #[test]
    fn a_project_with_an_undrawable_figure_is_an_error_naming_it() {
        let path = Path::new("broken.json");
        let mut r = result();
        if let crate::figures::FigureKind::Chart(c) = &mut r.figures[0].1.kind {
            c.series[0].y.pop();
        }
        let text = serde_json::to_string(&Project::new(Vec::new(), vec![r])).unwrap();
        let e = Project::parse(&text, path).unwrap_err().to_string();
        assert!(
            e.starts_with("broken.json: `results[0]` (DS, all features)"),
            "{e}"
        );
        assert!(e.contains("x values"), "{e}");
        let e = Project::parse("{\"format\": 3", path)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("broken.json: "), "{e}");
    }

    #[test]
    fn details_pick_the_nearest_key_and_older_projects_load_without_them() {
        let fig = |t: &str| {
            Figure::chart(
                t,
                Axis::new("x", ""),
                Axis::new("y", ""),
                vec![Series::new("s", vec![0.0], vec![0.0])],
            )
        };
        let d = FigureDetails {
            figure: FigureId::ScoresVsThreshold,
            selector: "novelty threshold".into(),
            items: vec![(0.1, fig("a")), (0.2, fig("b")), (0.4, fig("c"))],
        };
        assert_eq!(d.nearest(-5.0), Some(0));
        assert_eq!(d.nearest(0.16), Some(1));
        assert_eq!(d.nearest(0.31), Some(2));
        let mut r = result();
        r.details.push(d);
        assert!(r.details_of(FigureId::ScoresVsThreshold).is_some());
        assert!(r.details_of(FigureId::BasesRaw).is_none());
        let mut json = serde_json::to_value(result()).unwrap();
        json.as_object_mut().unwrap().remove("details");
        let back: AnalysisResult = serde_json::from_value(json).unwrap();
        assert!(back.details.is_empty());
        let mut json = serde_json::to_value(result()).unwrap();
        json.as_object_mut().unwrap().remove("model_size");
        let back: AnalysisResult = serde_json::from_value(json).unwrap();
        assert_eq!(back.model_size, None);
    }

    #[test]
    fn links_must_name_a_part_of_a_figure_and_older_projects_load_without_them() {
        use crate::figures::{AxisTitle, ColorScale, FigureKind, Heatmap};
        let path = Path::new("linked.json");
        let mut r = result();
        let title = |t: &str| AxisTitle {
            title: t.into(),
            unit: String::new(),
        };
        r.figures.push((
            FigureId::Confusion,
            Figure::new(
                "Confusion",
                FigureKind::Heatmap(Heatmap {
                    x: title("predicted"),
                    y: title("true"),
                    columns: vec!["a".into(), "b".into(), "c".into()],
                    rows: vec!["a".into(), "b".into()],
                    values: vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]],
                    colors: ColorScale::viridis("share", ""),
                    annotate: false,
                    marked: Vec::new(),
                }),
            ),
        ));
        let link = |figure: FigureId, at: [usize; 2]| GraspLinks {
            figure,
            detail: None,
            items: vec![LinkedItem {
                at,
                grasps: vec![3],
                text: "true a, predicted c: 1 grasp".into(),
            }],
        };
        let parse = |r: &AnalysisResult| {
            let text = serde_json::to_string(&Project::new(Vec::new(), vec![r.clone()])).unwrap();
            Project::parse(&text, path)
        };
        r.links = vec![link(FigureId::Confusion, [0, 2])];
        let back = parse(&r).unwrap();
        assert_eq!(back.results[0].links, r.links);
        assert_eq!(
            back.results[0]
                .links_of(FigureId::Confusion, None)
                .unwrap()
                .item([0, 2])
                .unwrap()
                .grasps,
            vec![3]
        );
        for (bad, why) in [
            (link(FigureId::Confusion, [2, 0]), "no part [2, 0]"),
            (link(FigureId::Confusion, [1, 3]), "no part [1, 3]"),
            (link(FigureId::AccuracyByTrials, [0, 0]), "no part [0, 0]"),
            (link(FigureId::BasesRaw, [0, 0]), "figure `bases-raw`"),
        ] {
            r.links = vec![bad];
            let e = parse(&r).unwrap_err().to_string();
            assert!(e.starts_with("linked.json: `results[0]`"), "{e}");
            assert!(e.contains(why), "{e}");
        }
        let mut json = serde_json::to_value(result()).unwrap();
        let fields = json.as_object_mut().unwrap();
        fields.remove("links");
        fields.remove("grasp_codes");
        let back: AnalysisResult = serde_json::from_value(json).unwrap();
        assert!(back.links.is_empty() && back.grasp_codes.is_empty());
    }
}
