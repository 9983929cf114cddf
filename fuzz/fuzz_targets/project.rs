//! The project reader on arbitrary bytes: errors name the file, and a project it accepts has
//! only drawable figures and survives a save and a reload unchanged; the file reader, which
//! parses as it reads, gives what the text reader gives.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::project::Project;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        Ok(text) => {
            let path = Path::new("fuzz-project.json");
            let parsed = Project::parse(text, path);
            let file = common::scratch_file(data, "json");
            match (&parsed, Project::load(&file)) {
                (Ok(_), Ok(_)) => {}
                (Err(_), Err(e)) => common::assert_names_file(&e, &file),
                (a, b) => panic!(
                    "the text reader gave {:?}, the file reader {:?}",
                    a.as_ref().map(|_| ()),
                    b.map(|_| ())
                ),
            }
            match parsed {
                Ok(p) => {
                    for r in &p.results {
                        for (_, f) in &r.figures {
                            assert!(f.validate().is_ok(), "an accepted figure does not validate");
                        }
                    }
                    let saved = serde_json::to_string(&p).expect("a project serialises");
                    let reloaded = Project::parse(&saved, path)
                        .unwrap_or_else(|e| panic!("a saved project does not load: {e}"));
                    // Compared as text: figures may hold NaN, which is never equal to itself.
                    assert_eq!(
                        serde_json::to_string(&reloaded).unwrap(),
                        saved,
                        "the project changed through save and load"
                    );
                }
                Err(e) => common::assert_names_file(&e, path),
            }
        }
        Err(_) => {
            let path = common::scratch_file(data, "json");
            match Project::load(&path) {
                Ok(_) => panic!("invalid UTF-8 was loaded"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
