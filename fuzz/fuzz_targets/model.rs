//! The model-file reader on arbitrary bytes: errors name the file, and a model it accepts
//! predicts on the sample session or refuses it by name, and survives a save and a reload
//! unchanged; the file reader, which parses as it reads, gives what the text reader gives.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::models::{self, Calibration, ModelFile};

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        Ok(text) => {
            let path = "fuzz-model.json";
            let parsed = ModelFile::from_json(text, path);
            let file = common::scratch_file(data, "json");
            match (&parsed, models::load(&file)) {
                (Ok(a), Ok(b)) => assert_eq!(a.to_json(), b.to_json(), "the file reader differs"),
                (Err(_), Err(e)) => common::assert_names_file(&e, &file),
                (a, b) => panic!("the text reader gave {a:?}, the file reader {b:?}"),
            }
            match parsed {
                Ok(m) => {
                    let saved = m.to_json();
                    let reloaded = ModelFile::from_json(&saved, path)
                        .unwrap_or_else(|e| panic!("a saved model does not load: {e}"));
                    assert_eq!(reloaded.to_json(), saved, "the model changed through save and load");
                    let session = tactile_workbench::session::simulate::grasp_stability(0);
                    // Either predictions for every grasp, or an error; never a panic.
                    if let Ok(rows) = models::predict(&m, &session, Calibration::Session) {
                        assert_eq!(rows.len(), session.grasps.len());
                    }
                }
                Err(e) => common::assert_names_file(&e, Path::new(path)),
            }
        }
        Err(_) => {
            let path = common::scratch_file(data, "json");
            match models::load(&path) {
                Ok(_) => panic!("invalid UTF-8 was loaded"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
