//! Shared helpers of the integration tests.
#![allow(dead_code)] // each test binary uses a different subset

#[cfg(feature = "gui")]
pub mod gui;
pub mod legibility;

use std::path::PathBuf;

#[path = "../../src/test_datasets.rs"]
mod test_datasets;
#[allow(unused_imports)] // as dead_code above
pub use test_datasets::{dataset, datasets_dir};

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
