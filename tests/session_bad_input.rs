//! Every kind of bad input gives an error naming the file, the place and the problem,
//! and never a panic.

mod common;

use std::path::Path;

use tactile_workbench::session::{self, Location, bts3, icub, native, simulate};

fn bts3_header() -> String {
    let mut h = vec!["object".to_string(), "slipped".to_string()];
    for f in ["ff", "mf", "th"] {
        for e in 1..=24 {
            h.push(format!("{f}_biotac_{e}"));
        }
    }
    h.join(",")
}

fn bts3_row(object: &str, slipped: &str) -> Vec<String> {
    let mut r = vec![object.to_string(), slipped.to_string()];
    r.extend((0..72).map(|i| (2000 + i).to_string()));
    r
}

fn bts3_err(text: &str) -> String {
    let e = bts3::parse_bts3(text, Path::new("grasps.csv")).unwrap_err();
    assert!(e.to_string().starts_with("grasps.csv"), "{e}");
    e.to_string()
}

/// CSV headers are case-free: `Object`, `Slipped`, `FF_biotac_1` name the same columns.
#[test]
fn bts3_header_names_in_any_case() {
    let h = bts3_header()
        .replace("object", "Object")
        .replace("slipped", "SLIPPED")
        .replace("ff_biotac_1,", "FF_Biotac_1,");
    let good = bts3_row("cup", "0").join(",");
    let s = bts3::parse_bts3(&format!("{h}\n{good}\n"), Path::new("x")).unwrap();
    assert_eq!(s.grasps.len(), 1);
    assert_eq!(s.grasps[0].object, "cup");
}

#[test]
fn bts3_bad_inputs_name_the_problem() {
    let h = bts3_header();
    let good = bts3_row("cup", "0").join(",");
    assert!(bts3::parse_bts3(&format!("{h}\n{good}\n"), Path::new("x")).is_ok());

    assert!(bts3_err("").contains("empty"));
    assert!(bts3_err(&format!("{h}\n")).contains("no grasps"));
    let mut short = bts3_row("cup", "0");
    short.pop();
    let e = bts3_err(&format!("{h}\n{good}\n{}\n", short.join(",")));
    assert!(
        e.contains("grasps.csv:3") && e.contains("73 values, expected 74"),
        "{e}"
    );
    let mut nan = bts3_row("cup", "1");
    nan[5] = "NaN".into();
    let e = bts3_err(&format!("{h}\n{}\n", nan.join(",")));
    assert!(
        e.contains(":2") && e.contains("ff_biotac_4") && e.contains("not a finite number"),
        "{e}"
    );
    let mut text = bts3_row("cup", "1");
    text[40] = "abc".into();
    let e = bts3_err(&format!("{h}\n{}\n", text.join(",")));
    assert!(
        e.contains("mf_biotac_15") && e.contains("`abc` is not a number"),
        "{e}"
    );
    let e = bts3_err(&format!("{h}\n{}\n", bts3_row("cup", "2").join(",")));
    assert!(e.contains("slipped") && e.contains("not 0 or 1"), "{e}");
    let e = bts3_err(&format!("object,slipped\n{good}\n"));
    assert!(e.contains("grasps.csv:1") && e.contains("header"), "{e}");
    let e = bts3_err(&format!(
        "{}\n{good}\n",
        h.replace("mf_biotac_3", "mf_biotac_x")
    ));
    assert!(
        e.contains("mf_biotac_x") && e.contains("expected `mf_biotac_3`"),
        "{e}"
    );
    // Truncated mid-row.
    let e = bts3_err(&format!("{h}\n{}", &good[..good.len() / 2]));
    assert!(e.contains(":2") && e.contains("values, expected 74"), "{e}");
}

fn icub_step(taxel: &str) -> String {
    let enc = "1 2 3 4 5 6 7 8 9";
    let maxes = "1 1 1 1 1";
    let row = |v: &str| [v; 12].join(" ");
    format!(
        "{enc}\n{maxes}\n{}\n{}\n{}\n{}\n{}\n",
        row(taxel),
        row("240"),
        row("240"),
        row("240"),
        row("240")
    )
}

fn icub_err(text: &str) -> String {
    let e = icub::parse_trial(text, Path::new("mug_3.txt")).unwrap_err();
    assert!(e.to_string().starts_with("mug_3.txt"), "{e}");
    e.to_string()
}

#[test]
fn icub_bad_inputs_name_the_problem() {
    let ok = format!("-10000\n{}{}", icub_step("240"), icub_step("230"));
    assert_eq!(icub::parse_trial(&ok, Path::new("x")).unwrap().len(), 2);

    assert!(icub_err("").contains("empty"));
    assert!(icub_err("-10000\n").contains("no time steps"));
    // Truncated: the second step has only 3 of its 7 lines.
    let trunc: String =
        format!("-10000\n{}", icub_step("240")) + "1 2 3 4 5 6 7 8 9\n1 1 1 1 1\n240 240\n";
    let e = icub_err(&trunc);
    assert!(e.contains("truncated") && e.contains("mug_3.txt:11"), "{e}");
    // Wrong count on the thumb line (line 4).
    let bad = ok.replacen(&["240"; 12].join(" "), &["240"; 11].join(" "), 1);
    let e = icub_err(&bad);
    assert!(
        e.contains("mug_3.txt:4") && e.contains("thumb taxels: 11 values, expected 12"),
        "{e}"
    );
    let e = icub_err(&format!("-10000\n{}", icub_step("nan")));
    assert!(
        e.contains("thumb taxels[0]") && e.contains("not a finite number"),
        "{e}"
    );
    let e = icub_err(&format!("-10000\n{}", icub_step("2x4")));
    assert!(e.contains("`2x4` is not a number"), "{e}");
    let e = icub_err(&icub_step("240"));
    assert!(e.contains("mug_3.txt:1") && e.contains("header"), "{e}");
}

#[test]
fn icub_missing_folder_or_trial_is_named() {
    let e = session::import_icub(Path::new("/no/such/folder")).unwrap_err();
    assert!(e.to_string().contains("/no/such/folder") && e.to_string().contains("not a folder"));
    let dir = common::temp_dir("icub-missing");
    let e = session::import_icub(&dir).unwrap_err();
    assert!(
        e.to_string().contains("blue_bear_1.txt") && e.to_string().contains("missing trial 1"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

fn native_err(text: &str) -> session::SessionError {
    let e = native::from_str(text, Path::new("s.json")).unwrap_err();
    assert!(e.to_string().starts_with("s.json"), "{e}");
    e
}

fn small_session_text() -> String {
    let mut s = simulate::object_recognition(3);
    s.grasps.truncate(2);
    native::to_string(&s)
}

#[test]
fn native_bad_inputs_name_the_problem() {
    let good = small_session_text();
    assert!(native::from_str(&good, Path::new("s.json")).is_ok());

    assert!(native_err("").to_string().contains("empty"));
    let e = native_err(&good[..good.len() / 2]);
    assert!(e.to_string().contains("truncated"), "{e}");
    assert!(matches!(e.location, Location::LineColumn { .. }));
    let e = native_err(&good.replace("\"version\": 1", "\"version\": 7"));
    assert!(
        e.to_string().contains("unsupported format version 7"),
        "{e}"
    );
    let e = native_err("{\"version\": 1}");
    assert!(
        e.to_string().contains("format") && e.to_string().contains("missing"),
        "{e}"
    );
    let e = native_err(&good.replace("tactile-workbench-session", "something-else"));
    assert!(
        e.to_string().contains("not a tactile-workbench session"),
        "{e}"
    );
    // A value that is text where a number belongs: the line of the grasp is named.
    let bad = good.replacen("\"t\":0.0", "\"t\":\"soon\"", 1);
    let e = native_err(&bad);
    assert!(
        matches!(e.location, Location::LineColumn { line, .. } if line > 5),
        "{e}"
    );
    // Wrong count of values for a sensor.
    let mut s = simulate::object_recognition(3);
    s.grasps.truncate(2);
    s.grasps[1].frames[2].taxels[3].pop();
    let e = native_err(&native::to_string(&s));
    assert!(
        e.to_string().contains("grasps[1].frames[2].taxels[3]")
            && e.to_string().contains("expected 12 values, found 11"),
        "{e}"
    );
    // Empty session.
    let mut s = simulate::object_recognition(3);
    s.grasps.clear();
    assert!(
        native_err(&native::to_string(&s))
            .to_string()
            .contains("no grasps")
    );
    // A sensor without taxels.
    let mut s = simulate::grasp_stability(3);
    s.grasps.truncate(1);
    s.sensors[1].layout = session::Layout::Grid { rows: 0, cols: 7 };
    let e = native_err(&native::to_string(&s));
    assert!(
        e.to_string().contains("sensors[1]") && e.to_string().contains("no taxels"),
        "{e}"
    );
    // A label out of range, a key frame out of range.
    let mut s = simulate::grasp_stability(3);
    s.grasps.truncate(3);
    s.grasps[2].labels[0] = 5;
    assert!(
        native_err(&native::to_string(&s))
            .to_string()
            .contains("grasps[2].labels[0]")
    );
    let mut s = simulate::grasp_stability(3);
    s.grasps.truncate(3);
    s.grasps[0].key_frame = 99;
    assert!(
        native_err(&native::to_string(&s))
            .to_string()
            .contains("grasps[0].key_frame")
    );
    // Huge numbers overflow f64 to infinity: rejected by serde_json with a position.
    let e = native_err(&good.replacen("\"t\":0.0", "\"t\":1e999", 1));
    assert!(matches!(e.location, Location::LineColumn { .. }), "{e}");
}

#[test]
fn native_garbage_and_utf8_errors_do_not_panic() {
    let dir = common::temp_dir("garbage");
    let p = dir.join("g.json");
    std::fs::write(&p, [0xff, 0xfe, 0x00, 0x12, 0x80]).unwrap();
    let e = session::load(&p).unwrap_err();
    assert!(
        e.to_string().contains("g.json") && e.to_string().contains("UTF-8"),
        "{e}"
    );
    std::fs::write(
        &p,
        "{\"format\": \"tactile-workbench-session\", \"version\": 1, \"session\": [1,2",
    )
    .unwrap();
    assert!(session::load(&p).is_err());
    let e = session::load(&dir.join("absent.json")).unwrap_err();
    assert!(e.to_string().contains("absent.json"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn save_replaces_atomically() {
    let dir = common::temp_dir("save");
    let p = dir.join("s.json");
    let s = simulate::object_recognition(2);
    session::save(&s, &p).unwrap();
    assert_eq!(session::load(&p).unwrap(), s);
    // Saving into a folder that does not exist fails cleanly and names the path.
    let e = session::save(&s, &dir.join("nope/s.json")).unwrap_err();
    assert!(e.to_string().contains("nope/s.json"));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(dir);
}
