//! Per-step feature sequences on the real iCub data: sizes, normalisation, feature switches
//! and the raw-taxel noise of the robustness experiment.

mod common;

use tactile_workbench::features::{FeatureSet, SequenceParams, feature_sequences};
use tactile_workbench::session::import_icub;

#[test]
fn icub_sequences_have_the_papers_sizes_and_are_normalised() {
    let Some(dir) = common::dataset("icub-grasp") else {
        return;
    };
    let s = import_icub(&dir).unwrap();
    let of = |features, noise: f64, seed| {
        feature_sequences(
            &s,
            &SequenceParams {
                features,
                taxel_noise_variance: noise,
                seed,
            },
        )
        .unwrap()
    };
    let all = of(FeatureSet::ALL, 0.0, 0);
    assert_eq!(all.dim(), 34);
    assert_eq!(of(FeatureSet::MOMENTS, 0.0, 0).dim(), 25);
    assert_eq!(of(FeatureSet::ENCODERS, 0.0, 0).dim(), 9);
    assert_eq!(all.sequences.len(), 200);
    assert_eq!(all.names[9], "thumb/mean");
    for (g, m) in all.sequences.iter().enumerate() {
        assert_eq!(m.nrows(), s.grasps[g].frames.len());
        assert!(m.iter().all(|v| (0.0..=1.0).contains(v)));
    }
    // Every feature reaches both ends of its range somewhere.
    for j in 0..34 {
        let col = all.sequences.iter().flat_map(|m| m.column(j).to_vec());
        let (lo, hi) = col.fold((1.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        assert!(lo == 0.0 && hi == 1.0, "feature {j}: {lo}..{hi}");
    }
    // The thumb's raw mean pressure is 255 − reading, averaged over its 12 taxels.
    let f0 = &s.grasps[0].frames[0];
    let mean: f64 = f0.taxels[0].iter().map(|r| 255.0 - r).sum::<f64>() / 12.0;
    let norm = (mean - all.min[9]) / (all.max[9] - all.min[9]);
    assert!((all.sequences[0][[0, 9]] - norm).abs() < 1e-12);
    // Noise on the raw taxels moves the tactile features only, reproducibly.
    let noisy = of(FeatureSet::ALL, 100.0, 7);
    let again = of(FeatureSet::ALL, 100.0, 7);
    assert_eq!(noisy, again);
    let raw_enc = |fs: &tactile_workbench::features::FeatureSequences| {
        fs.sequences[3][[2, 4]] * (fs.max[4] - fs.min[4]) + fs.min[4]
    };
    assert!((raw_enc(&noisy) - raw_enc(&all)).abs() < 1e-9);
    assert!((noisy.sequences[3][[2, 9]] - all.sequences[3][[2, 9]]).abs() > 1e-6);
    assert!(
        feature_sequences(
            &s,
            &SequenceParams {
                taxel_noise_variance: -1.0,
                ..SequenceParams::default()
            }
        )
        .unwrap_err()
        .to_string()
        .contains("taxel_noise_variance")
    );
}
