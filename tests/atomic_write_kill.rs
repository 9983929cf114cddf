//! Saving never leaves a half-written file: a writer killed at any moment leaves the old
//! file intact or the new one complete (temporary file + rename), never a mix.

mod common;

use std::process::Command;
use std::time::Duration;

use tactile_workbench::session::{self, native, simulate};

#[test]
fn a_writer_killed_midway_leaves_the_old_file_or_the_new_one() {
    let dir = common::temp_dir("kill-writer");
    let path = dir.join("object-recognition.json");
    let old = native::to_string(&simulate::object_recognition(1));
    let new = native::to_string(&simulate::object_recognition(2));
    assert_ne!(old, new);
    let (mut kept_old, mut got_new) = (0, 0);
    for round in 0..24u64 {
        std::fs::write(&path, &old).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .args(["simulate", "--kind", "recognition", "--seed", "2", "-o"])
            .arg(&dir)
            .stdout(std::process::Stdio::null())
            .spawn()
            .expect("start the writer");
        // Staggered kill times, from before the write starts to after it ends.
        std::thread::sleep(Duration::from_millis(2 + round * round * 2));
        let _ = child.kill();
        let _ = child.wait();
        let now = std::fs::read_to_string(&path).unwrap();
        if now == old {
            kept_old += 1;
        } else if now == new {
            got_new += 1;
        } else {
            panic!(
                "round {round}: the file is neither the old one nor the new one ({} bytes)",
                now.len()
            );
        }
        assert!(
            session::load(&path).is_ok(),
            "round {round}: the file does not load"
        );
    }
    // Both outcomes occur, so the kills really land before and after the rename.
    assert!(
        kept_old > 0 && got_new > 0,
        "old kept {kept_old}, new written {got_new}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
