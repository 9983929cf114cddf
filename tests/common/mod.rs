//! Shared helpers of the integration tests.
#![allow(dead_code)] // each test binary uses a different subset

#[cfg(feature = "gui")]
pub mod gui;
pub mod legibility;

use std::path::{Path, PathBuf};

#[path = "../../src/test_datasets.rs"]
mod test_datasets;
#[allow(unused_imports)] // as dead_code above
pub use test_datasets::{dataset, datasets_dir};

pub fn sample(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/sample-sessions")).join(name)
}

/// A fresh empty folder under the system temp dir, removed with everything in it when the
/// value is dropped (a test that panics unwinds through the drop too): a run of the suite
/// leaves nothing behind on the machine's disk.
pub fn temp_dir(tag: &str) -> TempDir {
    let root = std::env::temp_dir().join(format!("tw-test-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).expect("temp dir");
    TempDir {
        path: root.clone(),
        root,
    }
}

/// A path inside a test's own temp folder (the folder itself, or a file or folder in it):
/// it reads as that path, and dropping it removes the whole folder. See [`temp_dir`].
pub struct TempDir {
    root: PathBuf,
    path: PathBuf,
}

impl TempDir {
    /// The path `name` inside this one, which now owns the folder.
    pub fn child(mut self, name: &str) -> TempDir {
        // The folder passes to the child: `self`, emptied, removes nothing when dropped.
        let root = std::mem::take(&mut self.root);
        TempDir {
            path: self.path.join(name),
            root,
        }
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !self.root.as_os_str().is_empty() {
            let _ = std::fs::remove_dir_all(&self.root);
        }
    }
}
