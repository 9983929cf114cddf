//! Saving never leaves a half-written file: a writer killed in the middle of its write
//! leaves the old file intact, and one that finishes leaves the new one (temporary file +
//! rename), never a mix.
//!
//! The writer is killed at a chosen point of the write, not at a chosen time: a file-size
//! limit (`ulimit -f`) makes the kernel stop it (SIGXFSZ) once it has written that much.
#![cfg(unix)]

mod common;

use std::path::Path;
use std::process::{Command, ExitStatus};

use tactile_workbench::session::{self, native, simulate};

/// Run `simulate` writing into `dir`, limited to files of `limit` blocks (none if None).
fn write_session(dir: &Path, limit: Option<usize>) -> ExitStatus {
    let limit = limit.map_or("unlimited".to_string(), |b| b.to_string());
    Command::new("sh")
        .args([
            "-c",
            "ulimit -c 0; ulimit -f \"$1\"; shift; exec \"$@\"",
            "sh",
            &limit,
            env!("CARGO_BIN_EXE_tactile-workbench"),
            "simulate",
            "--kind",
            "recognition",
            "--seed",
            "2",
            "-o",
        ])
        .arg(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .expect("start the writer")
}

#[test]
fn a_writer_killed_midway_leaves_the_old_file_and_a_finished_one_the_new() {
    let dir = common::temp_dir("kill-writer");
    let path = dir.join("object-recognition.json");
    let old = native::to_string(&simulate::object_recognition(1));
    let new = native::to_string(&simulate::object_recognition(2));
    assert_ne!(old, new);
    // Blocks are 512 or 1024 bytes depending on the shell: count in KiB so that every
    // limit falls inside the new file either way.
    let kib = new.len() / 1024;
    assert!(
        kib >= 8,
        "the session is large enough to cut: {} bytes",
        new.len()
    );
    for eighth in 1..8 {
        std::fs::write(&path, &old).unwrap();
        let status = write_session(&dir, Some(kib * eighth / 8));
        assert!(
            !status.success(),
            "cut at {eighth}/8: the writer should have been stopped mid-write"
        );
        let now = std::fs::read_to_string(&path).unwrap();
        assert!(
            now == old,
            "cut at {eighth}/8: the old file was replaced ({} bytes, old {}, new {})",
            now.len(),
            old.len(),
            new.len()
        );
        assert!(session::load(&path).is_ok(), "cut at {eighth}/8: loads");
    }
    std::fs::write(&path, &old).unwrap();
    assert!(write_session(&dir, None).success());
    assert_eq!(std::fs::read_to_string(&path).unwrap(), new);
    assert!(session::load(&path).is_ok());
    let _ = std::fs::remove_dir_all(dir);
}
