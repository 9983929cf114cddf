//! Shared helpers of the integration tests.
#![allow(dead_code)] // each test binary uses a different subset

#[cfg(feature = "gui")]
pub mod gui;

use std::path::PathBuf;

/// `../shared/datasets/<rel>` beside the checkout, or None (with the reason printed) when
/// the real data is not there: tests that need it then skip.
pub fn dataset(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/datasets")).join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: real dataset {} is not present", p.display());
        None
    }
}

pub fn sample(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/sample-sessions")).join(name)
}

/// A fresh empty folder under the system temp dir.
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tw-test-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}
