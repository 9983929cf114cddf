//! Per-grasp features of the second paper's Table I, for the partial-online and offline
//! baselines (iSVM, SVM, C4.5, sequential k-means, SOM), and their normalisation.
//!
//! For every finger (sensor) f, the per-step statistics over its taxel pressures
//! (`FingerStats`: mean, sd, skewness) form three time series over the grasp. Then:
//! - features 1–75: for each series (mean, then sd, then skewness), for each finger, the
//!   series' first three moments over time (mean, population sd, skewness), its maximum and
//!   its minimum: 3 series × 5 fingers × 5 = 75 on the iCub;
//! - features 76–165: for each finger, all encoders at the time step of the finger's
//!   maximum tactile reading, then at the step of its minimum: 5 fingers × 2 × 9 = 90.
//!
//! Reading of "encoder data during maximum and minimum tactile readings": a finger's
//! tactile reading at a step is its mean pressure over its taxels (the first per-step
//! feature of the paper and the finger's overall contact level); the steps are the argmax
//! and argmin over time of that mean, the earliest step on ties. The per-taxel maximum
//! would follow a single taxel's noise; the mean follows the finger's contact.
//!
//! The layout generalises to any session with S sensors and E encoders: 15 S + 2 S E values.

use ndarray::Array2;

use super::{FeatureError, FingerStats};
use crate::session::Session;

const SERIES: [&str; 3] = ["mean", "sd", "skewness"];

/// Number of Table I features of a session (165 on the iCub).
pub fn feature_count(session: &Session) -> usize {
    let (s, e) = (session.sensors.len(), session.encoders.len());
    15 * s + 2 * s * e
}

/// Names of the features, in order, e.g. "mean/thumb/skewness", "encoders@max/index/3".
pub fn feature_names(session: &Session) -> Vec<String> {
    let mut names = Vec::with_capacity(feature_count(session));
    for series in SERIES {
        for sensor in &session.sensors {
            for stat in FingerStats::NAMES {
                names.push(format!("{series}/{}/{stat}", sensor.name));
            }
        }
    }
    for sensor in &session.sensors {
        for at in ["max", "min"] {
            for enc in &session.encoders {
                names.push(format!("encoders@{at}/{}/{enc}", sensor.name));
            }
        }
    }
    names
}

/// The Table I features of grasp `g`.
pub fn grasp_row(session: &Session, g: usize) -> Result<Vec<f64>, FeatureError> {
    let grasp = session
        .grasps
        .get(g)
        .ok_or_else(|| FeatureError::InvalidData(format!("no grasp {g}")))?;
    if grasp.frames.is_empty() {
        return Err(FeatureError::InvalidData(format!(
            "grasp {g} has no frames"
        )));
    }
    let n_enc = session.encoders.len();
    for (t, frame) in grasp.frames.iter().enumerate() {
        if frame.taxels.len() != session.sensors.len() || frame.encoders.len() != n_enc {
            return Err(FeatureError::InvalidData(format!(
                "grasp {g}, frame {t}: {} sensors and {} encoders, the session has {} and {n_enc}",
                frame.taxels.len(),
                frame.encoders.len(),
                session.sensors.len()
            )));
        }
    }
    // per sensor, per step: the finger's statistics over its taxels
    let per_step: Vec<Vec<FingerStats>> = (0..session.sensors.len())
        .map(|s| {
            grasp
                .frames
                .iter()
                .map(|f| FingerStats::of(&session.frame_pressures(f, s)))
                .collect()
        })
        .collect();
    let mut out = Vec::with_capacity(feature_count(session));
    for series in 0..SERIES.len() {
        for steps in &per_step {
            let values: Vec<f64> = steps
                .iter()
                .map(|st| [st.mean, st.sd, st.skewness][series])
                .collect();
            out.extend(FingerStats::of(&values).to_array());
        }
    }
    for steps in &per_step {
        let (mut t_max, mut t_min) = (0, 0);
        for (t, st) in steps.iter().enumerate() {
            if st.mean > steps[t_max].mean {
                t_max = t;
            }
            if st.mean < steps[t_min].mean {
                t_min = t;
            }
        }
        out.extend_from_slice(&grasp.frames[t_max].encoders);
        out.extend_from_slice(&grasp.frames[t_min].encoders);
    }
    if let Some(i) = out.iter().position(|v| !v.is_finite()) {
        return Err(FeatureError::InvalidData(format!(
            "grasp {g}: feature {i} is not finite"
        )));
    }
    Ok(out)
}

/// The Table I features of every grasp: grasps × features.
pub fn session_features(session: &Session) -> Result<Array2<f64>, FeatureError> {
    let width = feature_count(session);
    let mut data = Array2::zeros((session.grasps.len(), width));
    for g in 0..session.grasps.len() {
        let row = grasp_row(session, g)?;
        data.row_mut(g).assign(&ndarray::ArrayView1::from(&row));
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{Normalisation, Normaliser};
    use crate::session::{Frame, Grasp, LabelSet, Layout, Sensor, SessionMeta, ValueTransform};

    /// Two fingers of three taxels, two encoders, raw = 10 − pressure.
    fn tiny_session() -> Session {
        let sensor = |name: &str| Sensor {
            name: name.into(),
            layout: Layout::Grid { rows: 1, cols: 3 },
            unit: "raw".into(),
            transform: ValueTransform::Reversed { offset: 10.0 },
            range: None,
        };
        let frame = |t: f64, a: [f64; 3], b: [f64; 3], enc: [f64; 2]| Frame {
            t,
            taxels: vec![a.map(|p| 10.0 - p).to_vec(), b.map(|p| 10.0 - p).to_vec()],
            encoders: enc.to_vec(),
        };
        Session {
            meta: SessionMeta::default(),
            sensors: vec![sensor("a"), sensor("b")],
            encoders: vec!["e0".into(), "e1".into()],
            label_sets: vec![LabelSet {
                name: "object".into(),
                classes: vec!["x".into()],
            }],
            grasps: vec![Grasp {
                object: "x".into(),
                trial: Some(1),
                labels: vec![0],
                frames: vec![
                    // finger a means 1, 3, 2; finger b means 5, 4, 6
                    frame(0.0, [1.0, 1.0, 1.0], [5.0, 5.0, 5.0], [10.0, 20.0]),
                    frame(0.1, [0.0, 3.0, 6.0], [4.0, 4.0, 4.0], [11.0, 21.0]),
                    frame(0.2, [2.0, 2.0, 2.0], [3.0, 6.0, 9.0], [12.0, 22.0]),
                ],
                key_frame: 2,
            }],
        }
    }

    #[test]
    fn table_one_layout_by_hand() {
        let s = tiny_session();
        assert_eq!(feature_count(&s), 15 * 2 + 2 * 2 * 2);
        let f = grasp_row(&s, 0).unwrap();
        assert_eq!(f.len(), 38);
        assert_eq!(feature_names(&s).len(), 38);
        // mean series of finger a: 1, 3, 2 → mean 2, sd √(2/3), skewness 0, max 3, min 1
        let want_a = FingerStats::of(&[1.0, 3.0, 2.0]).to_array();
        assert_eq!(&f[0..5], &want_a);
        assert!((f[0] - 2.0).abs() < 1e-15 && (f[1] - (2.0f64 / 3.0).sqrt()).abs() < 1e-15);
        // mean series of finger b: 5, 4, 6
        assert_eq!(&f[5..10], &FingerStats::of(&[5.0, 4.0, 6.0]).to_array());
        // sd series of finger a: 0, √6, 0
        assert_eq!(
            &f[10..15],
            &FingerStats::of(&[0.0, 6f64.sqrt(), 0.0]).to_array()
        );
        // skewness series: finger b's last frame 3, 6, 9 is symmetric → all zero
        assert_eq!(&f[25..30], &[0.0; 5]);
        // finger a: max mean at step 1, min at step 0; finger b: max at 2, min at 1
        assert_eq!(
            &f[30..38],
            &[11.0, 21.0, 10.0, 20.0, 12.0, 22.0, 11.0, 21.0]
        );
        assert_eq!(feature_names(&s)[30], "encoders@max/a/e0");
        assert_eq!(feature_names(&s)[10], "sd/a/mean");
    }

    #[test]
    fn malformed_grasps_are_errors() {
        let mut s = tiny_session();
        s.grasps[0].frames[1].encoders.pop();
        assert!(grasp_row(&s, 0).is_err());
        let mut s = tiny_session();
        s.grasps[0].frames.clear();
        assert!(session_features(&s).is_err());
        assert!(grasp_row(&tiny_session(), 3).is_err());
    }

    #[test]
    fn normalisers() {
        let data =
            Array2::from_shape_vec((4, 2), vec![1.0, 5.0, 2.0, 5.0, 3.0, 5.0, 6.0, 5.0]).unwrap();
        let z = Normaliser::fit(Normalisation::ZScore, data.view()).unwrap();
        let t = z.transform(data.view()).unwrap();
        let col: Vec<f64> = t.column(0).to_vec();
        let mean = col.iter().sum::<f64>() / 4.0;
        let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 4.0;
        assert!(mean.abs() < 1e-15 && (var - 1.0).abs() < 1e-14);
        assert!(t.column(1).iter().all(|&v| v == 0.0));
        let m = Normaliser::fit(Normalisation::MinMax, data.view()).unwrap();
        let t = m.transform(data.view()).unwrap();
        assert_eq!(t.column(0).to_vec(), vec![0.0, 0.2, 0.4, 1.0]);
        assert!(m.transform(Array2::zeros((1, 3)).view()).is_err());
    }

    /// On the iCub dataset: 200 grasps × 165 finite features.
    #[test]
    fn icub_table_one_features() {
        let Some(dir) = crate::test_datasets::dataset("icub-grasp") else {
            return;
        };
        let session = crate::session::import_icub(&dir).unwrap();
        let data = session_features(&session).unwrap();
        assert_eq!(data.dim(), (200, 165));
        // the tactile moments vary across grasps
        let z = Normaliser::fit(Normalisation::ZScore, data.view()).unwrap();
        let live = z.scale.iter().filter(|&&s| s > 0.0).count();
        assert!(live > 150, "{live} non-constant features");
    }
}
