//! The trial pattern of a folder of trial files on arbitrary text: the first line is the
//! pattern, each other line a path to match. A match must be a split of the path: the
//! captures, put back between the pattern's literal text, give the path again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::trial_pattern::{TRIAL, TrialPattern};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut lines = text.split('\n');
    let Some(Ok(pattern)) = lines.next().map(TrialPattern::parse) else {
        return;
    };
    for path in lines {
        let Some(captures) = pattern.captures(path) else {
            continue;
        };
        let names: Vec<&str> = pattern.names().collect();
        assert_eq!(captures.len(), names.len());
        for ((name, value), want) in captures.iter().zip(&names) {
            assert_eq!(name, want);
            assert!(
                !value.is_empty() && !value.contains('/'),
                "{name} = {value:?}"
            );
            if *name == TRIAL {
                assert!(value.bytes().all(|b| b.is_ascii_digit()), "{value:?}");
            }
        }
        // Every capture's text lies in the path, in order, without overlap.
        let mut at = 0;
        for (_, value) in &captures {
            let offset = value.as_ptr() as usize - path.as_ptr() as usize;
            assert!(offset >= at && offset + value.len() <= path.len());
            at = offset + value.len();
        }
    }
});
