//! One trial file of a folder of trial files, on arbitrary text, with the by-folder fixture's
//! spec (two 2 × 3 sensors, two joints, 16 Hz, so a file without `time` is timed by rows):
//! the long CSV's row parser as the folder importer uses it.
#![no_main]

use std::path::Path;
use std::sync::LazyLock;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{ImportSpec, trial_folder};

// Only its error check is used here.
#[allow(dead_code)]
#[path = "common.rs"]
mod common;

static SPEC: LazyLock<ImportSpec> = LazyLock::new(|| {
    let text = include_str!("../../tests/fixtures/trials/by-folder.spec.json");
    ImportSpec::from_str(text, Path::new("by-folder.spec.json")).expect("the fixture spec reads")
});

fuzz_target!(|data: &[u8]| {
    // The importer reads each file with the UTF-8 check every text reader shares (fuzzed by
    // the other targets); the parse is what is new.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz-trial.csv");
    match trial_folder::parse_trial(text, path, &SPEC) {
        Ok(trial) => {
            assert!(!trial.frames.is_empty(), "a trial without frames");
            assert_eq!(trial.frames[0].t, 0.0, "the first frame is not at t = 0");
            for w in trial.frames.windows(2) {
                assert!(
                    w[0].t <= w[1].t,
                    "time goes backwards: {} then {}",
                    w[0].t,
                    w[1].t
                );
            }
            for f in &trial.frames {
                assert!(f.t.is_finite());
                assert_eq!(f.taxels.len(), 2);
                for (s, values) in f.taxels.iter().enumerate() {
                    assert_eq!(values.len(), 6, "sensor {s}");
                    assert!(
                        values.iter().all(|v| (0.0..=100.0).contains(v)),
                        "{values:?}"
                    );
                }
                assert_eq!(f.encoders.len(), 2);
                assert!(f.encoders.iter().all(|v| v.is_finite()));
            }
            if let Some(k) = trial.key_frame {
                assert!(k < trial.frames.len());
            }
        }
        Err(e) => common::assert_names_file(&e, path),
    }
});
