//! One iCub trial file on arbitrary bytes. The folder importer (`import_icub`) needs all
//! 200 trial files, so this target runs what it does per file: a strict UTF-8 check
//! (`String::from_utf8`, as its private `read_text`), then `parse_trial`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::icub;

#[path = "common.rs"]
#[allow(dead_code)] // this target has no file-reading entry point to write to
mod common;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("blue_bear_1.txt");
    match icub::parse_trial(text, path) {
        Ok(frames) => {
            // Every frame the importer keeps has the dataset's shape and finite values.
            for f in &frames {
                assert_eq!(f.taxels.len(), icub::FINGERS.len());
                assert!(f.taxels.iter().all(|t| t.len() == icub::TAXELS));
                assert_eq!(f.encoders.len(), icub::ENCODERS);
                assert!(
                    f.taxels
                        .iter()
                        .flatten()
                        .chain(&f.encoders)
                        .all(|v| v.is_finite())
                );
            }
        }
        Err(e) => common::assert_names_file(&e, path),
    }
});
