//! The real datasets that tests read from `../shared/datasets` beside the checkout.
//!
//! Where they are absent a test that needs one skips, and says so on the terminal rather
//! than in its captured output (which libtest shows only for failures), so the run's
//! summary shows what was not tested. Under CI (the `CI` variable set) a missing dataset is
//! a failure, not a skip. Integration tests include this file through `tests/common`.

use std::io::Write;
use std::path::PathBuf;

/// The real datasets' folder beside the checkout.
pub fn datasets_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/datasets"))
}

/// `../shared/datasets/<rel>`, or None when it is absent outside CI: the caller skips.
///
/// # Panics
/// When it is absent and `CI` is set.
pub fn dataset(rel: &str) -> Option<PathBuf> {
    let p = datasets_dir().join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "real dataset {} is missing: under CI the real-data tests must run",
        p.display()
    );
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    // Straight to the terminal: libtest captures print! and eprint! only.
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED {test}: real dataset {} is not present",
        p.display()
    );
    None
}
