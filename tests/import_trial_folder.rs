//! Folders of trial files (one CSV per grasp), imported with their specs: the fixtures in
//! tests/fixtures/trials/ (written by make_trial_folders.py) hold the eight grasps of the
//! long-format CSV fixture, split into files by class folders and by file name, so each must
//! import to exactly the long CSV's grasps (themselves checked against the fixture script's
//! values in import_recordings.rs). Bad input gives an error naming the file and the line or
//! the path, and writes nothing.

mod common;
use common::TempDir;

use std::path::{Path, PathBuf};
use std::process::Command;

use tactile_workbench::session::{self, Session};

fn fixtures() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures"))
}

fn trials(name: &str) -> (PathBuf, PathBuf) {
    let d = fixtures().join("trials");
    (d.join(name), d.join(format!("{name}.spec.json")))
}

fn long_csv() -> Session {
    let d = fixtures().join("long");
    session::import_with_spec(&d.join("grasps.csv"), &d.join("grasps.spec.json")).unwrap()
}

fn import(dir: &Path, spec: &Path) -> Result<Session, String> {
    session::import_with_spec(dir, spec).map_err(|e| e.to_string())
}

/// The long CSV's grasps in the folder's natural path order: `box` before `cup`, `no` before
/// `yes`, then by number (grasp numbers 1-based, as the long CSV's ids `g1` … `g8`).
const PATH_ORDER: [usize; 8] = [4, 8, 2, 6, 3, 7, 1, 5];

/// Every grasp of `s` against the long CSV's grasp of the same number: object and classes
/// by name, every frame's time, taxels and encoders, and the key frame.
fn check_against_long_csv(s: &Session) {
    let long = long_csv();
    assert_eq!(s.sensors, long.sensors);
    assert_eq!(s.encoders, long.encoders);
    assert_eq!(s.meta.frame_rate_hz, Some(16.0));
    assert_eq!(s.grasps.len(), PATH_ORDER.len());
    let class = |s: &Session, g: usize, set: &str| {
        let l = s.label_set(set).unwrap();
        s.label_sets[l].classes[s.grasps[g].labels[l]].clone()
    };
    for (g, &n) in PATH_ORDER.iter().enumerate() {
        let (got, want) = (&s.grasps[g], &long.grasps[n - 1]);
        assert_eq!(got.object, want.object, "grasp {g}");
        for set in ["object", "stable"] {
            assert_eq!(
                class(s, g, set),
                class(&long, n - 1, set),
                "grasp {g}: {set}"
            );
        }
        assert_eq!(got.frames, want.frames, "grasp {g}: frames");
        assert_eq!(got.key_frame, want.key_frame, "grasp {g}: key frame");
    }
}

#[test]
fn a_folder_per_class_imports_the_long_csvs_grasps() {
    let (dir, spec) = trials("by-folder");
    let s = import(&dir, &spec).unwrap();
    check_against_long_csv(&s);
    assert_eq!(s.meta.name, "Trials by folder");
    assert_eq!(
        s.meta.source,
        "folder of trial files by-folder, imported with the spec by-folder.spec.json"
    );
    // Without `{trial}`, each object's files are numbered in their order.
    let t: Vec<u32> = s.grasps.iter().map(|g| g.trial.unwrap()).collect();
    assert_eq!(t, [1, 2, 3, 4, 1, 2, 3, 4]);
    assert!(
        s.meta.notes.contains("`{object}/{stable}/*.csv`"),
        "{}",
        s.meta.notes
    );
}

#[test]
fn a_file_name_pattern_imports_the_long_csvs_grasps() {
    let (dir, spec) = trials("by-name");
    let s = import(&dir, &spec).unwrap();
    // The files have no `time` column: rows are 1/16 s apart by the spec's rate, as the
    // long CSV's are by their times.
    check_against_long_csv(&s);
    // `{trial}` gives each grasp its number.
    let t: Vec<u32> = s.grasps.iter().map(|g| g.trial.unwrap()).collect();
    assert_eq!(t, PATH_ORDER.map(|n| n as u32));
}

#[test]
fn the_window_treats_a_folder_of_trial_files_as_a_recording() {
    let (dir, _) = trials("by-name");
    assert!(session::needs_spec(&dir));
    assert!(session::needs_spec(&trials("by-folder").0));
    // The bundled iCub layout (text trial files) is not one.
    let icub = common::temp_dir("trials-icub-like");
    std::fs::write(icub.join("blue_bear_1.txt"), "x").unwrap();
    assert!(!session::needs_spec(&icub));
    let _ = std::fs::remove_dir_all(icub);
}

// ---------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------

/// A scratch copy of a fixture folder (and its spec, beside it).
/// The copy owns the scratch folder (the spec's too).
fn copy_of(name: &str, tag: &str) -> (TempDir, PathBuf) {
    let (dir, spec) = trials(name);
    let root = common::temp_dir(tag);
    copy_dir(&dir, &root.join(name));
    let spec_copy = root.join(format!("{name}.spec.json"));
    std::fs::copy(&spec, &spec_copy).unwrap();
    (root.child(name), spec_copy)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

fn edit(file: &Path, f: impl Fn(String) -> String) {
    let text = std::fs::read_to_string(file).unwrap();
    let edited = f(text.clone());
    assert_ne!(edited, text, "the edit changed nothing");
    std::fs::write(file, edited).unwrap();
}

fn error_of(dir: &Path, spec: &Path) -> String {
    match import(dir, spec) {
        Ok(_) => panic!("{} imported without error", dir.display()),
        Err(e) => e,
    }
}

fn assert_has(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "expected `{p}` in: {e}");
    }
}

fn cleanup(dir: &Path) {
    if let Some(root) = dir.parent() {
        let _ = std::fs::remove_dir_all(root);
    }
}

#[test]
fn a_bad_value_names_the_file_line_and_column() {
    let (dir, spec) = copy_of("by-folder", "trials-bad-value");
    let file = dir.join("cup/no/g7.csv");
    // Line 3 (the second frame): `ff_2` becomes text.
    edit(&file, |t| {
        let mut lines: Vec<String> = t.lines().map(String::from).collect();
        let mut fields: Vec<&str> = lines[2].split(',').collect();
        fields[3] = "3x";
        lines[2] = fields.join(",");
        lines.join("\n")
    });
    let e = error_of(&dir, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:3: field `ff_2`", file.display()),
            "`3x` is not a number",
        ],
    );
    // A reading outside the sensor's range, and a non-finite one, in the pattern folder.
    let (dir2, spec2) = copy_of("by-name", "trials-bad-range");
    let file2 = dir2.join("box_yes_6.csv");
    edit(&file2, |t| {
        let mut lines: Vec<String> = t.lines().map(String::from).collect();
        let mut fields: Vec<String> = lines[4].split(',').map(String::from).collect();
        fields[13] = "250".into(); // ff_1
        lines[4] = fields.join(",");
        lines.join("\n")
    });
    let e = error_of(&dir2, &spec2);
    assert_has(
        &e,
        &[
            &format!("{}:5: field `ff_1`", file2.display()),
            "reading 250 is outside sensor `ff`'s range",
        ],
    );
    cleanup(&dir);
    cleanup(&dir2);
}

#[test]
fn a_missing_column_names_the_file_and_its_header() {
    let (dir, spec) = copy_of("by-folder", "trials-missing-column");
    let file = dir.join("box/yes/g2.csv");
    edit(&file, |t| t.replacen("th_4", "th_four", 1));
    let e = error_of(&dir, &spec);
    assert_has(&e, &[&format!("{}:1: no `th_4` column", file.display())]);
    cleanup(&dir);
}

#[test]
fn an_empty_folder_is_refused_by_name() {
    let root = common::temp_dir("trials-empty");
    let dir = root.join("empty");
    std::fs::create_dir_all(dir.join("cup")).unwrap();
    // Files that are not trial files do not count.
    std::fs::write(dir.join("README.txt"), "notes").unwrap();
    std::fs::write(dir.join(".hidden.csv"), "a,b").unwrap();
    let e = error_of(&dir, &trials("by-folder").1);
    assert_has(
        &e,
        &[
            &dir.display().to_string(),
            "the folder holds no trial files",
        ],
    );
    let _ = std::fs::remove_dir_all(root);
}

#[test]
fn a_file_not_matching_the_pattern_is_named() {
    let (dir, spec) = copy_of("by-name", "trials-no-match");
    let stray = dir.join("cup-yes-9.csv");
    std::fs::copy(dir.join("cup_yes_1.csv"), &stray).unwrap();
    let e = error_of(&dir, &spec);
    assert_has(
        &e,
        &[
            &stray.display().to_string(),
            "from its path `cup-yes-9.csv`: does not match the spec's trial pattern \
             `{object}_{stable}_{trial}.csv`",
        ],
    );
    std::fs::remove_file(&stray).unwrap();
    // A file one folder too deep for the default pattern.
    let (dir2, spec2) = copy_of("by-folder", "trials-too-deep");
    let deep = dir2.join("cup/yes/old/g1.csv");
    std::fs::create_dir_all(deep.parent().unwrap()).unwrap();
    std::fs::copy(dir2.join("cup/yes/g1.csv"), &deep).unwrap();
    let e = error_of(&dir2, &spec2);
    assert_has(&e, &[&deep.display().to_string(), "does not match"]);
    // A class the spec does not have, and a trial number given twice.
    std::fs::remove_file(&deep).unwrap();
    let maybe = dir2.join("cup/maybe/g9.csv");
    std::fs::create_dir_all(maybe.parent().unwrap()).unwrap();
    std::fs::copy(dir2.join("cup/yes/g1.csv"), &maybe).unwrap();
    let e = error_of(&dir2, &spec2);
    assert_has(
        &e,
        &[
            &maybe.display().to_string(),
            "`maybe` is not a class of label set `stable` (yes, no)",
        ],
    );
    let again = dir.join("cup_no_1.csv");
    std::fs::copy(dir.join("cup_yes_1.csv"), &again).unwrap();
    let e = error_of(&dir, &spec);
    assert_has(
        &e,
        &[
            &again.display().to_string(),
            "trial 1 of `cup` again",
            &dir.join("cup_yes_1.csv").display().to_string(),
        ],
    );
    cleanup(&dir);
    cleanup(&dir2);
}

#[test]
fn mixed_taxel_counts_are_refused_naming_the_file() {
    // One file has three more `ff` taxels than the spec's 2 × 3 grid: they would be lost.
    let (dir, spec) = copy_of("by-folder", "trials-more-taxels");
    let file = dir.join("box/no/g8.csv");
    edit(&file, |t| {
        t.lines()
            .enumerate()
            .map(|(i, l)| match i {
                0 => format!("{l},ff_7,ff_8,ff_9"),
                _ => format!("{l},1,2,3"),
            })
            .collect::<Vec<_>>()
            .join("\n")
    });
    let e = error_of(&dir, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:1:", file.display()),
            "column `ff_7` is not a taxel of sensor `ff`, whose layout has 6",
        ],
    );
    // A row with fewer values than the header.
    let (dir2, spec2) = copy_of("by-name", "trials-short-row");
    let file2 = dir2.join("cup_no_7.csv");
    edit(&file2, |t| t.replacen(",row 2", "", 1));
    let e = error_of(&dir2, &spec2);
    assert_has(
        &e,
        &[&format!("{}:4: 15 values, expected 16", file2.display())],
    );
    cleanup(&dir);
    cleanup(&dir2);
}

#[test]
fn a_pattern_that_cannot_give_every_label_is_a_spec_error() {
    let (dir, spec) = trials("by-name");
    let root = common::temp_dir("trials-bad-pattern");
    let text = std::fs::read_to_string(&spec).unwrap();
    for (pattern, want) in [
        ("{object}_{trial}.csv", "does not capture `{stable}`"),
        (
            "{object}_{colour}_{trial}.csv",
            "`{colour}` is neither `{object}`, `{trial}` nor a label set",
        ),
        ("{object}_{stable.csv", "a `{` is not closed"),
        ("{object}_{stable}_{trial}.txt", "does not end in `.csv`"),
    ] {
        let bad = root.join("bad.spec.json");
        std::fs::write(&bad, text.replace("{object}_{stable}_{trial}.csv", pattern)).unwrap();
        let e = error_of(&dir, &bad);
        assert_has(&e, &[&bad.display().to_string(), "`trials.pattern`", want]);
    }
    let _ = std::fs::remove_dir_all(root);
}

/// `import csv DIR -o OUT`: a failed import writes nothing, a good one writes the session,
/// and an output that is one of the trial files (or the spec) is refused before anything
/// is read, naming both, with the file left intact.
#[test]
fn the_command_writes_only_good_sessions_and_never_over_an_input() {
    let run = |dir: &Path, out: &Path, spec: &Path| {
        Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .args(["import", "csv"])
            .arg(dir)
            .arg("-o")
            .arg(out)
            .arg("--spec")
            .arg(spec)
            .output()
            .unwrap()
    };
    let (dir, spec) = copy_of("by-name", "trials-cli");
    let out = dir.parent().unwrap().join("session.json");
    let r = run(&dir, &out, &spec);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(session::load(&out).unwrap(), import(&dir, &spec).unwrap());
    std::fs::remove_file(&out).unwrap();
    let trial = dir.join("cup_yes_5.csv");
    let before = std::fs::read(&trial).unwrap();
    for output in [&trial, &spec] {
        let r = run(&dir, output, &spec);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{err}");
        assert!(
            err.contains(&format!("the output {} is the input", output.display())),
            "{err}"
        );
    }
    assert_eq!(
        std::fs::read(&trial).unwrap(),
        before,
        "the trial file is intact"
    );
    edit(&trial, |t| {
        let (header, rows) = t.split_once('\n').unwrap();
        let (_, rest) = rows.split_once(',').unwrap();
        format!("{header}\nnan,{rest}")
    });
    let r = run(&dir, &out, &spec);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success(), "{err}");
    assert!(err.contains("not a finite number"), "{err}");
    assert!(!out.exists(), "a failed import wrote its output");
    cleanup(&dir);
}
