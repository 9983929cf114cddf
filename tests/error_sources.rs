//! Issue #42's rule for errors: an engine error that wraps a lower layer's error keeps it as
//! its `source()`, so the window and the command line can show the whole chain and a caller
//! can ask what went wrong below. Each test reaches a lower error through the layers above
//! it and walks the chain down to it.

mod common;

use std::error::Error;
use std::path::Path;
use std::time::Duration;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::error::MethodError;
use tactile_workbench::experiments::stability::{
    Config, DataOptions, StabilityData, StabilityError, StabilityOptions,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::live::LiveError;
use tactile_workbench::live::channels::Plan;
use tactile_workbench::live::discover;
use tactile_workbench::live::protocol::{self, Channel};
use tactile_workbench::models::{self, ModelError, ModelFile};
use tactile_workbench::project::{Project, ProjectError};
use tactile_workbench::session::cdr::CdrError;
use tactile_workbench::session::long_csv::{self, CsvError};
use tactile_workbench::session::spec::{LabelError, SpecError};
use tactile_workbench::session::trial_pattern::PatternError;
use tactile_workbench::session::{ImportSpec, Location};

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

/// A stream whose port is closed: the socket's own error is the source of the live error,
/// whose message names the address.
#[test]
fn a_refused_connection_keeps_the_socket_error() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let url = format!("ws://127.0.0.1:{port}");
    let err = discover::discover(&url, Duration::from_millis(200))
        .expect_err("nothing listens on a port just freed");
    assert!(matches!(err, LiveError::Socket { .. }), "{err:?}");
    assert!(
        err.to_string().contains(&format!("127.0.0.1:{port}")),
        "{err}"
    );
    let io = err
        .source()
        .and_then(|s| s.downcast_ref::<std::io::Error>())
        .unwrap_or_else(|| panic!("the socket's error is the source: {err:?}"));
    assert_eq!(io.kind(), std::io::ErrorKind::ConnectionRefused, "{io}");
}

/// A peer that accepts the connection and hangs up: the WebSocket library's error is the
/// source of the failed handshake.
#[test]
fn a_failed_handshake_keeps_the_websocket_error() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let peer = std::thread::spawn(move || drop(listener.accept()));
    let err = discover::discover(&format!("ws://127.0.0.1:{port}"), Duration::from_secs(1))
        .expect_err("a peer that hangs up is no server");
    peer.join().unwrap();
    assert!(matches!(err, LiveError::Handshake { .. }), "{err:?}");
    let ws = chain(&err)[1]
        .downcast_ref::<tungstenite::Error>()
        .unwrap_or_else(|| panic!("the WebSocket error is the source: {err:?}"));
    assert!(err.to_string().contains(&ws.to_string()), "{err}");
}

/// A server's text that is not JSON, and a JSON channel's message that is not: the parser's
/// error is the source.
#[test]
fn malformed_live_messages_keep_the_parser_error() {
    let err = protocol::parse_text("{\"op\": ").expect_err("a truncated op is refused");
    assert!(matches!(err, LiveError::NotAnOp(_)), "{err:?}");
    let json = err
        .source()
        .and_then(|s| s.downcast_ref::<serde_json::Error>())
        .unwrap_or_else(|| panic!("the parser's error is the source: {err:?}"));
    assert!(json.is_eof(), "{json}");

    let spec = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "raw"}]}"#,
        Path::new("spec.json"),
    )
    .unwrap();
    let plan = Plan::of(&spec).unwrap();
    let channel = Channel {
        id: 1,
        topic: "/a".into(),
        encoding: "json".into(),
        schema_name: "std_msgs/msg/Float64MultiArray".into(),
        schema_encoding: None,
        schema: String::new(),
    };
    let route = plan.route(&channel).unwrap().expect("the spec reads `/a`");
    let err = plan
        .decode(&route, b"{\"data\": [1, 2")
        .expect_err("a truncated message is refused");
    let json = err
        .source()
        .and_then(|s| s.downcast_ref::<serde_json::Error>())
        .unwrap_or_else(|| panic!("the parser's error is the source: {err:?}"));
    assert!(json.is_eof(), "{json}");
}

/// A bag whose tactile topic's definition only borrows the standard name: the session
/// error names the bag and the topic, and keeps the CDR check's own error as its source.
#[test]
fn a_bag_with_a_look_alike_definition_keeps_the_cdr_error() {
    let dir = common::temp_dir("error-sources-cdr");
    let bag = dir.join("look-alike.mcap");
    let mut w = mcap::WriteOptions::new()
        .create(std::io::BufWriter::new(
            std::fs::File::create(&bag).unwrap(),
        ))
        .unwrap();
    let schema = w
        .add_schema(
            "std_msgs/msg/Float64MultiArray",
            "ros2msg",
            b"std_msgs/MultiArrayLayout layout\nfloat64[] data\nint32 extra\n",
        )
        .unwrap();
    let channel = w
        .add_channel(schema, "/a", "cdr", &std::collections::BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 1,
        publish_time: 1,
    };
    w.write_to_known_channel(&header, &[0, 1, 0, 0]).unwrap();
    w.finish().unwrap();
    drop(w);
    let spec = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "raw"}],
            "grasps": {"events": "/ev"}}"#,
        Path::new("spec.json"),
    )
    .unwrap();
    let err = tactile_workbench::session::ros2::import_bag(&bag, &spec)
        .expect_err("a look-alike definition is refused");
    assert!(
        matches!(&err.location, Location::Topic { topic, .. } if topic == "/a"),
        "{err:?}"
    );
    let cdr = err
        .source()
        .and_then(|s| s.downcast_ref::<CdrError>())
        .unwrap_or_else(|| panic!("the CDR check's error is the source: {err:?}"));
    assert!(
        matches!(cdr, CdrError::NotStandard { inside: None, got, .. } if got.contains("int32 extra")),
        "{cdr:?}"
    );
    assert!(err.to_string().contains(&cdr.to_string()), "{err}");
}

/// A long CSV whose header names a column twice: the session error names the file and the
/// header's line, and keeps the CSV reader's own error as its source.
#[test]
fn a_long_csv_header_naming_a_column_twice_keeps_the_csv_error() {
    let spec = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "layout": "grid 1x2", "unit": "raw"}]}"#,
        Path::new("spec.json"),
    )
    .unwrap();
    let text = "grasp,time,object,a_1,a_2,a_1\ng1,0,cup,1,2,3\n";
    let err = long_csv::parse_long_csv(text, Path::new("long.csv"), &spec)
        .expect_err("a column named twice is refused");
    assert_eq!(
        err.location,
        Location::Line {
            line: 1,
            field: None
        }
    );
    let csv = err
        .source()
        .and_then(|s| s.downcast_ref::<CsvError>())
        .unwrap_or_else(|| panic!("the CSV reader's error is the source: {err:?}"));
    assert_eq!(
        csv,
        &CsvError::DuplicateColumn {
            first: 4,
            second: 6,
            name: "a_1".into()
        }
    );
    assert!(err.to_string().contains(&csv.to_string()), "{err}");
}

/// A long CSV row whose label is not one of its label set's classes: the session error
/// names the file, line and column, and keeps the spec's refusal as its source.
#[test]
fn a_class_the_spec_does_not_have_keeps_the_label_error() {
    let spec = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "layout": "grid 1x2", "unit": "raw"}],
            "label_sets": [{"name": "outcome", "classes": ["ok", "slip"]}]}"#,
        Path::new("spec.json"),
    )
    .unwrap();
    let text = "grasp,time,object,outcome,a_1,a_2\ng1,0,cup,wobbly,1,2\n";
    let err = long_csv::parse_long_csv(text, Path::new("long.csv"), &spec)
        .expect_err("a class the spec does not have is refused");
    assert_eq!(
        err.location,
        Location::Line {
            line: 2,
            field: Some("outcome".into())
        }
    );
    let label = err
        .source()
        .and_then(|s| s.downcast_ref::<LabelError>())
        .unwrap_or_else(|| panic!("the spec's refusal is the source: {err:?}"));
    assert!(
        matches!(label, LabelError::NotAClass { class, set, .. } if class == "wobbly" && set == "outcome"),
        "{label:?}"
    );
    assert!(err.to_string().contains(&label.to_string()), "{err}");
}

/// A spec whose layout object does not parse: the session error names the spec and the
/// field, and keeps the spec's error, whose source is the JSON parser's.
#[test]
fn a_layout_object_that_does_not_parse_keeps_the_parser_error() {
    let err = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "layout": {"kind": "hexagon"}, "unit": "raw"}]}"#,
        Path::new("spec.json"),
    )
    .expect_err("a layout object that does not parse is refused");
    assert_eq!(err.location, Location::Field("sensors[0].layout".into()));
    let chain = chain(&err);
    let spec = chain
        .get(1)
        .and_then(|e| e.downcast_ref::<SpecError>())
        .unwrap_or_else(|| panic!("the spec's error is the source: {chain:?}"));
    assert!(matches!(spec, SpecError::LayoutObject(_)), "{spec:?}");
    let json = chain
        .get(2)
        .and_then(|e| e.downcast_ref::<serde_json::Error>())
        .unwrap_or_else(|| panic!("the parser's error is the spec error's source: {chain:?}"));
    assert!(err.to_string().contains(&json.to_string()), "{err}");
}

/// A spec whose trial pattern does not parse: the session error names the field, and keeps
/// the spec's error, whose source is the pattern parser's.
#[test]
fn a_trial_pattern_that_does_not_parse_keeps_the_pattern_error() {
    let err = ImportSpec::from_str(
        r#"{"sensors": [{"name": "a", "layout": "grid 1x2", "unit": "raw"}],
            "trials": {"pattern": "{object.csv"}}"#,
        Path::new("spec.json"),
    )
    .expect_err("a pattern whose brace is not closed is refused");
    assert_eq!(err.location, Location::Field("trials.pattern".into()));
    let chain = chain(&err);
    assert!(
        matches!(
            chain.get(1).and_then(|e| e.downcast_ref::<SpecError>()),
            Some(SpecError::Pattern(_))
        ),
        "the spec's error is the source: {chain:?}"
    );
    let pattern = chain
        .get(2)
        .and_then(|e| e.downcast_ref::<PatternError>())
        .unwrap_or_else(|| panic!("the pattern's error is the spec error's source: {chain:?}"));
    assert_eq!(pattern, &PatternError::Unclosed);
    assert!(err.to_string().contains("a `{` is not closed"), "{err}");
}
