//! Researchers' own recordings: ROS 2 bags (MCAP) written by real ROS 2 writers and a
//! long-format CSV, imported with their specs (tests/fixtures/, written by
//! tests/fixtures/make_fixtures.py, which also wrote the expected values checked here);
//! every bad input gives its error, names its file and place, and writes nothing; the
//! imported sessions run the stability and recognition analyses.

mod common;
use common::TempDir;

use std::path::{Path, PathBuf};
use std::process::Command;

use serde::Deserialize;
use tactile_workbench::experiments::recognition::{RecognitionParams, run_recognition};
use tactile_workbench::experiments::stability::{
    self, Config, CvScheme, DataOptions, PipelineSettings, StabilityData, StabilityOptions,
};
use tactile_workbench::jobs::Progress;
use tactile_workbench::session::{self, Session};
use tactile_workbench::sparse::DictionaryParams;

fn fixtures() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures"))
}

fn events_bag() -> (PathBuf, PathBuf) {
    let d = fixtures().join("ros2");
    (d.join("zstd-events"), d.join("zstd-events.spec.json"))
}

fn windows_bag() -> (PathBuf, PathBuf) {
    let d = fixtures().join("ros2");
    (
        d.join("plain-windows.mcap"),
        d.join("plain-windows.spec.json"),
    )
}

fn long_csv() -> (PathBuf, PathBuf) {
    let d = fixtures().join("long");
    (d.join("grasps.csv"), d.join("grasps.spec.json"))
}

#[derive(Deserialize)]
struct Expected {
    sensors: Vec<String>,
    encoders: Vec<String>,
    objects: Vec<String>,
    frame_rate_hz: f64,
    /// Frames the alignment leaves out for lacking a message within the tolerance.
    #[serde(default)]
    left_out: usize,
    grasps: Vec<ExpectedGrasp>,
}

#[derive(Deserialize)]
struct ExpectedGrasp {
    object: String,
    labels: std::collections::BTreeMap<String, String>,
    key_frame: usize,
    frames: Vec<ExpectedFrame>,
}

#[derive(Deserialize)]
struct ExpectedFrame {
    t: f64,
    taxels: Vec<Vec<f64>>,
    encoders: Vec<f64>,
}

/// Every value of the session against what the fixture script wrote.
fn check_against_script(s: &Session, expected: &str) {
    let path = fixtures().join("expected").join(expected);
    let e: Expected = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let names: Vec<&str> = s.sensors.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(names, e.sensors);
    assert_eq!(s.encoders, e.encoders);
    assert_eq!(
        s.label_sets[s.label_set("object").unwrap()].classes,
        e.objects
    );
    assert_eq!(s.meta.frame_rate_hz, Some(e.frame_rate_hz));
    assert_eq!(s.grasps.len(), e.grasps.len());
    let mut values = 0;
    for (g, (got, want)) in s.grasps.iter().zip(&e.grasps).enumerate() {
        assert_eq!(got.object, want.object, "grasp {g}");
        assert_eq!(got.key_frame, want.key_frame, "grasp {g}: key frame");
        for (set, class) in &want.labels {
            let l = s.label_set(set).unwrap();
            assert_eq!(
                &s.label_sets[l].classes[got.labels[l]], class,
                "grasp {g}: {set}"
            );
        }
        assert_eq!(got.frames.len(), want.frames.len(), "grasp {g}: frames");
        for (f, (a, b)) in got.frames.iter().zip(&want.frames).enumerate() {
            assert_eq!(a.t, b.t, "grasp {g} frame {f}: t");
            assert_eq!(a.taxels, b.taxels, "grasp {g} frame {f}: taxels");
            assert_eq!(a.encoders, b.encoders, "grasp {g} frame {f}: encoders");
            values += a.taxels.iter().map(Vec::len).sum::<usize>() + a.encoders.len();
        }
    }
    assert!(values > 500, "only {values} values checked");
    if e.left_out > 0 {
        let note = format!("{} frames were left out", e.left_out);
        assert!(
            s.meta.notes.contains(&note),
            "no `{note}` in: {}",
            s.meta.notes
        );
    } else {
        assert!(!s.meta.notes.contains("left out"), "{}", s.meta.notes);
    }
}

fn import(pair: &(PathBuf, PathBuf)) -> Result<Session, String> {
    session::import_with_spec(&pair.0, &pair.1).map_err(|e| e.to_string())
}

#[test]
fn zstd_split_bag_cut_by_events_matches_the_script() {
    let s = import(&events_bag()).unwrap();
    check_against_script(&s, "zstd-events.json");
    assert_eq!(s.meta.name, "Two fingers, grasps cut by events");
    // The source is named without a machine's path.
    assert_eq!(
        s.meta.source,
        "ROS 2 bag zstd-events, imported with the spec zstd-events.spec.json"
    );
    assert_eq!(s.label_sets[0].name, "object");
    assert_eq!(s.sensors[0].range, Some([0.0, 4095.0]));
}

#[test]
fn uncompressed_bag_cut_by_windows_matches_the_script() {
    let s = import(&windows_bag()).unwrap();
    check_against_script(&s, "plain-windows.json");
    // The spec placed `object` itself, with its own class order.
    assert_eq!(s.label_sets[0].classes, ["ball", "can"]);
    assert_eq!(s.label_sets[1].name, "outcome");
}

fn aligned_bag(name: &str) -> (PathBuf, PathBuf) {
    let d = fixtures().join("ros2");
    (d.join(name), d.join(format!("{name}.spec.json")))
}

/// A bag written by rosbags whose joint states are stamped 1 ms after the tactile frames and
/// a second sensor 1 ms before, cut by windows whose last one ends 15 ms after the bag's
/// last message: every frame is imported, each with the joint values and palm readings
/// nearest in time (the fixture script computed them), and the clipped window is noted.
#[test]
fn topics_offset_by_one_ms_and_a_window_past_the_bag_import_every_frame() {
    let s = import(&aligned_bag("offset-joints")).unwrap();
    check_against_script(&s, "offset-joints.json");
    // Every frame of the 300 ms windows at 100 Hz, the last window up to the bag's end.
    let frames: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    assert_eq!(frames, [31, 31, 31, 31, 30]);
    // The first frame of each grasp has the joint message 1 ms after it: joint `wrist` is
    // the message's index (k / 1024) at 100 Hz, so frame k of the bag has (k + 0) / 1024.
    for (g, grasp) in s.grasps.iter().enumerate() {
        let k = 10 + 50 * g;
        assert_eq!(grasp.frames[0].encoders[0], k as f64 / 1024.0, "grasp {g}");
    }
    assert!(
        s.meta
            .notes
            .contains("1 window was clipped to the bag's span"),
        "{}",
        s.meta.notes
    );
}

/// A second sensor at half the reference's rate (2 ms after every other frame) reaches only
/// those frames within the default tolerance of 5 ms, and joints that stop in the middle of
/// the third grasp leave its later frames without a value: such frames are left out and
/// counted, never given a held value.
#[test]
fn a_topic_at_half_the_rate_and_one_that_stops_leave_frames_out() {
    let s = import(&aligned_bag("gaps")).unwrap();
    check_against_script(&s, "gaps.json");
    let frames: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    assert_eq!(frames, [16, 16, 8]);
    assert!(s.meta.notes.contains("within 5 ms"), "{}", s.meta.notes);
    assert!(
        s.meta.notes.contains("`/hand/palm` in 45")
            && s.meta.notes.contains("`/joint_states` in 16"),
        "{}",
        s.meta.notes
    );
    // A tolerance of 10 ms in the spec: the palm reaches every frame, and the third grasp
    // keeps the frames up to 10 ms after the joints' last message (at 1.241 s).
    let s = import(&aligned_bag("gaps-10ms")).unwrap();
    check_against_script(&s, "gaps-10ms.json");
    let frames: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    assert_eq!(frames, [31, 31, 16]);
}

#[test]
fn long_csv_matches_the_script() {
    let s = import(&long_csv()).unwrap();
    check_against_script(&s, "long-grasps.json");
    assert_eq!(
        s.meta.source,
        "long-format CSV grasps.csv, imported with the spec grasps.spec.json"
    );
}

#[test]
fn imported_sessions_round_trip_through_the_native_format() {
    let dir = common::temp_dir("import-roundtrip");
    for (i, pair) in [events_bag(), windows_bag(), long_csv()].iter().enumerate() {
        let s = import(pair).unwrap();
        let p = dir.join(format!("s{i}.json"));
        session::save(&s, &p).unwrap();
        assert_eq!(session::load(&p).unwrap(), s);
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn imported_sessions_run_stability_and_recognition() {
    for pair in [events_bag(), windows_bag(), long_csv()] {
        let s = import(&pair).unwrap();
        let data = StabilityData::from_session(&s, &DataOptions::default()).unwrap();
        assert_eq!(data.grasp_count(), s.grasps.len());
        let opts = StabilityOptions {
            settings: PipelineSettings {
                dictionary: DictionaryParams {
                    max_iter: 20,
                    ..Default::default()
                },
                ..Default::default()
            },
            selection_cv: CvScheme::KFold { k: 2 },
            kfold: CvScheme::KFold { k: 2 },
            objects: CvScheme::LeaveObjectsOut { folds: None },
            grid: None,
            nested: Vec::new(),
            size_reason: None,
            single: Config {
                num_bases: 4,
                beta: 1.0,
                gamma: 1.0,
            },
        };
        let report = stability::run(&data, &opts, &Progress::new()).unwrap();
        let wsr = report.best.kfold.weighted_success_rate;
        assert!((0.0..=1.0).contains(&wsr), "{}: {wsr}", s.meta.name);

        let params = RecognitionParams {
            reps: 2,
            trial_sets: 2,
            ..Default::default()
        };
        let r = run_recognition(&s, &params, &Progress::new()).unwrap();
        assert_eq!(
            r.classes,
            s.label_sets[s.label_set("object").unwrap()].classes
        );
        assert!(r.summary.all.mean.is_finite(), "{}", s.meta.name);
    }
}

// ---------------------------------------------------------------------------------------
// Bad input: each gives its error, naming the file and the topic or line.
// ---------------------------------------------------------------------------------------

/// A scratch copy of a fixture with its spec rewritten by `edit` (JSON text replacement).
/// The spec owns the scratch folder: dropping it removes the copy.
fn with_spec(pair: &(PathBuf, PathBuf), tag: &str, edit: impl Fn(String) -> String) -> TempDir {
    let dir = common::temp_dir(tag);
    let text = std::fs::read_to_string(&pair.1).unwrap();
    let edited = edit(text.clone());
    assert_ne!(edited, text, "the edit changed nothing");
    std::fs::write(dir.join("spec.json"), edited).unwrap();
    // A windows CSV is found beside the spec.
    let windows = pair.1.with_file_name("plain-windows.windows.csv");
    if text.contains("plain-windows.windows.csv") {
        std::fs::copy(&windows, dir.join("plain-windows.windows.csv")).unwrap();
    }
    dir.child("spec.json")
}

fn error_of(bag: &Path, spec: &Path) -> String {
    match session::import_with_spec(bag, spec) {
        Ok(_) => panic!("{} imported without error", bag.display()),
        Err(e) => e.to_string(),
    }
}

fn assert_has(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "expected `{p}` in: {e}");
    }
}

#[test]
fn truncated_bag() {
    let (bag, spec) = windows_bag();
    let bytes = std::fs::read(&bag).unwrap();
    let dir = common::temp_dir("truncated-bag");
    let cut = dir.join("cut.mcap");
    for n in [bytes.len() / 2, bytes.len() - 10] {
        std::fs::write(&cut, &bytes[..n]).unwrap();
        let e = error_of(&cut, &spec);
        assert_has(&e, &[&cut.display().to_string(), "truncated"]);
    }
    std::fs::write(&cut, b"not a bag at all").unwrap();
    assert_has(&error_of(&cut, &spec), &["not an MCAP file"]);
    // A damaged chunk on which the MCAP library panics (found by fuzzing).
    let damaged = fixtures().join("ros2/bad/damaged-chunk.mcap");
    assert_has(
        &error_of(&damaged, &events_bag().1),
        &["damaged-chunk.mcap: the bag is damaged"],
    );
    // Fuzzing found a bag on which the MCAP library asks for a 116 TB buffer, an abort. It
    // has no end magic, which the library checks last; with it, its records are read.
    let fuzzed = fixtures().join("ros2/bad/fuzzed-huge-buffer.mcap");
    let e = error_of(&fuzzed, &events_bag().1);
    assert_has(&e, &["fuzzed-huge-buffer.mcap: the bag is truncated"]);
    let mut bytes = std::fs::read(&fuzzed).unwrap();
    bytes.extend_from_slice(b"\x89MCAP0\r\n");
    let ended = dir.join("fuzzed-huge-buffer.mcap");
    std::fs::write(&ended, &bytes).unwrap();
    assert_has(
        &error_of(&ended, &events_bag().1),
        &["fuzzed-huge-buffer.mcap: the bag is damaged"],
    );
}

/// The first zstd chunk of the split bag's first file, as (record start, body start).
fn first_chunk(bytes: &[u8]) -> (usize, usize) {
    // Records after the 8 magic bytes: opcode (1 byte), length (u64), body.
    let mut at = 8;
    loop {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if bytes[at] == 0x06 {
            return (at, at + 9);
        }
        at += 9 + len;
    }
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
}

/// Sizes a damaged bag claims are not trusted: the MCAP library reserves them before
/// decompressing, so without the importer's own reading of chunks the process aborts (or
/// the library panics).
#[test]
fn chunk_claiming_an_impossible_size() {
    let first = events_bag().0.join("zstd-events_0.mcap");
    let bytes = std::fs::read(&first).unwrap();
    let (_, body) = first_chunk(&bytes);
    let dir = common::temp_dir("huge-chunk");

    // The chunk's uncompressed size (after its start and end times) raised to 2⁶⁰ bytes.
    let mut huge = bytes.clone();
    huge[body + 16..body + 24].copy_from_slice(&(1u64 << 60).to_le_bytes());
    let bag = dir.join("huge-chunk.mcap");
    std::fs::write(&bag, &huge).unwrap();
    assert_has(
        &error_of(&bag, &events_bag().1),
        &[
            "huge-chunk.mcap: the bag is damaged: a zstd chunk of",
            "claims 1152921504606846976 bytes uncompressed but holds",
        ],
    );

    // The first record inside the chunk claims 2⁴⁵ bytes, the chunk itself intact: the
    // chunk is recompressed and its sizes and CRC kept consistent.
    let compression_len = u32::from_le_bytes(bytes[body + 28..body + 32].try_into().unwrap());
    let sizes = body + 32 + compression_len as usize;
    let data_start = sizes + 8;
    let data_end = data_start + u64_at(&bytes, sizes) as usize;
    let mut records = zstd::decode_all(&bytes[data_start..data_end]).unwrap();
    assert_eq!(records.len() as u64, u64_at(&bytes, body + 16));
    records[1..9].copy_from_slice(&(1u64 << 45).to_le_bytes());
    let data = zstd::encode_all(&records[..], 3).unwrap();
    let mut inner = bytes[..sizes].to_vec();
    inner.extend_from_slice(&(data.len() as u64).to_le_bytes());
    inner.extend_from_slice(&data);
    inner.extend_from_slice(&bytes[data_end..]);
    let chunk_len = u64_at(&bytes, body - 8) - (data_end - data_start) as u64 + data.len() as u64;
    inner[body - 8..body].copy_from_slice(&chunk_len.to_le_bytes());
    // A CRC of 0 means none was computed.
    inner[body + 24..body + 28].copy_from_slice(&0u32.to_le_bytes());
    let bag = dir.join("huge-record.mcap");
    std::fs::write(&bag, &inner).unwrap();
    assert_has(
        &error_of(&bag, &events_bag().1),
        &["huge-record.mcap: the bag is damaged", "35184372088832"],
    );

    // In the uncompressed bag's chunk, the first schema's name claims 2.4 GB (fuzzing found
    // the library reserving such a string before reading it).
    let (bag, spec) = windows_bag();
    let mut plain = std::fs::read(&bag).unwrap();
    let (_, body) = first_chunk(&plain);
    assert_eq!(
        &plain[body + 28..body + 32],
        &0u32.to_le_bytes(),
        "uncompressed"
    );
    let mut at = body + 32 + 8;
    while plain[at] != 0x03 {
        at += 9 + u64_at(&plain, at + 1) as usize;
    }
    // After the opcode and length: the schema id (u16), then the name's length.
    plain[at + 11..at + 15].copy_from_slice(&2_400_000_000u32.to_le_bytes());
    let bag = dir.join("huge-string.mcap");
    std::fs::write(&bag, &plain).unwrap();
    assert_has(
        &error_of(&bag, &spec),
        &["huge-string.mcap: the bag is damaged: a string or data does not fit in its record"],
    );
}

#[test]
fn unknown_message_type() {
    let pair = events_bag();
    let spec = with_spec(&pair, "unknown-type", |t| {
        t.replace("\"/hand/thumb/tactile\"", "\"/hand/temperature\"")
    });
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &[
            "zstd-events_0.mcap",
            "topic `/hand/temperature`",
            "sensor_msgs/msg/Temperature",
            "Float32MultiArray",
        ],
    );
}

#[test]
fn spec_topic_not_in_the_bag() {
    let pair = events_bag();
    let spec = with_spec(&pair, "missing-topic", |t| {
        t.replace("\"/joint_states\"", "\"/arm/joint_states\"")
    });
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &[
            "zstd-events: topic `/arm/joint_states`",
            "not in the bag",
            "/joint_states (sensor_msgs/msg/JointState)",
        ],
    );
}

#[test]
fn multiarray_length_does_not_match_the_layout() {
    let pair = events_bag();
    let spec = with_spec(&pair, "wrong-length", |t| t.replace("grid 4x6", "grid 4x5"));
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &[
            "zstd-events_0.mcap: topic `/hand/thumb/tactile`, message at 1700000000.007000000 s",
            "holds 24 values",
            "`thumb` (20 taxels at 0..20)",
        ],
    );
    // Two sensors side by side: the slices must cover the array exactly.
    let pair = windows_bag();
    let spec = with_spec(&pair, "wrong-slices", |t| {
        t.replace("[12, 24]", "[10, 22]")
            .replace("[0, 12]", "[0, 10]")
            .replace("grid 3x4", "grid 2x5")
    });
    let e = error_of(&pair.0, &spec);
    assert_has(&e, &["topic `/tactile`", "holds 24 values", "read 22"]);
}

/// The windows fixture with its windows CSV replaced.
/// The spec copy owns the scratch folder.
fn with_windows(tag: &str, csv: &str) -> (PathBuf, TempDir, PathBuf) {
    let (bag, spec) = windows_bag();
    let dir = common::temp_dir(tag);
    let text = std::fs::read_to_string(&spec).unwrap();
    std::fs::write(dir.join("spec.json"), text).unwrap();
    let windows = dir.join("plain-windows.windows.csv");
    std::fs::write(&windows, csv).unwrap();
    (bag, dir.child("spec.json"), windows)
}

#[test]
fn windows_that_overlap() {
    let (bag, spec, windows) = with_windows(
        "overlap",
        "start,end,object,outcome\n1700000000.2,1700000000.5,can,success\n\
         1700000001.0,1700000001.2,ball,failure\n1700000000.4,1700000000.6,can,failure\n",
    );
    let e = error_of(&bag, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:4:", windows.display()),
            "overlaps the one of line 2",
        ],
    );
}

#[test]
fn windows_outside_the_bag() {
    // The bag spans 1700000000.000–1700000003.375 s: the second window lies wholly after.
    let (bag, spec, windows) = with_windows(
        "outside",
        "start,end,object,outcome\n1700000000.2,1700000000.5,can,success\n\
         1700000004.0,1700000005.0,ball,failure\n",
    );
    let e = error_of(&bag, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:3:", windows.display()),
            "falls outside the bag, which spans 1700000000.000000000–",
            "holds no frame",
        ],
    );
    // Windows reaching past either end of the bag are clipped to it, and noted.
    let (bag, spec, _) = with_windows(
        "clipped",
        "start,end,object,outcome\n1699999999.5,1700000000.2,can,success\n\
         1700000003.0,1700000004.0,ball,failure\n",
    );
    let s = session::import_with_spec(&bag, &spec).unwrap();
    assert!(
        s.meta.notes.contains("2 windows were clipped"),
        "{}",
        s.meta.notes
    );
    // Frames every 25 ms from the bag's start, 0–200 ms and 3000–3375 ms.
    let frames: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    assert_eq!(frames, [9, 16]);
    assert_eq!(s.grasps[0].frames[0].t, 0.0);
    let (bag, spec, windows) = with_windows(
        "backwards-window",
        "start,end,object,outcome\n1700000000.5,1700000000.2,can,success\n",
    );
    let e = error_of(&bag, &spec);
    assert_has(&e, &[&format!("{}:2:", windows.display()), "ends"]);
}

#[test]
fn time_going_backwards() {
    let (_, spec) = windows_bag();
    let bag = fixtures().join("ros2/bad/time-backwards.mcap");
    let e = error_of(&bag, &spec);
    assert_has(
        &e,
        &[
            "time-backwards.mcap: topic `/tactile`, message at 1700000000.025000000 s",
            "time goes backwards: the previous message was at 1700000000.050000000 s",
        ],
    );
    let (csv, spec) = long_csv();
    let text = std::fs::read_to_string(&csv)
        .unwrap()
        .replacen("g1,0.5625,", "g1,0.25,", 1);
    let dir = common::temp_dir("csv-backwards");
    let bad = dir.join("grasps.csv");
    std::fs::write(&bad, text).unwrap();
    let e = error_of(&bad, &spec);
    assert_has(
        &e,
        &[&format!("{}:3: field `time`", bad.display()), "backwards"],
    );
}

#[test]
fn non_finite_values() {
    let (_, spec) = windows_bag();
    let bag = fixtures().join("ros2/bad/nan.mcap");
    let e = error_of(&bag, &spec);
    assert_has(
        &e,
        &[
            "nan.mcap: topic `/tactile`, message at 1700000000.100000000 s",
            "value 14 is NaN",
        ],
    );
    let (csv, spec) = long_csv();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut fields: Vec<&str> = lines[4].split(',').collect();
    fields[7] = "inf";
    lines[4] = fields.join(",");
    let dir = common::temp_dir("csv-inf");
    let bad = dir.join("grasps.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let e = error_of(&bad, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:5: field `ff_3`", bad.display()),
            "not a finite number",
        ],
    );
}

#[test]
fn readings_outside_the_range_name_the_value() {
    let pair = events_bag();
    let spec = with_spec(&pair, "range-bag", |t| t.replace("[0, 1000]", "[0, 100]"));
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &["topic `/hand/thumb/tactile`", "outside its range 0–100"],
    );
    let pair = long_csv();
    let spec = with_spec(&pair, "range-csv", |t| t.replacen("[0, 100]", "[0, 10]", 1));
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &[
            "grasps.csv:2: field `ff_1`",
            "reading 11 is outside sensor `ff`'s range 0–10",
        ],
    );
}

#[test]
fn bad_events() {
    // The events bag read with `end` events that carry too few labels for the spec.
    let pair = events_bag();
    let spec = with_spec(&pair, "events-labels", |t| {
        t.replace(
            "\"label_sets\": [",
            "\"label_sets\": [{\"name\": \"weight\", \"classes\": [\"light\"]}, ",
        )
    });
    let e = error_of(&pair.0, &spec);
    assert_has(
        &e,
        &[
            "zstd-events: topic `/grasp_events`, message at 1700000000.445000000 s",
            "gives 1 labels",
        ],
    );
}

#[test]
fn bad_specs_name_the_field() {
    let pair = events_bag();
    let cases: [(&str, &str, &str); 4] = [
        (
            "grid 4x6",
            "grid 4by6",
            "`sensors[1].layout`: `grid 4by6` is not a layout",
        ),
        (
            "\"unit\": \"raw\"",
            "\"unit\": \"raw\", \"colour\": 1",
            "unknown field `colour`",
        ),
        (
            "\"events\": \"/grasp_events\"",
            "\"events\": \"/e\", \"windows\": \"w.csv\"",
            "`grasps`: give exactly one",
        ),
        ("[0, 4095]", "[4095, 0]", "`sensors[0].range`"),
    ];
    for (i, (from, to, want)) in cases.iter().enumerate() {
        let spec = with_spec(&pair, &format!("spec-{i}"), |t| t.replace(from, to));
        let e = error_of(&pair.0, &spec);
        assert_has(&e, &[&spec.display().to_string(), want]);
    }
}

#[test]
fn a_failed_import_writes_nothing() {
    let dir = common::temp_dir("cli-import");
    let out = dir.join("session.json");
    let (_, spec) = windows_bag();
    let bad = fixtures().join("ros2/bad/nan.mcap");
    let run = |bag: &Path, spec: &Path| {
        Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .args(["import", "mcap"])
            .arg(bag)
            .arg("-o")
            .arg(&out)
            .arg("--spec")
            .arg(spec)
            .output()
            .unwrap()
    };
    let r = run(&bad, &spec);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("not a finite number"));
    assert!(!out.exists());
    let (bag, spec) = windows_bag();
    let r = run(&bag, &spec);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(
        session::load(&out).unwrap(),
        import(&windows_bag()).unwrap()
    );
    let (csv, spec) = long_csv();
    let out_csv = dir.join("long.json");
    let r = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args(["import", "csv"])
        .arg(&csv)
        .arg("-o")
        .arg(&out_csv)
        .arg("--spec")
        .arg(&spec)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(session::load(&out_csv).is_ok());
    let _ = std::fs::remove_dir_all(dir);
}

/// A long CSV naming a column twice is refused, naming both columns: found by name, the
/// second would otherwise be silently ignored.
#[test]
fn a_long_csv_naming_a_column_twice() {
    let (csv, spec) = long_csv();
    let text = std::fs::read_to_string(&csv).unwrap();
    let dir = common::temp_dir("long-duplicate");
    let twice = dir.join("twice.csv");
    // A 20th column, `ff_3` again (column 8), with its own values.
    let rows: Vec<String> = text.lines().map(|l| format!("{l},99")).collect();
    let header = format!("{},ff_3", text.lines().next().unwrap());
    std::fs::write(&twice, format!("{header}\n{}\n", rows[1..].join("\n"))).unwrap();
    let e = error_of(&twice, &spec);
    assert_has(
        &e,
        &[
            &format!("{}:1:", twice.display()),
            "columns 8 and 20 are both named `ff_3`",
        ],
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// An events topic declared in the bag that carries no message is reported as empty, not
/// as missing.
#[test]
fn an_empty_events_topic_is_reported_as_empty() {
    let bag = fixtures().join("ros2/bad/empty-events");
    let e = error_of(&bag, &events_bag().1);
    assert_has(
        &e,
        &[
            "topic `/grasp_events`",
            "the spec's events topic is in the bag but holds no messages",
        ],
    );
    assert!(!e.contains("not in the bag"), "{e}");
}

/// `import … -o` naming the bag, one of its files, the spec or the windows CSV is refused
/// before anything is read or written, naming both paths; the input is left intact.
#[test]
fn an_output_that_is_an_input_is_refused() {
    let dir = common::temp_dir("output-is-input");
    let (bag, spec) = windows_bag();
    let copy = dir.join("rec.mcap");
    std::fs::copy(&bag, &copy).unwrap();
    let spec_copy = dir.join("rec.spec.json");
    std::fs::copy(&spec, &spec_copy).unwrap();
    let windows = dir.join("plain-windows.windows.csv");
    std::fs::copy(spec.with_file_name("plain-windows.windows.csv"), &windows).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let same_bag = dir.join(".").join("rec.mcap");
    for output in [&same_bag, &spec_copy, &windows] {
        let r = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
            .args(["import", "mcap"])
            .arg(&copy)
            .arg("-o")
            .arg(output)
            .arg("--spec")
            .arg(&spec_copy)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{err}");
        assert!(
            err.contains(&format!("the output {} is the input", output.display())),
            "{err}"
        );
    }
    assert_eq!(std::fs::read(&copy).unwrap(), before, "the bag is intact");
    // The same for a command with `--json`: the session is its input.
    let session = dir.join("s.json");
    let s = import(&windows_bag()).unwrap();
    session::save(&s, &session).unwrap();
    let saved = std::fs::read(&session).unwrap();
    let r = Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .arg("stability")
        .arg(&session)
        .arg("--json")
        .arg(&session)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success() && err.contains("is the input"), "{err}");
    assert_eq!(std::fs::read(&session).unwrap(), saved);
    let _ = std::fs::remove_dir_all(dir);
}

/// The windows fixture's messages rewritten with zstd chunks, with camera images in a chunk
/// of their own between two tactile chunks (as large images fill chunks alone in real bags);
/// then the camera chunk, or else the last tactile chunk, damaged at the start of its
/// compressed records (the zstd magic number), so that decompressing it must fail.
fn bag_with_a_damaged_chunk(path: &Path, damage_camera: bool) {
    use std::collections::BTreeMap;
    let original = std::fs::read(windows_bag().0).unwrap();
    let messages: Vec<mcap::Message> = mcap::MessageStream::new(&original)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    let half = messages.len() / 2;
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(None)
        .create(file)
        .unwrap();
    for m in &messages[..half] {
        w.write(m).unwrap();
    }
    w.flush().unwrap();
    let schema = w
        .add_schema(
            "sensor_msgs/msg/Image",
            "ros2msg",
            b"uint32 height\nuint32 width",
        )
        .unwrap();
    let camera = w
        .add_channel(schema, "/camera/image_raw", "cdr", &BTreeMap::new())
        .unwrap();
    let t = messages[half - 1].log_time;
    for i in 0..5u32 {
        let header = mcap::records::MessageHeader {
            channel_id: camera,
            sequence: i,
            log_time: t + u64::from(i),
            publish_time: t + u64::from(i),
        };
        w.write_to_known_channel(&header, &[i as u8; 4096]).unwrap();
    }
    w.flush().unwrap();
    for m in &messages[half..] {
        w.write(m).unwrap();
    }
    w.finish().unwrap();
    drop(w);
    let mut bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let chunks = &summary.chunk_indexes;
    assert_eq!(chunks.len(), 3, "tactile, camera, tactile");
    let has_camera = |c: &mcap::records::ChunkIndex| c.message_index_offsets.contains_key(&camera);
    assert!(has_camera(&chunks[1]) && chunks[1].message_index_offsets.len() == 1);
    let target = if damage_camera {
        &chunks[1]
    } else {
        &chunks[2]
    };
    // Opcode, record length, start and end time, uncompressed size, CRC, "zstd" with its
    // length, the records' length: then the zstd frame, whose magic number is overwritten.
    let records = (target.chunk_start_offset + 1 + 8 + 8 + 8 + 8 + 4 + 4 + 4 + 8) as usize;
    assert_eq!(&bytes[records..records + 4], &[0x28, 0xb5, 0x2f, 0xfd]);
    bytes[records..records + 4].copy_from_slice(b"XXXX");
    std::fs::write(path, bytes).unwrap();
}

/// The importer reads only the chunks that hold one of the spec's channels (the summary's
/// message indexes say which): a damaged camera chunk it never decompresses does not stop
/// the import, which gives exactly the original bag's session, while the same damage in a
/// tactile chunk is reported.
#[test]
fn chunks_without_the_specs_channels_are_never_read() {
    let dir = common::temp_dir("skipped-chunk");
    let (_, spec) = windows_bag();
    let camera = dir.join("camera-damaged.mcap");
    bag_with_a_damaged_chunk(&camera, true);
    let s = session::import_with_spec(&camera, &spec).unwrap();
    let original = import(&windows_bag()).unwrap();
    assert_eq!(s.grasps, original.grasps);
    let tactile = dir.join("tactile-damaged.mcap");
    bag_with_a_damaged_chunk(&tactile, false);
    let e = error_of(&tactile, &spec);
    assert_has(&e, &[&tactile.display().to_string(), "damaged"]);
    // The decompressor's own error is kept as the source, and said in the message.
    let err = session::import_with_spec(&tactile, &spec).expect_err("a damaged chunk");
    let source = std::error::Error::source(&err)
        .unwrap_or_else(|| panic!("the decompressor's error is kept: {err:?}"));
    assert!(
        source.downcast_ref::<std::io::Error>().is_some(),
        "{source:?}"
    );
    assert_has(&e, &[&source.to_string()]);
    let _ = std::fs::remove_dir_all(dir);
}
