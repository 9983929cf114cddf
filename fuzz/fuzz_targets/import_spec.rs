//! The import spec reader on arbitrary bytes; a spec it accepts drives the long-format CSV
//! importer over the fixture CSV without panicking (the spec's layouts, slices, ranges and
//! label sets reach the importer's indexing and the session's validation). The file reader,
//! which parses as it reads, gives what the text reader gives.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{ImportSpec, long_csv};

#[path = "common.rs"]
mod common;

const CSV: &str = include_str!("../../tests/fixtures/long/grasps.csv");

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        Ok(text) => {
            let path = Path::new("fuzz.spec.json");
            let parsed = ImportSpec::from_str(text, path);
            let file = common::scratch_file(data, "json");
            match (&parsed, ImportSpec::load(&file)) {
                (Ok(a), Ok(b)) => assert_eq!(a.sensors, b.sensors, "the file reader differs"),
                (Err(_), Err(e)) => common::assert_names_file(&e, &file),
                (a, b) => panic!("the text reader gave {a:?}, the file reader {b:?}"),
            }
            match parsed {
                Ok(spec) => {
                    let csv = Path::new("grasps.csv");
                    if let Err(e) = long_csv::parse_long_csv(CSV, csv, &spec) {
                        let m = e.to_string();
                        assert!(
                            m.contains("grasps.csv") || m.contains("fuzz.spec.json"),
                            "the error names neither file: {m}"
                        );
                    }
                }
                Err(e) => common::assert_names_file(&e, path),
            }
        }
        Err(_) => {
            let path = common::scratch_file(data, "json");
            match ImportSpec::load(&path) {
                Ok(_) => panic!("invalid UTF-8 was read as a spec"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
