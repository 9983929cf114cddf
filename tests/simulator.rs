//! The sample sessions: deterministic per seed, byte for byte equal to the committed files,
//! with the documented label balance and failure signature.

mod common;

use tactile_workbench::session::{self, native, simulate};

#[test]
fn committed_samples_are_regenerated_byte_for_byte() {
    let stability = native::to_string(&simulate::grasp_stability(1));
    let committed = std::fs::read_to_string(common::sample("grasp-stability.json")).unwrap();
    assert!(
        stability == committed,
        "grasp-stability.json differs from `simulate --seed 1`"
    );
    let recognition = native::to_string(&simulate::object_recognition(1));
    let committed = std::fs::read_to_string(common::sample("object-recognition.json")).unwrap();
    assert!(
        recognition == committed,
        "object-recognition.json differs from `simulate --seed 1`"
    );
}

#[test]
fn same_seed_same_session_other_seed_other_session() {
    assert_eq!(simulate::grasp_stability(5), simulate::grasp_stability(5));
    assert_ne!(simulate::grasp_stability(5), simulate::grasp_stability(6));
    assert_ne!(
        simulate::object_recognition(5),
        simulate::object_recognition(6)
    );
}

#[test]
fn stability_sample_has_the_documented_balance_and_failure_signature() {
    for seed in [1, 2, 3] {
        let s = simulate::grasp_stability(seed);
        session::validate(&s, std::path::Path::new("simulated")).unwrap();
        assert_eq!(s.grasps.len(), 540);
        assert_eq!(s.objects().len(), 54);
        let failures = s.grasps.iter().filter(|g| g.labels[0] == 1).count();
        let share = failures as f64 / 540.0;
        assert!((0.23..=0.27).contains(&share), "failure share {share}");
        // Failed grasps: fewer active taxels at full contact (the paper's observation).
        let active = |label: usize| -> f64 {
            let gs: Vec<usize> = (0..s.grasps.len())
                .filter(|&i| s.grasps[i].labels[0] == label)
                .collect();
            let n: usize = gs
                .iter()
                .map(|&i| {
                    s.key_patches(i)
                        .concat()
                        .iter()
                        .filter(|&&v| v > 5.0)
                        .count()
                })
                .sum();
            n as f64 / gs.len() as f64
        };
        assert!(
            active(1) < 0.8 * active(0),
            "seed {seed}: {} vs {}",
            active(1),
            active(0)
        );
    }
}

#[test]
fn recognition_sample_is_shaped_like_the_icub_data() {
    let s = simulate::object_recognition(1);
    session::validate(&s, std::path::Path::new("simulated")).unwrap();
    assert_eq!(s.grasps.len(), 200);
    assert_eq!(s.label_sets[0].classes.len(), 10);
    assert_eq!(s.encoders.len(), 9);
    assert!(s.sensors.iter().all(|x| x.layout.taxel_count() == 12));
    for g in &s.grasps {
        assert!((4..=22).contains(&g.frames.len()));
        assert!(
            g.frames
                .iter()
                .flat_map(|f| f.taxels.concat())
                .all(|v| (0.0..=255.0).contains(&v))
        );
    }
}
