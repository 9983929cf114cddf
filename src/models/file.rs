//! The model file: `{"format": "tactile-workbench-model", "version": 1, "provenance": …,
//! "model": …}`. The provenance says what was trained, on what, how and how well: the
//! method and its parameters, its size and why, the training session's name and content
//! hash, the features and their normalisation, the label set and classes, when and how
//! long it trained, and the scores it was selected with. Loading checks the format and
//! version first, then every field; writing is atomic.

use std::path::Path;
use std::time::SystemTime;

use serde::{Deserialize, Serialize};

use super::{
    ClassifierModel, ClusterModel, ModelError, SequenceModel, StabilityClassifier, TableOneModel,
};
use crate::catalogue::MethodId;
use crate::experiments::feature_choice::FeatureChoice;
use crate::experiments::result::SizeReason;
use crate::session::Session;

pub const FORMAT: &str = "tactile-workbench-model";
pub const VERSION: u32 = 1;

/// A session as a model or a result refers to it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SessionRef {
    pub name: String,
    /// `sha256:` of the session's native JSON, whatever file it was read from.
    pub hash: String,
    pub grasps: usize,
    pub objects: usize,
}

impl SessionRef {
    pub fn of(session: &Session) -> SessionRef {
        let bytes = serde_json::to_vec(session).unwrap_or_default();
        SessionRef {
            name: session.meta.name.clone(),
            hash: crate::fsutil::content_hash(&bytes),
            grasps: session.grasps.len(),
            objects: session.objects().len(),
        }
    }
}

/// A score a model was selected with, under a named protocol.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SelectionScore {
    pub protocol: String,
    pub name: String,
    pub value: f64,
}

impl SelectionScore {
    /// Named scores all measured under one protocol.
    pub fn under(protocol: &str, scores: &[(&str, f64)]) -> Vec<SelectionScore> {
        scores
            .iter()
            .map(|&(name, value)| SelectionScore {
                protocol: protocol.into(),
                name: name.into(),
                value,
            })
            .collect()
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    pub method: MethodId,
    pub parameters: Vec<(String, String)>,
    /// The size knobs' values (e.g. num_bases 29).
    pub size: Vec<(String, usize)>,
    pub size_reason: SizeReason,
    pub session: SessionRef,
    pub features: String,
    pub normalisation: String,
    pub label_set: String,
    pub classes: Vec<String>,
    /// RFC 3339, UTC.
    pub trained_at: String,
    pub train_seconds: f64,
    pub selection: Vec<SelectionScore>,
    /// How `--features auto` chose the inputs (None: they were given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature_choice: Option<FeatureChoice>,
}

impl Provenance {
    /// The time now in the provenance's format.
    pub fn now() -> String {
        humantime::format_rfc3339_seconds(SystemTime::now()).to_string()
    }

    /// "sparse coding + SVM (num_bases 29), trained on NAME (n grasps)"; a pipeline on
    /// other inputs than the paper's says which ("num_bases 29, codes+raw").
    pub fn summary(&self) -> String {
        let inputs = self
            .parameters
            .iter()
            .find(|(k, v)| k == "inputs" && v != "codes")
            .map(|(_, v)| v.clone());
        let size = self
            .size
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .chain(inputs)
            .collect::<Vec<_>>()
            .join(", ");
        let size = if size.is_empty() {
            String::new()
        } else {
            format!(" ({size})")
        };
        format!(
            "{}{size}, trained on {} ({} grasps)",
            self.method.title(),
            self.session.name,
            self.session.grasps
        )
    }
}

/// A trained model of any method of the catalogue.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Model {
    /// Sparse coding + linear SVM, or the raw linear SVM.
    Stability(StabilityClassifier),
    /// DS or GS experts over per-step feature sequences.
    Sequences(SequenceModel),
    /// DU or GU experts: online clusters of grasps.
    Clusters(ClusterModel),
    /// k-means, the SOM or the RBF SVM on the Table I features.
    TableOne(TableOneModel),
    /// A registered method, with the state its trait saved.
    Classifier(ClassifierModel),
}

impl Model {
    pub fn method(&self) -> MethodId {
        match self {
            Model::Stability(c) => c.method(),
            Model::Sequences(m) => m.method(),
            Model::Clusters(m) => m.method(),
            Model::TableOne(m) => m.method(),
            Model::Classifier(m) => m.method,
        }
    }

    fn validate(&self) -> Result<(), ModelError> {
        match self {
            Model::Stability(c) => c.validate(),
            Model::Sequences(m) => m.validate(),
            Model::Clusters(m) => m.validate(),
            Model::TableOne(m) => m.validate(),
            Model::Classifier(m) => m.validate(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    pub format: String,
    pub version: u32,
    pub provenance: Provenance,
    pub model: Model,
}

impl ModelFile {
    pub fn new(provenance: Provenance, model: Model) -> ModelFile {
        ModelFile {
            format: FORMAT.into(),
            version: VERSION,
            provenance,
            model,
        }
    }

    /// Check everything a file could get wrong.
    pub fn validate(&self) -> Result<(), ModelError> {
        if self.format != FORMAT {
            return Err(ModelError::field(
                "format",
                format!("{:?} where a model file says {FORMAT:?}", self.format),
            ));
        }
        if self.version != VERSION {
            return Err(ModelError::field(
                "version",
                format!(
                    "version {} (this build reads version {VERSION})",
                    self.version
                ),
            ));
        }
        let p = &self.provenance;
        if p.method != self.model.method() {
            return Err(ModelError::field(
                "provenance.method",
                format!(
                    "says {} but the model is {}",
                    p.method.key(),
                    self.model.method().key()
                ),
            ));
        }
        if !(p.train_seconds.is_finite() && p.train_seconds >= 0.0) {
            return Err(ModelError::field(
                "provenance.train_seconds",
                "must be finite and ≥ 0",
            ));
        }
        if humantime::parse_rfc3339(&p.trained_at).is_err() {
            return Err(ModelError::field(
                "provenance.trained_at",
                format!("{:?} is not an RFC 3339 time", p.trained_at),
            ));
        }
        if p.classes.is_empty() {
            return Err(ModelError::field(
                "provenance.classes",
                "no classes: a model names what it predicts",
            ));
        }
        let mut seen = std::collections::HashSet::new();
        if let Some(c) = p.classes.iter().find(|c| !seen.insert(c.as_str())) {
            return Err(ModelError::field(
                "provenance.classes",
                format!("{c:?} is listed twice"),
            ));
        }
        if let Some(s) = p.selection.iter().find(|s| !s.value.is_finite()) {
            return Err(ModelError::field(
                "provenance.selection",
                format!("score {:?} is not finite", s.name),
            ));
        }
        self.model.validate()
    }

    /// Parse and check a model file's text (`path` names it in errors).
    pub fn from_json(text: &str, path: &str) -> Result<ModelFile, ModelError> {
        let text = crate::fsutil::without_bom(text);
        check_head(
            serde_json::from_str(text).map_err(|e| not_a_model(path, e))?,
            path,
        )?;
        let file: ModelFile = serde_json::from_str(text).map_err(|e| json_err(path, "", e))?;
        file.validate().map_err(|e| invalid(path, e))?;
        Ok(file)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// A model file's format and version, read before the rest.
#[derive(Deserialize)]
struct Head {
    format: Option<serde_json::Value>,
    version: Option<serde_json::Value>,
}

fn json_err(path: &str, what: &'static str, source: serde_json::Error) -> ModelError {
    ModelError::Json {
        path: path.into(),
        what,
        source,
    }
}

fn invalid(path: &str, e: ModelError) -> ModelError {
    ModelError::Invalid {
        path: path.into(),
        source: crate::error::Kept::new(e),
    }
}

fn not_a_model(path: &str, e: serde_json::Error) -> ModelError {
    let what = match e.classify() {
        serde_json::error::Category::Syntax | serde_json::error::Category::Eof => "not JSON: ",
        _ => "not a model file: ",
    };
    json_err(path, what, e)
}

/// Format and version first, so that a newer or foreign file says so rather than failing
/// on whichever field changed.
fn check_head(head: Head, path: &str) -> Result<(), ModelError> {
    let file_err = |message: String| ModelError::File {
        path: path.into(),
        message,
    };
    match head.format.as_ref().and_then(|v| v.as_str()) {
        Some(FORMAT) => {}
        Some(other) => {
            return Err(file_err(format!(
                "format {other:?}: not a model file ({FORMAT:?})"
            )));
        }
        None => return Err(file_err(format!("no \"format\": {FORMAT:?} field"))),
    }
    match head.version.as_ref().and_then(|v| v.as_u64()) {
        Some(v) if v == u64::from(VERSION) => Ok(()),
        Some(v) => Err(file_err(format!(
            "model file version {v}; this build reads version {VERSION}"
        ))),
        None => Err(file_err("no numeric \"version\" field".into())),
    }
}

/// Read and check a model file, parsed as it is read (at most
/// [`crate::fsutil::max_bytes::MODEL`]; the head first, then the whole).
pub fn load(path: &Path) -> Result<ModelFile, ModelError> {
    let name = path.display().to_string();
    let open = || {
        crate::fsutil::open_json(path, crate::fsutil::max_bytes::MODEL, "model file").map_err(
            |source| ModelError::Io {
                path: name.clone(),
                source,
            },
        )
    };
    check_head(
        serde_json::from_reader(open()?).map_err(|e| not_a_model(&name, e))?,
        &name,
    )?;
    let file: ModelFile = serde_json::from_reader(open()?).map_err(|e| json_err(&name, "", e))?;
    file.validate().map_err(|e| invalid(&name, e))?;
    Ok(file)
}

/// Write a model file atomically (a killed write leaves the old file or none).
pub fn save(file: &ModelFile, path: &Path) -> Result<(), ModelError> {
    crate::fsutil::write_atomic(path, file.to_json().as_bytes()).map_err(|source| ModelError::Io {
        path: path.display().to_string(),
        source,
    })
}
