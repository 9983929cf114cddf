//! The importers on the real datasets: counts, exact values against the raw files, and
//! the round trip import → save → load.

mod common;

use tactile_workbench::session::{self, ValueTransform};

#[test]
fn icub_dataset_imports_the_papers_200_grasps() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    let s = session::import_icub(&dir).expect("import");
    assert_eq!(s.grasps.len(), 200);
    assert_eq!(s.label_sets[0].classes.len(), 10);
    assert!(!s.label_sets[0].classes.iter().any(|c| c == "full_coke"));
    for c in 0..10 {
        assert_eq!(s.grasps.iter().filter(|g| g.labels[0] == c).count(), 20);
    }
    assert_eq!(s.sensors.len(), 5);
    assert_eq!(s.encoders.len(), 9);
    let lengths: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    assert_eq!(*lengths.iter().min().unwrap(), 4);
    assert_eq!(*lengths.iter().max().unwrap(), 22);
    assert!(s.meta.licence.contains("Copyright 2012 Harold Soh"));
    // The source names the folder, not where it lies on this machine.
    assert_eq!(
        s.meta.source,
        "iCub grasp dataset (Soh & Demiris), imported from icub-grasp"
    );
    assert_eq!(s.sensors[0].range, Some([0.0, 255.0]));
    // blue_bear_1.txt, first time step: encoder 0 is 20.7273, thumb taxel 0 reads 242.
    let g = s
        .grasps
        .iter()
        .find(|g| g.object == "blue_bear" && g.trial == Some(1))
        .unwrap();
    assert_eq!(g.frames[0].encoders[0], 20.7273);
    assert_eq!(g.frames[0].encoders[8], 2.00816);
    assert_eq!(g.frames[0].taxels[0][0], 242.0);
    assert_eq!(g.frames[0].taxels[4][11], 245.0);
    assert_eq!(s.frame_pressures(&g.frames[0], 0)[0], 13.0);
    assert!((g.frames[1].t - 0.1).abs() < 1e-12);
}

#[test]
fn icub_full_coke_only_on_request() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    let opts = session::icub::IcubOptions {
        include_full_coke: true,
    };
    let s = session::import_icub_with(&dir, &opts).expect("import");
    assert_eq!(s.grasps.len(), 220);
    assert_eq!(s.label_sets[0].classes.last().unwrap(), "full_coke");
}

#[test]
fn bts3_imports_1276_grasps_on_41_objects() {
    let Some(csv) = common::dataset("bts3/biotac-palmdown-grasps.csv") else {
        return;
    };
    let s = session::import_bts3(&csv).expect("import");
    assert_eq!(s.grasps.len(), 1276);
    assert_eq!(s.objects().len(), 41);
    assert_eq!(s.grasps.iter().filter(|g| g.labels[0] == 1).count(), 609);
    assert_eq!(s.sensors.len(), 3);
    assert!(s.sensors.iter().all(|x| x.layout.taxel_count() == 24));
    // First data row: pringles, slipped 0, ff_biotac_1 = 2795, ff_biotac_2 = 3097.
    let g = &s.grasps[0];
    assert_eq!(g.object, "pringles");
    assert_eq!(g.labels[0], 0);
    assert_eq!(g.frames.len(), 1);
    assert_eq!(g.frames[0].taxels[0][0], 2795.0);
    assert_eq!(g.frames[0].taxels[0][1], 3097.0);
    // Pressure = per-electrode session maximum − reading: never negative, zero somewhere.
    let ValueTransform::BaselineMinus { baseline } = &s.sensors[0].transform else {
        panic!("BTS3 uses a baseline transform")
    };
    assert_eq!(baseline.len(), 24);
    let p: Vec<f64> = (0..s.grasps.len())
        .flat_map(|i| s.key_patches(i).concat())
        .collect();
    assert!(p.iter().all(|&v| v >= 0.0));
    assert!(p.contains(&0.0));
}

#[test]
fn a_bts3_file_is_named_after_the_file_not_the_palm_down_set() {
    let Some(csv) = common::dataset("bts3/biotac-palmdown-grasps.csv") else {
        return;
    };
    let s = session::import_bts3(&csv).expect("import");
    assert_eq!(
        s.meta.name,
        "BioTac SP grasp stability (biotac-palmdown-grasps)"
    );
    assert_eq!(
        s.meta.source,
        "BTS3 BioTac SP grasps, imported from biotac-palmdown-grasps.csv"
    );
    // The palm-side file of the same set, here the first grasps under that name.
    let dir = common::temp_dir("bts3-name");
    let side = dir.join("biotac-palmside-grasps.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let head: Vec<&str> = text.lines().take(6).collect();
    std::fs::write(&side, head.join("\n")).unwrap();
    let s = session::import_bts3(&side).expect("import");
    assert_eq!(
        s.meta.name,
        "BioTac SP grasp stability (biotac-palmside-grasps)"
    );
    assert!(!s.meta.name.contains("palm down") && !s.meta.notes.contains("palm"));
    assert!(!s.meta.source.contains(&*dir.to_string_lossy()));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn real_sessions_round_trip_exactly() {
    let dir = common::temp_dir("roundtrip");
    let mut sessions = Vec::new();
    if let Some(d) = common::dataset("icub-grasp") {
        sessions.push(session::import_icub(&d).unwrap());
    }
    if let Some(c) = common::dataset("bts3/biotac-palmdown-grasps.csv") {
        sessions.push(session::import_bts3(&c).unwrap());
    }
    for (i, s) in sessions.iter().enumerate() {
        let p = dir.join(format!("s{i}.json"));
        session::save(s, &p).unwrap();
        let back = session::load(&p).unwrap();
        assert_eq!(&back, s);
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Which real datasets this run has, on the terminal whatever the outcome: where one is
/// absent every test that needs it skips (and says so); under CI this test fails instead.
#[test]
fn real_datasets_found() {
    use std::io::Write;
    let found: Vec<String> = ["icub-grasp", "bts3/biotac-palmdown-grasps.csv"]
        .into_iter()
        .map(|rel| match common::dataset(rel) {
            Some(_) => format!("{rel} found"),
            None => format!("{rel} ABSENT, its tests skipped"),
        })
        .collect();
    let _ = writeln!(
        std::io::stderr(),
        "real datasets in {}: {}",
        common::datasets_dir().display(),
        found.join(", ")
    );
}
