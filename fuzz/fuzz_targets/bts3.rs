//! The BTS3 (BioTac palm-down CSV) importer on arbitrary bytes.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{self, bts3};

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        // `import_bts3` reads the file and runs this same UTF-8 check before `parse_bts3`:
        // valid text goes straight to the parser, without the cost of a file.
        Ok(text) => {
            let path = Path::new("fuzz.csv");
            if let Err(e) = bts3::parse_bts3(text, path) {
                common::assert_names_file(&e, path);
            }
        }
        // Invalid UTF-8 goes through the real file reader and its UTF-8 error.
        Err(_) => {
            let path = common::scratch_file(data, "csv");
            match session::import_bts3(&path) {
                Ok(_) => panic!("invalid UTF-8 was imported"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
