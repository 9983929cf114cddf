//! Shared by the targets: how the fuzzer's bytes reach a reader, and the checks every
//! reader's errors must pass.

use std::fmt::Display;
use std::path::{Path, PathBuf};

/// A scratch file of this process: readers that only take a path (`import_bts3`,
/// `session::load`) then see the bytes exactly as they would see a user's file.
pub fn scratch_file(data: &[u8], extension: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("tw-fuzz-{}.{extension}", std::process::id()));
    std::fs::write(&path, data).expect("the scratch file can be written");
    path
}

/// Every reader's error names the file it comes from (the project's error standard).
pub fn assert_names_file(error: &impl Display, path: &Path) {
    let message = error.to_string();
    assert!(
        message.contains(&path.display().to_string()),
        "the error does not name {}: {message}",
        path.display()
    );
}
