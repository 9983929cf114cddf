//! The native session reader on arbitrary bytes; a session it accepts must survive a
//! save and a reload unchanged (the workbench must never lose data), and the file reader,
//! which parses as it reads, must give what the text reader gives.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{self, native};

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    match std::str::from_utf8(data) {
        Ok(text) => {
            let path = Path::new("fuzz.json");
            let parsed = native::from_str(text, path);
            let file = common::scratch_file(data, "json");
            match (&parsed, session::load(&file)) {
                (Ok(a), Ok(b)) => assert_eq!(a, &b, "the file reader read another session"),
                (Err(_), Err(e)) => common::assert_names_file(&e, &file),
                (a, b) => panic!("the text reader gave {a:?}, the file reader {b:?}"),
            }
            match parsed {
                Ok(s) => {
                    let saved = native::to_string(&s);
                    let reloaded = native::from_str(&saved, path)
                        .unwrap_or_else(|e| panic!("a saved session does not load: {e}"));
                    assert_eq!(reloaded, s, "the session changed through save and load");
                }
                Err(e) => common::assert_names_file(&e, path),
            }
        }
        // Invalid UTF-8 goes through the real file reader and its UTF-8 error.
        Err(_) => {
            let path = common::scratch_file(data, "json");
            match session::load(&path) {
                Ok(_) => panic!("invalid UTF-8 was loaded"),
                Err(e) => common::assert_names_file(&e, &path),
            }
        }
    }
});
