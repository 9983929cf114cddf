//! The class labels of a session under one of its label sets, as every protocol reads them.

use super::ExperimentError;
use crate::session::Session;

/// The class labels of the session under `label_set`, with the class names.
pub fn session_labels(
    session: &Session,
    label_set: &str,
) -> Result<(Vec<usize>, Vec<String>), ExperimentError> {
    let set = session.label_set(label_set).ok_or_else(|| {
        let names: Vec<&str> = session.label_sets.iter().map(|l| l.name.as_str()).collect();
        ExperimentError::param(
            "label_set",
            format!(
                "the session has no label set `{label_set}`; its label sets: {}",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ),
        )
    })?;
    let classes = session.label_sets[set].classes.clone();
    let labels: Vec<usize> = session
        .grasps
        .iter()
        .map(|g| g.labels.get(set).copied().unwrap_or(usize::MAX))
        .collect();
    if labels.iter().any(|&l| l >= classes.len()) {
        return Err(ExperimentError::Data(format!(
            "a grasp has no valid `{label_set}` label"
        )));
    }
    Ok((labels, classes))
}
