//! Perturbations of a session and the robustness sweep: each perturbation does exactly what
//! it says, seeds reproduce, bad strengths are refused by name, break points interpolate,
//! and on the sample sessions strong faults lower the score.

use std::path::Path;

use tactile_workbench::catalogue::MethodId;
use tactile_workbench::experiments::ExperimentError;
use tactile_workbench::experiments::recognition::{
    RecognitionParams, SupervisedLearner, run_recognition,
};
use tactile_workbench::experiments::robustness::report::robustness_report;
use tactile_workbench::experiments::robustness::{
    Family, Perturbation, RobustnessParams, Sweep, break_point, run_robustness,
};
use tactile_workbench::features::FeatureSet;
use tactile_workbench::jobs::Progress;
use tactile_workbench::perturb::{
    PerturbError, PerturbParams, PerturbationKind, Stuck, perturb, raw_ranges,
};
use tactile_workbench::rng::Rng;
use tactile_workbench::session::{
    Frame, Grasp, LabelSet, Layout, Sensor, Session, SessionMeta, ValueTransform,
};

/// Two iCub-like fingers (12 taxels, 0–255, pressure = 255 − reading) and, optionally, a
/// third sensor on a 0–1020 scale (4 × the iCub's), readings mid-range.
fn session(grasps: usize, frames: usize, wide: bool) -> Session {
    let mut sensors: Vec<Sensor> = ["thumb", "index"]
        .iter()
        .map(|n| Sensor {
            name: n.to_string(),
            layout: Layout::Grid { rows: 3, cols: 4 },
            unit: "raw capacitance (0–255, falls under pressure)".into(),
            transform: ValueTransform::Reversed { offset: 255.0 },
            range: None,
        })
        .collect();
    if wide {
        sensors.push(Sensor {
            name: "wide".into(),
            layout: Layout::Grid { rows: 3, cols: 4 },
            unit: "counts (0–1020)".into(),
            transform: ValueTransform::BaselineMinus {
                baseline: vec![900.0; 12],
            },
            range: None,
        });
    }
    let mut rng = Rng::new(7);
    let n_s = sensors.len();
    let grasps = (0..grasps)
        .map(|g| Grasp {
            object: format!("o{}", g % 4),
            trial: None,
            labels: vec![g % 2],
            frames: (0..frames)
                .map(|t| Frame {
                    t: 0.1 * t as f64,
                    taxels: (0..n_s)
                        .map(|s| {
                            let scale = if s == 2 { 4.0 } else { 1.0 };
                            (0..12).map(|_| scale * rng.range(100.0, 150.0)).collect()
                        })
                        .collect(),
                    encoders: Vec::new(),
                })
                .collect(),
            key_frame: frames / 2,
        })
        .collect();
    Session {
        meta: SessionMeta::default(),
        sensors,
        encoders: Vec::new(),
        label_sets: vec![LabelSet {
            name: "outcome".into(),
            classes: vec!["success".into(), "failure".into()],
        }],
        grasps,
    }
}

fn run(s: &Session, kind: PerturbationKind, strength: f64, seed: u64) -> Session {
    perturb(s, &PerturbParams::new(kind, strength, seed)).unwrap()
}

fn pressures(s: &Session, g: usize, f: usize, sensor: usize) -> Vec<f64> {
    s.frame_pressures(&s.grasps[g].frames[f], sensor)
}

#[test]
fn noise_has_the_asked_variance_relative_to_full_scale() {
    let s = session(40, 30, true);
    let p = run(&s, PerturbationKind::Noise, 100.0, 3);
    // Per sensor: the variance of the added noise.
    for (sensor, want) in [(0, 100.0), (1, 100.0), (2, 100.0 * 16.0)] {
        let mut sum = 0.0;
        let mut sum2 = 0.0;
        let mut n = 0.0;
        for (a, b) in s.grasps.iter().zip(&p.grasps) {
            for (fa, fb) in a.frames.iter().zip(&b.frames) {
                for (x, y) in fa.taxels[sensor].iter().zip(&fb.taxels[sensor]) {
                    let d = y - x;
                    sum += d;
                    sum2 += d * d;
                    n += 1.0;
                }
            }
        }
        let mean = sum / n;
        let var = sum2 / n - mean * mean;
        assert!(
            (var / want - 1.0).abs() < 0.05,
            "sensor {sensor}: variance {var}, want {want}"
        );
        assert!(mean.abs() < 0.05 * want.sqrt(), "noise mean {mean}");
    }
}

#[test]
fn saturation_clamps_to_the_raw_range_only_when_asked() {
    let s = session(10, 20, false);
    let loud = PerturbParams::new(PerturbationKind::Noise, 1e5, 1);
    let clamped = perturb(&s, &loud).unwrap();
    let free = perturb(
        &s,
        &PerturbParams {
            saturate: false,
            ..loud
        },
    )
    .unwrap();
    let all = |x: &Session| -> Vec<f64> {
        x.grasps
            .iter()
            .flat_map(|g| &g.frames)
            .flat_map(|f| f.taxels.iter().flatten().copied())
            .collect()
    };
    assert!(all(&clamped).iter().all(|v| (0.0..=255.0).contains(v)));
    assert!(all(&clamped).contains(&255.0) && all(&clamped).contains(&0.0));
    assert!(all(&free).iter().any(|v| !(0.0..=255.0).contains(v)));
    let r = raw_ranges(&s).unwrap();
    assert_eq!((r[0].lo, r[0].hi), (0.0, 255.0));
}

#[test]
fn dead_taxels_are_an_exact_nested_share() {
    let s = session(6, 4, false);
    let stuck_taxels = |x: &Session, value: f64| -> Vec<(usize, usize)> {
        (0..2)
            .flat_map(|sn| (0..12).map(move |t| (sn, t)))
            .filter(|&(sn, t)| {
                x.grasps.iter().all(|g| {
                    g.frames
                        .iter()
                        .all(|f| x.pressure(sn, t, f.taxels[sn][t]) == value)
                })
            })
            .collect()
    };
    let zero = PerturbationKind::DeadTaxels { stuck: Stuck::Zero };
    let quarter = stuck_taxels(&run(&s, zero, 0.25, 9), 0.0);
    let half = stuck_taxels(&run(&s, zero, 0.5, 9), 0.0);
    assert_eq!(quarter.len(), 6);
    assert_eq!(half.len(), 12);
    assert!(quarter.iter().all(|t| half.contains(t)), "not nested");
    // Stuck at full scale: pressure 255 (reading 0).
    let max = stuck_taxels(
        &run(
            &s,
            PerturbationKind::DeadTaxels { stuck: Stuck::Max },
            0.25,
            9,
        ),
        255.0,
    );
    assert_eq!(max.len(), 6);
    // The others are untouched.
    let p = run(&s, zero, 0.25, 9);
    let untouched = (0..2)
        .flat_map(|sn| (0..12).map(move |t| (sn, t)))
        .filter(|k| !quarter.contains(k))
        .all(|(sn, t)| p.grasps[0].frames[0].taxels[sn][t] == s.grasps[0].frames[0].taxels[sn][t]);
    assert!(untouched);
}

#[test]
fn a_dead_sensor_is_one_whole_sensor() {
    let s = session(5, 3, true);
    let p = run(
        &s,
        PerturbationKind::DeadSensor { stuck: Stuck::Zero },
        1.0,
        4,
    );
    let dead: Vec<usize> = (0..3)
        .filter(|&sn| (0..5).all(|g| pressures(&p, g, 1, sn).iter().all(|v| *v == 0.0)))
        .collect();
    assert_eq!(dead.len(), 1);
    for sn in (0..3).filter(|s| !dead.contains(s)) {
        assert_eq!(
            p.grasps[2].frames[1].taxels[sn],
            s.grasps[2].frames[1].taxels[sn]
        );
    }
    let err = perturb(
        &s,
        &PerturbParams::new(PerturbationKind::DeadSensor { stuck: Stuck::Zero }, 4.0, 0),
    )
    .unwrap_err();
    assert!(err.to_string().contains("strength"), "{err}");
}

#[test]
fn drift_grows_linearly_over_the_session() {
    let s = session(11, 2, true);
    let p = run(&s, PerturbationKind::Drift, 0.1, 0);
    for (sensor, width) in [(0, 255.0), (2, 1020.0)] {
        let mut last = -1.0;
        for g in 0..11 {
            let d: Vec<f64> = pressures(&p, g, 0, sensor)
                .iter()
                .zip(pressures(&s, g, 0, sensor))
                .map(|(a, b)| a - b)
                .collect();
            let want = 0.1 * width * g as f64 / 10.0;
            assert!(
                d.iter().all(|x| (x - want).abs() < 1e-9),
                "grasp {g}: {d:?}"
            );
            assert!(want > last);
            last = want;
        }
    }
}

#[test]
fn gain_multiplies_pressures_exactly() {
    let s = session(3, 2, true);
    let p = run(&s, PerturbationKind::Gain, 1.5, 0);
    for sn in 0..3 {
        for (a, b) in pressures(&s, 1, 1, sn).iter().zip(pressures(&p, 1, 1, sn)) {
            assert!((1.5 * a - b).abs() < 1e-9, "{a} → {b}");
        }
    }
}

#[test]
fn truncation_and_missing_frames_keep_the_asked_frames() {
    let s = session(4, 20, false);
    let t = run(&s, PerturbationKind::Truncation, 0.33, 0);
    for (a, b) in s.grasps.iter().zip(&t.grasps) {
        assert_eq!(b.frames.len(), 7); // ⌈0.33 · 20⌉
        assert_eq!(b.frames[..], a.frames[..7]);
        assert!(b.key_frame < b.frames.len());
    }
    let tiny = run(&s, PerturbationKind::Truncation, 0.01, 0);
    assert!(tiny.grasps.iter().all(|g| g.frames.len() == 1));
    let m = run(&s, PerturbationKind::MissingFrames, 0.25, 5);
    for (a, b) in s.grasps.iter().zip(&m.grasps) {
        assert_eq!(b.frames.len(), 15);
        assert!(b.frames.iter().all(|f| a.frames.contains(f)));
        assert!(b.frames.windows(2).all(|w| w[0].t < w[1].t));
        assert!(b.key_frame < b.frames.len());
    }
}

#[test]
fn seeds_reproduce_and_differ() {
    let s = session(5, 5, false);
    for kind in [
        PerturbationKind::Noise,
        PerturbationKind::DeadTaxels { stuck: Stuck::Zero },
        PerturbationKind::MissingFrames,
    ] {
        let strength = if kind == PerturbationKind::Noise {
            50.0
        } else {
            0.4
        };
        assert_eq!(run(&s, kind, strength, 11), run(&s, kind, strength, 11));
        assert_ne!(run(&s, kind, strength, 11), run(&s, kind, strength, 12));
    }
    // The neutral strength changes nothing.
    for kind in [
        PerturbationKind::Gain,
        PerturbationKind::Truncation,
        PerturbationKind::Drift,
    ] {
        assert_eq!(run(&s, kind, kind.neutral(), 1), s);
    }
}

#[test]
fn bad_strengths_are_refused_by_name() {
    let s = session(2, 2, false);
    for (kind, v) in [
        (PerturbationKind::Noise, -1.0),
        (PerturbationKind::Noise, f64::NAN),
        (PerturbationKind::DeadTaxels { stuck: Stuck::Zero }, 1.5),
        (PerturbationKind::DeadSensor { stuck: Stuck::Max }, 0.5),
        (PerturbationKind::Gain, -2.0),
        (PerturbationKind::Truncation, 0.0),
        (PerturbationKind::MissingFrames, 1.0),
        (PerturbationKind::Drift, 3.0),
    ] {
        match perturb(&s, &PerturbParams::new(kind, v, 0)) {
            Err(PerturbError::InvalidParameter { name, .. }) => assert_eq!(name, "strength"),
            other => panic!("{kind:?} at {v}: {other:?}"),
        }
    }
    let param_name = |p: RobustnessParams| match p.validate() {
        Err(ExperimentError::InvalidParameter { name, .. }) => name,
        other => panic!("{other:?}"),
    };
    let base = RobustnessParams::defaults(Family::Stability);
    assert_eq!(
        param_name(RobustnessParams {
            reps: 0,
            ..base.clone()
        }),
        "reps"
    );
    assert_eq!(
        param_name(RobustnessParams {
            fraction: 1.5,
            ..base.clone()
        }),
        "fraction"
    );
    assert_eq!(
        param_name(RobustnessParams {
            methods: vec![MethodId::Gs],
            ..base.clone()
        }),
        "methods"
    );
    assert_eq!(
        param_name(RobustnessParams {
            sweeps: vec![Sweep {
                perturbation: Perturbation::FewExamples,
                strengths: vec![2.5],
            }],
            ..base.clone()
        }),
        "strengths"
    );
    assert_eq!(
        param_name(RobustnessParams {
            sweeps: vec![Sweep {
                perturbation: Perturbation::Noise,
                strengths: vec![-4.0],
            }],
            ..base
        }),
        "strength"
    );
    assert!("nosie".parse::<Perturbation>().is_err());
    // More dead sensors than the session has: refused before any work.
    let mut p = RobustnessParams::defaults(Family::Stability);
    p.sweeps = vec![Sweep {
        perturbation: Perturbation::DeadSensor,
        strengths: vec![1.0, 3.0],
    }];
    match run_robustness(&s, &p, &Progress::new()) {
        Err(ExperimentError::InvalidParameter { name, reason }) => {
            assert_eq!(name, "strengths");
            assert!(reason.contains("dead-sensor"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn break_points_interpolate_between_the_bracketing_strengths() {
    // Clean 1.0 at 0; 0.95 at 1; 0.85 at 2 → 0.9 crossed half way: 1.5.
    let b = break_point(Some(0.0), 1.0, &[(1.0, 0.95), (2.0, 0.85)], 0.9).unwrap();
    assert!((b - 1.5).abs() < 1e-12, "{b}");
    // From the clean point itself: 0 → 4 with 1.0 → 0.8 crosses at 2.
    let b = break_point(Some(0.0), 1.0, &[(4.0, 0.8)], 0.9).unwrap();
    assert!((b - 2.0).abs() < 1e-12, "{b}");
    // A decreasing sweep (share kept): 0.8 + (0.05 / 0.2) · (0.4 − 0.8) = 0.7.
    let b = break_point(Some(1.0), 1.0, &[(0.8, 0.95), (0.4, 0.75)], 0.9).unwrap();
    assert!((b - 0.7).abs() < 1e-12, "{b}");
    // Holds through the sweep.
    assert_eq!(
        break_point(Some(0.0), 1.0, &[(1.0, 0.95), (2.0, 0.91)], 0.9),
        None
    );
    // No neutral point and the first strength already below: the break is there.
    assert_eq!(
        break_point(None, 0.8, &[(0.5, 0.6), (0.1, 0.5)], 0.9),
        Some(0.5)
    );
    // A dip that recovers still breaks at the first crossing.
    let b = break_point(Some(0.0), 1.0, &[(1.0, 0.8), (2.0, 0.95)], 0.9).unwrap();
    assert!((b - 0.5).abs() < 1e-12, "{b}");
}

fn sample(name: &str) -> Option<Session> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("sample-sessions")
        .join(name);
    if !path.exists() {
        eprintln!("skipping: {} is absent", path.display());
        return None;
    }
    Some(tactile_workbench::session::load(&path).unwrap())
}

#[test]
fn stability_sweep_on_the_sample_breaks_under_strong_faults() {
    let Some(s) = sample("grasp-stability.json") else {
        return;
    };
    let mut p = RobustnessParams::defaults(Family::Stability);
    p.reps = 1;
    p.stability.folds = 5;
    p.stability.config.num_bases = 10;
    p.stability.config.beta = 0.5;
    p.sweeps = vec![
        Sweep {
            perturbation: Perturbation::Noise,
            strengths: vec![1e5],
        },
        Sweep {
            perturbation: Perturbation::DeadSensor,
            strengths: vec![2.0],
        },
        Sweep {
            perturbation: Perturbation::Imbalance,
            strengths: vec![0.05],
        },
    ];
    let r = run_robustness(&s, &p, &Progress::new()).unwrap();
    for m in [MethodId::SparseSvm, MethodId::RawSvm] {
        let clean = r.clean_score(m).unwrap();
        // docs/grasp-stability.md: 0.69–0.76 on this session.
        assert!(clean > 0.64 && clean < 0.85, "{m:?}: clean {clean}");
        let noisy = r.curve(m, Perturbation::Noise).unwrap();
        assert!(noisy.points[0].score.mean < clean - 0.05, "{noisy:?}");
        assert!(noisy.break_point.is_some());
        // Both pads dead: every test grasp looks the same, one class for all: WSR 0.5.
        let dead = r.curve(m, Perturbation::DeadSensor).unwrap();
        assert!((dead.points[0].score.mean - 0.5).abs() < 1e-9, "{dead:?}");
        assert!(dead.break_point.unwrap() > 0.0 && dead.break_point.unwrap() < 2.0);
    }
    let report = robustness_report(&r.session, &r);
    assert_eq!(report.figures.len(), 3);
    for (_, f) in &report.figures {
        f.validate().unwrap();
    }
}

#[test]
fn recognition_clean_score_is_the_protocols_and_dead_fingers_break_it() {
    let Some(s) = sample("object-recognition.json") else {
        return;
    };
    let mut p = RobustnessParams::defaults(Family::Recognition);
    p.methods = vec![MethodId::Ds];
    p.reps = 1;
    p.seed = 3;
    p.recognition.features = FeatureSet::MOMENTS;
    p.sweeps = vec![Sweep {
        perturbation: Perturbation::DeadSensor,
        strengths: vec![5.0],
    }];
    let r = run_robustness(&s, &p, &Progress::new()).unwrap();
    let direct = run_recognition(
        &s,
        &RecognitionParams {
            learner: SupervisedLearner::Ds,
            features: FeatureSet::MOMENTS,
            reps: 1,
            seed: 3,
            ..Default::default()
        },
        &Progress::new(),
    )
    .unwrap();
    let clean = r.clean_score(MethodId::Ds).unwrap();
    assert_eq!(clean, direct.summary.final_20.mean);
    assert!(clean > 0.5, "clean {clean}");
    let dead = &r
        .curve(MethodId::Ds, Perturbation::DeadSensor)
        .unwrap()
        .points[0];
    // Every finger dead: the tactile features are constant, at best one class right.
    assert!(dead.score.mean <= 0.2, "{dead:?}");
}

#[test]
fn recognition_baselines_score_the_sample_and_lose_to_noise() {
    let Some(s) = sample("object-recognition.json") else {
        return;
    };
    let mut p = RobustnessParams::defaults(Family::Recognition);
    p.methods = vec![MethodId::KMeans, MethodId::RbfSvm];
    p.reps = 1;
    p.sweeps = vec![Sweep {
        perturbation: Perturbation::Noise,
        strengths: vec![1e5],
    }];
    let r = run_robustness(&s, &p, &Progress::new()).unwrap();
    // The sample's objects separate well on the Table I features.
    let km = r.clean_score(MethodId::KMeans).unwrap();
    let svm = r.clean_score(MethodId::RbfSvm).unwrap();
    assert!(km > 0.5 && km <= 1.0, "k-means NMI {km}");
    assert!(svm > 0.8 && svm <= 1.0, "RBF SVM accuracy {svm}");
    let noisy = r.curve(MethodId::RbfSvm, Perturbation::Noise).unwrap();
    assert!(noisy.points[0].score.mean < svm - 0.1, "{noisy:?}");
}
