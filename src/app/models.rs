//! The Models list: every model trained in the window or loaded from a file, whatever its
//! method, with its provenance. The list is kept as model files in the data folder's
//! `models/` (beside the kept results), so it survives a restart; the jobs that write,
//! read and evaluate them are `results::Analyses`'s, the list's panel is `views::models`.

use std::path::{Path, PathBuf};

use crate::models::{self, Calibration, ModelFile};

/// The folder of the data folder that keeps the models between runs.
pub const KEPT_MODELS: &str = "models";

/// A model of the list.
pub struct KeptModel {
    pub file: ModelFile,
    /// Its copy in the data folder (None while models are not kept).
    pub kept: Option<PathBuf>,
    /// The copy is written (or being written).
    pub written: bool,
    /// The result that trained it, by its creation time and label (None for a model read
    /// from a file): that result's card offers to save it.
    pub result: Option<(u64, String)>,
}

/// What "Evaluate on session…" is set to: a model of the list, an open session and the
/// calibration of that session's sensors.
#[derive(Clone, Debug, PartialEq)]
pub struct EvaluateForm {
    /// Index into the list.
    pub model: usize,
    /// Index into the open sessions.
    pub session: usize,
    pub calibration: Calibration,
    /// K of `first:K`, kept while another calibration is chosen.
    pub first: usize,
    /// Which open sessions the model can read (or why not), for the model and the open
    /// sessions' names it was asked of.
    pub readable: Option<Readable>,
}

/// The model's answer for each open session, asked once per model and set of sessions.
#[derive(Clone, Debug, PartialEq)]
pub struct Readable {
    pub model: usize,
    pub sessions: Vec<String>,
    pub verdicts: Vec<Result<(), String>>,
}

impl EvaluateForm {
    pub fn new(model: usize, session: usize) -> EvaluateForm {
        EvaluateForm {
            model,
            session,
            calibration: Calibration::default(),
            first: 50,
            readable: None,
        }
    }
}

#[derive(Default)]
pub struct Models {
    pub list: Vec<KeptModel>,
    /// Where models are kept (None: not kept between runs).
    pub dir: Option<PathBuf>,
    /// The "Evaluate on session…" window, while open.
    pub evaluate: Option<EvaluateForm>,
}

impl Models {
    /// Add `file` to the list unless an equal model is there; returns whether it was added.
    /// A new model gets a file of its own in the kept folder, written by the next keep.
    pub fn add(&mut self, file: ModelFile) -> bool {
        if self.list.iter().any(|m| m.file == file) {
            return false;
        }
        let kept = self
            .dir
            .as_ref()
            .map(|d| self.free_path(d, &file_name(&file)));
        self.list.push(KeptModel {
            file,
            kept,
            written: false,
            result: None,
        });
        true
    }

    /// Add `file`, trained by the result created at `created` and labelled `label`.
    pub fn add_trained(&mut self, file: ModelFile, created: u64, label: &str) {
        let key = Some((created, label.to_string()));
        match self.list.iter().position(|m| m.file == file) {
            Some(i) => self.list[i].result = key,
            None => {
                self.add(file);
                if let Some(m) = self.list.last_mut() {
                    m.result = key;
                }
            }
        }
    }

    /// A model read back from the kept folder.
    pub fn add_kept(&mut self, file: ModelFile, path: PathBuf) {
        if !self.list.iter().any(|m| m.file == file) {
            self.list.push(KeptModel {
                file,
                kept: Some(path),
                written: true,
                result: None,
            });
        }
    }

    /// `name` in `dir`, numbered when a file or another model already has it.
    fn free_path(&self, dir: &Path, name: &str) -> PathBuf {
        let taken = |p: &Path| p.exists() || self.list.iter().any(|m| m.kept.as_deref() == Some(p));
        let first = dir.join(name);
        if !taken(&first) {
            return first;
        }
        let stem = name.trim_end_matches(".json");
        (2..)
            .map(|k| dir.join(format!("{stem}-{k}.json")))
            .find(|p| !taken(p))
            .unwrap_or(first)
    }
}

/// A file name that says what the model is: method, training session, when it trained.
pub fn file_name(file: &ModelFile) -> String {
    let p = &file.provenance;
    let when: String = p.trained_at.chars().filter(char::is_ascii_digit).collect();
    format!(
        "{}-{}-{when}.json",
        p.method.key(),
        crate::experiments::result::slug(&p.session.name)
    )
}

/// When it trained, to the minute ("2026-11-25 17:30").
pub fn trained_when(file: &ModelFile) -> String {
    file.provenance
        .trained_at
        .replace('T', " ")
        .chars()
        .take(16)
        .collect()
}

/// Every model file of `dir` (`*.json`), read and checked: the models, and what could not
/// be read (each error names its file).
pub fn read_dir(dir: &Path) -> (Vec<(PathBuf, ModelFile)>, Vec<String>) {
    let mut paths: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "json"))
            .collect(),
        Err(e) => return (Vec::new(), vec![format!("{}: {e}", dir.display())]),
    };
    paths.sort();
    let (mut ok, mut bad) = (Vec::new(), Vec::new());
    for p in paths {
        match models::load(&p) {
            Ok(f) => ok.push((p, f)),
            Err(e) => bad.push(e.to_string()),
        }
    }
    (ok, bad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalogue::MethodId;
    use crate::experiments::stability::{DataOptions, StabilityData, StabilityOptions};
    use crate::jobs::Progress;
    use crate::models::fit_stability;

    fn raw_svm() -> ModelFile {
        let session = crate::session::simulate::grasp_stability(0);
        let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
        let opts = StabilityOptions::default();
        fit_stability(MethodId::RawSvm, &session, &data, &opts, &Progress::new())
            .unwrap()
            .into_file(&session, &data)
    }

    #[test]
    fn each_model_gets_a_file_of_its_own_and_a_bad_file_is_named() {
        let dir = std::env::temp_dir().join(format!("tw-app-models-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut list = Models {
            dir: Some(dir.clone()),
            ..Default::default()
        };
        let a = raw_svm();
        assert!(list.add(a.clone()));
        assert!(!list.add(a.clone()), "an equal model is listed once");
        // Another model trained in the same second on the same session: numbered.
        let mut b = a.clone();
        b.provenance.train_seconds += 1.0;
        assert!(list.add(b));
        let names: Vec<String> = list
            .list
            .iter()
            .map(|m| {
                m.kept
                    .as_ref()
                    .unwrap()
                    .file_name()
                    .unwrap()
                    .to_string_lossy()
                    .into()
            })
            .collect();
        let first = file_name(&a);
        assert!(
            first.starts_with("raw-svm-simulated-grasp-stability-"),
            "{first}"
        );
        assert_eq!(names, [first.clone(), first.replace(".json", "-2.json")]);

        // Read back: the good file, and the bad one named in its error.
        crate::models::save(&a, list.list[0].kept.as_ref().unwrap()).unwrap();
        std::fs::write(
            dir.join("torn.json"),
            "{\"format\": \"tactile-workbench-model\"",
        )
        .unwrap();
        std::fs::write(dir.join("notes.txt"), "not a model").unwrap();
        let (ok, bad) = read_dir(&dir);
        assert_eq!(ok.len(), 1);
        assert_eq!(ok[0].1, a);
        assert_eq!(bad.len(), 1);
        assert!(bad[0].contains("torn.json"), "{bad:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
