//! The adversarial pass of issue 44, through the command line: outputs that are devices,
//! folders or inside an input; trial ranges, wide CSVs, many sensors and junk files that
//! must cost neither time nor memory; model files, specs and sweep plans that must not be
//! trusted blindly. Each case and what it gets is listed in docs/testing.md.

mod common;

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use serde_json::Value;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_tactile-workbench")
}

fn run(args: &[&str]) -> Output {
    Command::new(bin())
        .args(args)
        .output()
        .expect("the binary runs")
}

/// The command under a limit of `mb` megabytes of address space (`ulimit -v`): an input
/// that makes it allocate for what a file declares fails instead of swapping.
fn run_in_memory(mb: u64, args: &[&str]) -> Output {
    let quoted: Vec<String> = std::iter::once(bin())
        .chain(args.iter().copied())
        .map(|a| format!("'{}'", a.replace('\'', r"'\''")))
        .collect();
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {}; exec {}",
            mb * 1024,
            quoted.join(" ")
        ))
        .output()
        .expect("sh runs")
}

/// The command, killed if it runs past `limit`: a guard against work quadratic in what a
/// file declares (seconds where linear work takes a fraction of one), not a measure of speed.
fn run_within(limit: Duration, args: &[&str]) -> Output {
    let child = Command::new(bin())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let pid = child.id().to_string();
    // The output is read while the command runs, so that a full pipe never stalls it.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(child.wait_with_output()));
    match rx.recv_timeout(limit) {
        Ok(out) => out.expect("output"),
        Err(_) => {
            let _ = Command::new("kill").args(["-9", &pid]).status();
            panic!("{args:?} still ran after {limit:?}");
        }
    }
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "failed: {}\n{}",
        stderr(out),
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The command failed with an error holding every one of `parts`.
fn fails_with(out: &Output, parts: &[&str]) -> String {
    let e = stderr(out);
    assert!(!out.status.success(), "succeeded; stderr: {e}");
    for p in parts {
        assert!(e.contains(p), "no {p:?} in: {e}");
    }
    e
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

fn fixtures() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures"))
}

fn model_seed(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/seeds/model")).join(name)
}

/// A device node like `/dev/null` (`full`: like `/dev/full`) in `dir`, made with mknod
/// where this user may (as root): a writer that replaced it by a file would then replace
/// the copy, never the system's node. Elsewhere the system's node, which such a user
/// cannot replace.
fn device(dir: &Path, full: bool) -> PathBuf {
    let (name, minor) = if full { ("full", "7") } else { ("null", "3") };
    let node = dir.join(name);
    let made = Command::new("mknod")
        .args([s(&node), "c", "1", minor])
        .status()
        .is_ok_and(|st| st.success());
    if made {
        node
    } else {
        PathBuf::from("/dev").join(name)
    }
}

#[cfg(unix)]
fn is_char_device(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device())
}

/// Defect 1: a device is written in place (null discards, full reports a full disk), a FIFO
/// passes the output on, a folder is refused by name; nothing replaces the node.
#[cfg(unix)]
#[test]
fn outputs_that_are_devices_are_written_in_place_and_folders_refused() {
    let dir = common::temp_dir("adv-devices");
    let sample = common::sample("object-recognition.json");
    let subset = |out: &Path| run(&["subset", s(&sample), "--trials", "1..2", "-o", s(out)]);

    let null = device(&dir, false);
    ok(&subset(&null));
    assert!(
        is_char_device(&null),
        "{} is still the device",
        null.display()
    );

    let full = device(&dir, true);
    fails_with(&subset(&full), &["No space left"]);
    assert!(
        is_char_device(&full),
        "{} is still the device",
        full.display()
    );

    let folder = dir.join("a-folder");
    fs::create_dir(&folder).unwrap();
    fails_with(&subset(&folder), &[s(&folder), "a folder"]);
    assert!(folder.is_dir());

    // A FIFO (as `/dev/stdout` is a pipe under a shell): what is written comes out of it.
    let fifo = dir.join("fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            fs::File::open(&fifo)
                .and_then(|mut f| f.read_to_string(&mut text))
                .map(|_| text)
        })
    };
    let (csv, spec) = (
        fixtures().join("long/grasps.csv"),
        fixtures().join("long/grasps.spec.json"),
    );
    let out = run(&["import", "csv", s(&csv), "--spec", s(&spec), "-o", s(&fifo)]);
    if !out.status.success() {
        // Unblock the reader before failing.
        let _ = fs::OpenOptions::new().write(true).open(&fifo);
    }
    ok(&out);
    let text = reader.join().unwrap().unwrap();
    assert!(text.contains("tactile-workbench-session"), "{text:.200}");
    assert!(!fifo.is_file(), "the FIFO was not replaced by a file");
}

/// Defect 2: an output inside a bag folder the import reads is refused, and the bag still
/// imports.
#[test]
fn an_import_never_writes_inside_the_folder_it_reads() {
    let dir = common::temp_dir("adv-inside");
    let bag = dir.join("bag");
    fs::create_dir(&bag).unwrap();
    let source = fixtures().join("ros2/zstd-events");
    for e in fs::read_dir(&source).unwrap() {
        let e = e.unwrap();
        fs::copy(e.path(), bag.join(e.file_name())).unwrap();
    }
    let spec = fixtures().join("ros2/zstd-events.spec.json");
    let metadata = bag.join("metadata.yaml");
    let before = fs::read(&metadata).unwrap();
    let import = |out: &Path| run(&["import", "mcap", s(&bag), "--spec", s(&spec), "-o", s(out)]);
    fails_with(&import(&metadata), &["inside the input folder", s(&bag)]);
    fails_with(&import(&bag.join("new.json")), &["inside the input folder"]);
    assert_eq!(fs::read(&metadata).unwrap(), before);
    ok(&import(&dir.join("session.json")));
}

/// Defect 3: a range stays a range (a billion trials in a small address space), and an
/// empty list or item is refused.
#[test]
fn trial_ranges_stay_ranges_and_empty_items_are_refused() {
    let dir = common::temp_dir("adv-trials");
    let sample = common::sample("object-recognition.json");
    let out = dir.join("part.json");
    let o = run_in_memory(
        1024,
        &[
            "subset",
            s(&sample),
            "--trials",
            "1..4000000000",
            "-o",
            s(&out),
        ],
    );
    let text = ok(&o);
    assert!(text.contains("trials 1..4000000000"), "{text}");
    for bad in ["", " ", "1,,2", "1,", "3..1"] {
        fails_with(
            &run(&["subset", s(&sample), "--trials", bad, "-o", s(&out)]),
            &["--trials"],
        );
    }
}

/// A long CSV of the fixture's spec with `extra` more columns, each ignored.
fn wide_csv(dir: &Path, extra: usize) -> PathBuf {
    let text = fs::read_to_string(fixtures().join("long/grasps.csv")).unwrap();
    let mut out = String::with_capacity(text.len() + extra * 12 * 2);
    for (i, line) in text.lines().enumerate() {
        out.push_str(line);
        for k in 0..extra {
            if i == 0 {
                out.push_str(&format!(",extra_{k}"));
            } else {
                out.push_str(",0");
            }
        }
        out.push('\n');
    }
    let path = dir.join(format!("wide-{extra}.csv"));
    fs::write(&path, out).unwrap();
    path
}

/// Defect 4: ignored columns and declared sensors cost linear time (a hundred thousand in
/// well under the guard's limit, where the quadratic reading took a minute), and past
/// their documented bounds they are refused naming the bound.
#[test]
fn wide_csvs_and_many_sensors_are_read_in_linear_time_up_to_their_bounds() {
    let dir = common::temp_dir("adv-quadratic");
    let spec = fixtures().join("long/grasps.spec.json");
    let limit = Duration::from_secs(20);
    let csv = wide_csv(&dir, 100_000);
    let out = dir.join("wide.json");
    ok(&run_within(
        limit,
        &["import", "csv", s(&csv), "--spec", s(&spec), "-o", s(&out)],
    ));
    let csv = wide_csv(&dir, 140_000);
    fails_with(
        &run_within(
            limit,
            &["import", "csv", s(&csv), "--spec", s(&spec), "-o", s(&out)],
        ),
        &[s(&csv), "more than 131072 columns"],
    );

    let mut many: Value = serde_json::from_str(&fs::read_to_string(&spec).unwrap()).unwrap();
    let sensor = many["sensors"][0].clone();
    many["sensors"] = (0..200_000)
        .map(|i| {
            let mut s = sensor.clone();
            s["name"] = format!("s{i}").into();
            s
        })
        .collect();
    let many_spec = dir.join("many.spec.json");
    fs::write(&many_spec, many.to_string()).unwrap();
    let csv = fixtures().join("long/grasps.csv");
    fails_with(
        &run_within(
            limit,
            &[
                "import",
                "csv",
                s(&csv),
                "--spec",
                s(&many_spec),
                "-o",
                s(&out),
            ],
        ),
        &[s(&many_spec), "`sensors`", "more than the 1024"],
    );
}

/// A spec declaring `classes` classes of `stable` (the fixture's two among them) and a long
/// CSV of one grasp of `rows` rows of its last class: each row is labelled in one look-up.
#[test]
fn many_classes_label_many_rows_in_linear_time() {
    let dir = common::temp_dir("adv-classes");
    let n = 100_000;
    let text = fs::read_to_string(fixtures().join("long/grasps.spec.json")).unwrap();
    let mut spec: Value = serde_json::from_str(&text).unwrap();
    spec["label_sets"][0]["classes"] = (0..n).map(|i| format!("c{i}")).collect();
    let spec_path = dir.join("classes.spec.json");
    fs::write(&spec_path, spec.to_string()).unwrap();
    let mut csv = String::from("grasp,time,object,stable,key");
    for s in ["ff", "th"] {
        for k in 1..=6 {
            csv.push_str(&format!(",{s}_{k}"));
        }
    }
    csv.push_str(",j1,j2\n");
    for r in 0..n {
        csv.push_str(&format!(
            "g1,{r},cup,c{},,1,1,1,1,1,1,1,1,1,1,1,1,0,0\n",
            n - 1
        ));
    }
    let csv_path = dir.join("rows.csv");
    fs::write(&csv_path, csv).unwrap();
    let out = dir.join("session.json");
    ok(&run_within(
        Duration::from_secs(20),
        &[
            "import",
            "csv",
            s(&csv_path),
            "--spec",
            s(&spec_path),
            "-o",
            s(&out),
        ],
    ));
}

/// A sparse file of `len` zero bytes (no disk space taken).
fn junk(dir: &Path, name: &str, len: u64) -> PathBuf {
    let path = dir.join(name);
    fs::File::create(&path).unwrap().set_len(len).unwrap();
    path
}

/// Defect 5: a 1 GiB junk model, session or spec is refused with an error naming it, in an
/// address space far smaller than the file (it is never read whole).
#[test]
fn junk_files_are_refused_without_being_read_whole() {
    let dir = common::temp_dir("adv-junk");
    let gib = 1 << 30;
    let sample = common::sample("grasp-stability.json");
    let out = dir.join("out.csv");
    let model = junk(&dir, "model.json", gib);
    fails_with(
        &run_in_memory(400, &["predict", s(&model), s(&sample), "-o", s(&out)]),
        &[s(&model), "more than the 256 MiB"],
    );
    let session = junk(&dir, "session.json", gib);
    fails_with(
        &run_in_memory(400, &["info", s(&session)]),
        &[s(&session), "expected value"],
    );
    let spec = junk(&dir, "spec.json", gib);
    let csv = fixtures().join("long/grasps.csv");
    fails_with(
        &run_in_memory(
            400,
            &["import", "csv", s(&csv), "--spec", s(&spec), "-o", s(&out)],
        ),
        &[s(&spec), "more than the 64 MiB"],
    );
    assert!(!out.exists());
    let figure = junk(&dir, "figure.json", gib);
    let svg = dir.join("out.svg");
    fails_with(
        &run_in_memory(400, &["render-figure", s(&figure), "-o", s(&svg)]),
        &[s(&figure), "more than the 256 MiB"],
    );
    assert!(!svg.exists());
}

/// A change made to a model file's JSON.
type Edit = Box<dyn Fn(&mut Value)>;

/// The raw-SVM model of the grasp-stability sample, changed by `edit`, written to `dir`.
fn edited_model(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let text = fs::read_to_string(model_seed("raw-svm-sample.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    edit(&mut v);
    let path = dir.join(name);
    fs::write(&path, v.to_string()).unwrap();
    path
}

/// Defect 6: every field that decides a prediction is checked, naming it, and a prediction
/// that comes out infinite is an error, never a class.
#[test]
fn model_fields_that_decide_a_prediction_are_checked() {
    let dir = common::temp_dir("adv-model");
    let sample = common::sample("grasp-stability.json");
    let out = dir.join("predictions.csv");
    let predict = |model: &Path| run(&["predict", s(model), s(&sample), "-o", s(&out)]);

    let huge = edited_model(&dir, "huge.json", |v| {
        v["model"]["svm"]["weights"]["data"][0] = 1e308.into();
    });
    fails_with(&predict(&huge), &["not a finite number", "grasp"]);
    assert!(!out.exists(), "no predictions written");
    let json = dir.join("evaluation.json");
    fails_with(
        &run(&["evaluate", s(&huge), s(&sample), "--json", s(&json)]),
        &["not a finite number"],
    );
    for (name, classes) in [
        ("none", Value::Array(vec![])),
        ("twice", serde_json::json!(["success", "success"])),
    ] {
        let m = edited_model(&dir, &format!("classes-{name}.json"), |v| {
            v["provenance"]["classes"] = classes;
        });
        fails_with(&predict(&m), &[s(&m), "provenance.classes"]);
    }

    // The RBF SVM: a machine's class out of the model's classes, and a kernel width ≤ 0.
    let recognition = common::sample("object-recognition.json");
    let rbf = dir.join("rbf.json");
    ok(&run(&["fit", "rbf-svm", s(&recognition), "-o", s(&rbf)]));
    let base: Value = serde_json::from_str(&fs::read_to_string(&rbf).unwrap()).unwrap();
    let cases: [(&str, Edit); 3] = [
        (
            "learner.machines[0].classes",
            Box::new(|v| v["model"]["learner"]["state"]["machines"][0]["classes"][0] = 99.into()),
        ),
        (
            "learner.gamma",
            Box::new(|v| v["model"]["learner"]["state"]["gamma"] = (-1.0).into()),
        ),
        (
            "learner.scaler",
            Box::new(|v| {
                let scale = &mut v["model"]["learner"]["state"]["scaler"]["scale"];
                let n = scale.as_array().unwrap().len();
                *scale = vec![0.0; n].into();
            }),
        ),
    ];
    for (field, edit) in cases {
        let mut v = base.clone();
        edit(&mut v);
        let m = dir.join("rbf-edited.json");
        fs::write(&m, v.to_string()).unwrap();
        fails_with(&run(&["evaluate", s(&m), s(&recognition)]), &[s(&m), field]);
    }
}

/// A grasp-stability plan of a tiny grid in `dir` (with `extra` options).
fn plan(dir: &Path, extra: &[&str]) -> Output {
    let sample = common::sample("grasp-stability.json");
    let mut args = vec![
        "sweep",
        "plan",
        "stability",
        s(&sample),
        "--num-bases",
        "2,4",
        "--beta",
        "1",
        "--gamma",
        "1",
        "--cv",
        "3",
        "--shards",
        "1",
        "-o",
        s(dir),
    ];
    args.extend(extra);
    run(&args)
}

/// Defect 7: nothing that enters the Slurm script can add a line to it, and a plan's
/// session is its own copy beside it, never a path elsewhere.
#[test]
fn sweep_plans_neither_inject_lines_nor_follow_paths_out() {
    let dir = common::temp_dir("adv-sweep");
    let injected = "gpu\n#SBATCH --wrap=\"rm -rf ~\"";
    fails_with(
        &plan(&dir.join("p1"), &["--partition", injected]),
        &["--partition", "control character"],
    );
    assert!(!dir.join("p1").exists(), "nothing written");
    fails_with(
        &plan(&dir.join("p2\ntouch x"), &[]),
        &["plan folder", "control character"],
    );
    fails_with(
        &plan(&dir.join("p3"), &["--program", "tw\nrm -rf ~"]),
        &["--program", "control character"],
    );

    // A value with spaces and `#` stays one quoted value of its line.
    let p = dir.join("with space #x");
    ok(&plan(&p, &["--partition", "gpu #short"]));
    let script = fs::read_to_string(p.join("sweep.sbatch")).unwrap();
    assert!(
        script.contains("#SBATCH --partition=\"gpu #short\"\n"),
        "{script}"
    );
    let chdir = format!(
        "#SBATCH --chdir=\"{}\"\n",
        fs::canonicalize(&p).unwrap().display()
    );
    assert!(script.contains(&chdir), "{script}");

    let plan_file = p.join("plan.json");
    let good = fs::read_to_string(&plan_file).unwrap();
    for elsewhere in ["/etc/passwd", "../../etc/passwd", "shards/../session.json"] {
        let mut v: Value = serde_json::from_str(&good).unwrap();
        v["session"]["file"] = elsewhere.into();
        fs::write(&plan_file, v.to_string()).unwrap();
        for command in ["status", "run"] {
            let mut args = vec!["sweep", command, s(&p)];
            if command == "run" {
                args.extend(["--shard", "0"]);
            }
            fails_with(&run(&args), &["session.file", elsewhere]);
        }
    }
}

/// Defect 8: a spec's layout errors name the spec and the field, duplicate cells of a
/// sparse grid are refused, and a byte-order mark before a spec or a model is accepted.
#[test]
fn specs_name_their_own_errors_and_a_byte_order_mark_is_read() {
    let dir = common::temp_dir("adv-spec");
    let csv = fixtures().join("long/grasps.csv");
    let text = fs::read_to_string(fixtures().join("long/grasps.spec.json")).unwrap();
    let base: Value = serde_json::from_str(&text).unwrap();
    let out = dir.join("session.json");
    let sparse = |cells: Value| {
        serde_json::json!({
            "kind": "sparse_grid", "rows": 2, "cols": 3, "cells": cells
        })
    };
    let cases = [
        (
            sparse(serde_json::json!([
                [0, 0],
                [0, 1],
                [0, 2],
                [1, 0],
                [1, 1],
                [0, 1]
            ])),
            "sensors[0].layout.cells[5]",
        ),
        (
            sparse(serde_json::json!([
                [0, 0],
                [0, 1],
                [0, 2],
                [1, 0],
                [1, 1],
                [2, 0]
            ])),
            "sensors[0].layout.cells[5]",
        ),
        (
            serde_json::json!({
                "kind": "points", "radius": 0.0,
                "positions": (0..6).map(|i| serde_json::json!({"x": i, "y": 0})).collect::<Vec<_>>()
            }),
            "sensors[0].layout.radius",
        ),
    ];
    for (i, (layout, field)) in cases.into_iter().enumerate() {
        let mut v = base.clone();
        v["sensors"][0]["layout"] = layout;
        let spec = dir.join(format!("bad-{i}.spec.json"));
        fs::write(&spec, v.to_string()).unwrap();
        let e = fails_with(
            &run(&["import", "csv", s(&csv), "--spec", s(&spec), "-o", s(&out)]),
            &[s(&spec), field],
        );
        assert!(!e.contains(s(&csv)), "the CSV is not at fault: {e}");
    }

    let spec = dir.join("bom.spec.json");
    fs::write(&spec, format!("\u{feff}{text}")).unwrap();
    ok(&run(&[
        "import",
        "csv",
        s(&csv),
        "--spec",
        s(&spec),
        "-o",
        s(&out),
    ]));
    let model = dir.join("bom-model.json");
    let m = fs::read_to_string(model_seed("raw-svm-sample.json")).unwrap();
    fs::write(&model, format!("\u{feff}{m}")).unwrap();
    let sample = common::sample("grasp-stability.json");
    ok(&run(&[
        "predict",
        s(&model),
        s(&sample),
        "-o",
        s(&dir.join("p.csv")),
    ]));
}

/// Defect 10: the temporary file a killed writer left beside an output goes with the next
/// write of that output; a running writer's stays.
#[test]
fn a_killed_writers_temporary_file_goes_with_the_next_write() {
    let dir = common::temp_dir("adv-leftover");
    let out = dir.join("part.json");
    // No process has an id above Linux's largest (2^22); process 1 always runs.
    let dead = dir.join(".part.json.4194305.tmp");
    let live = dir.join(".part.json.1.tmp");
    fs::write(&dead, vec![b'x'; 1 << 20]).unwrap();
    fs::write(&live, b"in progress").unwrap();
    let sample = common::sample("object-recognition.json");
    ok(&run(&[
        "subset",
        s(&sample),
        "--trials",
        "1",
        "-o",
        s(&out),
    ]));
    assert!(out.is_file());
    assert!(!dead.exists(), "the killed writer's file is removed");
    if Path::new("/proc/1").exists() {
        assert!(live.exists(), "a running writer's file is kept");
    }
}
