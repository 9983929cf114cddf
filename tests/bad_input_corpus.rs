//! The corpus of malformed files in `tests/corpus/`: every reader gives an error that names
//! the file, the place and the problem (listed in `EXPECTED.tsv`), and none panics.

use std::path::{Path, PathBuf};

use tactile_workbench::session::{self, icub};

fn corpus() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus"))
}

/// Read the file with the reader of its folder.
fn read(path: &Path) -> Result<(), String> {
    let folder = path
        .parent()
        .and_then(|p| p.file_name())
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    match folder {
        "bts3" => session::import_bts3(path).map(|_| ()),
        "native" => session::load(path).map(|_| ()),
        "icub" => {
            let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
            match String::from_utf8(bytes) {
                Ok(text) => icub::parse_trial(&text, path).map(|_| ()),
                // The folder importer reads trial files through the same UTF-8 check;
                // exercise it by importing a folder holding only this file as trial 1.
                Err(_) => {
                    let dir =
                        std::env::temp_dir().join(format!("tw-corpus-{}", std::process::id()));
                    let _ = std::fs::remove_dir_all(&dir);
                    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
                    std::fs::copy(path, dir.join("blue_bear_1.txt")).map_err(|e| e.to_string())?;
                    let r = session::import_icub(&dir).map(|_| ());
                    let _ = std::fs::remove_dir_all(&dir);
                    return r.map_err(|e| {
                        e.to_string().replace(
                            &dir.join("blue_bear_1.txt").display().to_string(),
                            &path.display().to_string(),
                        )
                    });
                }
            }
        }
        other => panic!("no reader for corpus folder {other}"),
    }
    .map_err(|e| e.to_string())
}

#[test]
fn every_malformed_file_gives_a_named_error() {
    let expected = std::fs::read_to_string(corpus().join("EXPECTED.tsv")).unwrap();
    let mut checked = 0;
    for line in expected
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
    {
        let (file, want) = line.split_once('\t').unwrap_or((line, ""));
        let path = corpus().join(file);
        let result = std::panic::catch_unwind(|| read(&path));
        let result = result.unwrap_or_else(|_| panic!("{file}: the reader panicked"));
        match (result, want.is_empty()) {
            (Ok(()), true) => {}
            (Ok(()), false) => panic!("{file}: read without error, expected `{want}`"),
            (Err(e), true) => panic!("{file}: expected to be valid, got {e}"),
            (Err(e), false) => {
                assert!(
                    e.contains(&path.display().to_string()),
                    "{file}: the error does not name the file: {e}"
                );
                assert!(e.contains(want), "{file}: expected `{want}` in: {e}");
            }
        }
        checked += 1;
    }
    let files = ["bts3", "icub", "native"]
        .iter()
        .map(|d| {
            std::fs::read_dir(corpus().join(d))
                .map(|r| r.count())
                .unwrap_or(0)
        })
        .sum::<usize>();
    assert_eq!(
        checked, files,
        "every corpus file is listed in EXPECTED.tsv"
    );
}
