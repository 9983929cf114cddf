//! Issue #42's rule for errors: an engine error that wraps a lower layer's error keeps it as
//! its `source()`, so the window and the command line can show the whole chain and a caller
//! can ask what went wrong below. Each test reaches a lower error through the layers above
//! it and walks the chain down to it.

mod common;

use std::error::Error;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::error::MethodError;
use tactile_workbench::experiments::stability::{
    Config, DataOptions, StabilityData, StabilityError, StabilityOptions,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::models::{self, ModelError, ModelFile};
use tactile_workbench::project::{Project, ProjectError};

/// Every error of the chain below `e`, top first.
fn chain<'a>(e: &'a (dyn Error + 'static)) -> Vec<&'a (dyn Error + 'static)> {
    let mut out = vec![e];
    let mut at = e;
    while let Some(next) = at.source() {
        out.push(next);
        at = next;
    }
    out
}

fn stability_inputs() -> (
    tactile_workbench::session::Session,
    StabilityData,
    StabilityOptions,
) {
    let session =
        tactile_workbench::session::load(&common::sample("grasp-stability.json")).unwrap();
    let data = StabilityData::from_session(&session, &DataOptions::default()).unwrap();
    let opts = StabilityOptions {
        single: Config {
            num_bases: 8,
            beta: 1.0,
            gamma: 1.0,
        },
        ..Default::default()
    };
    (session, data, opts)
}

fn fitted_file() -> ModelFile {
    let (session, data, opts) = stability_inputs();
    models::fit_stability(MethodId::RawSvm, &session, &data, &opts, &Progress::new())
        .unwrap()
        .into_file(&session, &data)
}

/// The SVM's refusal of its parameter, reached through the model layer: model → stability
/// pipeline → the SVM's own error, each the source of the one above.
#[test]
fn an_svm_error_through_the_model_layer_keeps_its_source() {
    let (session, data, mut opts) = stability_inputs();
    opts.settings.svm.c = -1.0;
    let err = models::fit_stability(MethodId::RawSvm, &session, &data, &opts, &Progress::new())
        .expect_err("a negative C is refused");
    let text = err.to_string();
    assert!(matches!(err, ModelError::Stability(_)), "{err:?}");
    let chain = chain(&err);
    let stability = chain[1]
        .downcast_ref::<StabilityError>()
        .unwrap_or_else(|| panic!("the model error's source is the pipeline's: {chain:?}"));
    assert!(matches!(stability, StabilityError::Svm(_)), "{stability:?}");
    let svm = chain[2]
        .downcast_ref::<MethodError>()
        .unwrap_or_else(|| panic!("the pipeline error's source is the SVM's: {chain:?}"));
    assert!(matches!(svm, MethodError::Param(_)), "{svm:?}");
    // The message shown in one line still says it all.
    assert!(
        text.contains("SVM") && text.contains(&svm.to_string()),
        "{text}"
    );
}

/// A model file that is not JSON: the parser's error is the source, and the message still
/// names the file.
#[test]
fn a_malformed_model_file_keeps_the_parser_error() {
    let dir = common::temp_dir("error-sources-json");
    let path = dir.join("broken.model.json");
    std::fs::write(
        &path,
        "{\"format\": \"tactile-workbench-model\", \"version\": ",
    )
    .unwrap();
    let err = models::load(&path).expect_err("a truncated file is refused");
    let text = err.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    let source = err.source().expect("the parser's error is kept");
    let json = source
        .downcast_ref::<serde_json::Error>()
        .unwrap_or_else(|| panic!("source is the JSON error: {source:?}"));
    assert!(json.is_eof(), "{json}");
}

/// A model file whose field is wrong, read alone and inside a project: the field's error is
/// the source of the file's, which is the source of the project's.
#[test]
fn a_bad_model_field_is_the_source_of_the_file_and_project_errors() {
    let dir = common::temp_dir("error-sources-field");
    let mut file = fitted_file();
    file.provenance.train_seconds = -1.0;

    let path = dir.join("bad.model.json");
    std::fs::write(&path, file.to_json()).unwrap();
    let err = models::load(&path).expect_err("a negative training time is refused");
    assert!(matches!(err, ModelError::Invalid { .. }), "{err:?}");
    let field = err
        .source()
        .and_then(|s| s.downcast_ref::<ModelError>())
        .expect("the field's error is the source");
    assert!(
        matches!(field, ModelError::Field { field, .. } if field == "provenance.train_seconds"),
        "{field:?}"
    );

    let project_path = dir.join("bad.twproj");
    Project::new(Vec::new(), Vec::new())
        .with_models(vec![file])
        .save(&project_path)
        .unwrap();
    let err = Project::load(&project_path).expect_err("a project with a bad model is refused");
    assert!(
        matches!(err, ProjectError::Model { index: 0, .. }),
        "{err:?}"
    );
    let text = err.to_string();
    assert!(
        text.contains("`models[0]`") && text.contains("provenance.train_seconds"),
        "{text}"
    );
    let model = err
        .source()
        .and_then(|s| s.downcast_ref::<ModelError>())
        .expect("the model's error is the source");
    assert!(matches!(model, ModelError::Field { .. }), "{model:?}");
}
