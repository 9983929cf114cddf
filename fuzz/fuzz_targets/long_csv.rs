//! The long-format CSV importer on arbitrary bytes, with the fixture's spec.
#![no_main]

use std::path::Path;
use std::sync::LazyLock;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{ImportSpec, long_csv};

#[path = "common.rs"]
mod common;

static SPEC: LazyLock<ImportSpec> = LazyLock::new(|| {
    let text = include_str!("../../tests/fixtures/long/grasps.spec.json");
    ImportSpec::from_str(text, Path::new("grasps.spec.json")).expect("the fixture spec reads")
});

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        // `import_long_csv` reads the file and runs this same UTF-8 check first.
        Ok(text) => {
            let path = Path::new("fuzz.csv");
            match long_csv::parse_long_csv(text, path, &SPEC) {
                Ok(s) => assert!(!s.grasps.is_empty()),
                Err(e) => common::assert_names_file(&e, path),
            }
        }
        Err(_) => {
            let path = common::scratch_file(data, "csv");
            match long_csv::import_long_csv(&path, &SPEC) {
                Ok(_) => panic!("invalid UTF-8 was imported"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
