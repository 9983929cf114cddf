//! Per-time-step feature sequences of the second paper (Sec. V-C) and the researcher's own
//! inputs. A feature set is a combination of families, in this column order:
//!
//! - `encoders`: the joint encoders (9 on the iCub);
//! - `moments`: for every finger the mean, sd, skewness, max and min of its taxel pressures
//!   (5 × 5 = 25 on the iCub) — the paper's "tactile" features;
//! - `raw`: every taxel's pressure (where on the finger the contact is, which the moments lose);
//! - `change`: every taxel's pressure minus its pressure at the grasp's first frame;
//! - `codes`: the first paper's sparse codes of every frame, one complete dictionary per
//!   sensor learned on the session's frames without labels (`super::codes`).
//!
//! `all` is the paper's 34 (encoders then moments) where the session has encoders and the
//! moments alone where it has none; `FeatureSequences::families` says which it used.
//! `auto` asks for a family chosen from the data by cross validation on the training
//! session (`crate::experiments::feature_choice`): it is replaced by the chosen family
//! before any sequence is built.
//!
//! Every column is min-max normalised to [0, 1] over every frame of every grasp of the
//! session, as the paper normalises its dataset (the OIESGP lengthscales start at 1 on that
//! scale). For `raw` this is also what z-scoring each taxel over the session would give:
//! min-max is invariant to a per-column affine change, so z-scoring first would change no
//! bit of meaning, only rounding, and is not done. Optional Gaussian noise on the raw taxel
//! readings reproduces the paper's robustness experiment (Fig. 8: variances 100 and 1000
//! on the 0–255 readings) and reaches every tactile family; readings are not clipped after
//! the noise, as the paper does not say they were.
//!
//! This file declares the inputs (families, feature sets, parameters, the sequences);
//! `build` assembles the sequences of a session.

mod build;

use std::fmt;
use std::str::FromStr;

use ndarray::Array2;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub use build::{feature_sequences, feature_sequences_in};

use super::FingerStats;
use super::codes::FrameCodes;
use crate::session::Session;

/// One family of per-step inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    Encoders,
    Moments,
    Raw,
    Change,
    Codes,
}

impl Family {
    /// Every family, in the column order of the sequences.
    pub const COLUMN_ORDER: [Family; 5] = [
        Family::Encoders,
        Family::Moments,
        Family::Raw,
        Family::Change,
        Family::Codes,
    ];
    /// The order of a set's name: tactile families first, as in `raw+encoders`.
    const NAME_ORDER: [Family; 5] = [
        Family::Moments,
        Family::Raw,
        Family::Change,
        Family::Codes,
        Family::Encoders,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Family::Encoders => "encoders",
            Family::Moments => "moments",
            Family::Raw => "raw",
            Family::Change => "change",
            Family::Codes => "codes",
        }
    }

    fn bit(self) -> u8 {
        match self {
            Family::Encoders => 1,
            Family::Moments => 2,
            Family::Raw => 4,
            Family::Change => 8,
            Family::Codes => 16,
        }
    }

    fn parse(s: &str) -> Option<Family> {
        match s {
            "encoders" | "encoder" => Some(Family::Encoders),
            "moments" | "tactile" => Some(Family::Moments),
            "raw" => Some(Family::Raw),
            "change" => Some(Family::Change),
            "codes" => Some(Family::Codes),
            _ => None,
        }
    }

    fn uses_taxels(self) -> bool {
        self != Family::Encoders
    }
}

/// The inputs of the OIESGP experiments: `all` (the paper's families the session has),
/// `auto` (a family chosen from the data) or an explicit combination of families. Saved as
/// its name (`"all"`, `"auto"`, `"moments"`, `"raw+encoders"`); the older names
/// `"tactile"` and `"encoder"` still load.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FeatureSet {
    /// Bits of `Family::bit`; `ALL_BIT` alone for `all`, `AUTO_BIT` alone for `auto`.
    bits: u8,
}

const ALL_BIT: u8 = 0x80;
const AUTO_BIT: u8 = 0x40;

impl FeatureSet {
    /// The paper's families the session has: encoders and moments (34 on the iCub), or the
    /// moments alone on a session without encoders.
    pub const ALL: FeatureSet = FeatureSet { bits: ALL_BIT };
    /// A family chosen by cross validation on the training session (the sequence methods'
    /// default on the command line and in the window).
    pub const AUTO: FeatureSet = FeatureSet { bits: AUTO_BIT };
    /// The paper's tactile features (25 on the iCub).
    pub const MOMENTS: FeatureSet = FeatureSet { bits: 2 };
    /// The paper's encoder features (9 on the iCub).
    pub const ENCODERS: FeatureSet = FeatureSet { bits: 1 };
    pub const RAW: FeatureSet = FeatureSet { bits: 4 };
    pub const CHANGE: FeatureSet = FeatureSet { bits: 8 };
    /// The first paper's sparse codes of every frame.
    pub const CODES: FeatureSet = FeatureSet { bits: 16 };
    /// The sets the window offers and the paper's figures know by name.
    pub const OFFERED: [FeatureSet; 9] = [
        FeatureSet::ALL,
        FeatureSet::MOMENTS,
        FeatureSet::ENCODERS,
        FeatureSet::RAW,
        FeatureSet::CHANGE,
        FeatureSet { bits: 4 | 1 },
        FeatureSet { bits: 8 | 1 },
        FeatureSet::CODES,
        FeatureSet { bits: 16 | 1 },
    ];

    /// The set of exactly these families (empty: none).
    pub fn of(families: &[Family]) -> FeatureSet {
        FeatureSet {
            bits: families.iter().fold(0, |b, f| b | f.bit()),
        }
    }

    pub fn is_all(self) -> bool {
        self.bits == ALL_BIT
    }

    pub fn is_auto(self) -> bool {
        self.bits == AUTO_BIT
    }

    /// The explicit families, in column order (empty for `all` and `auto`, which depend on
    /// the session).
    pub fn families(self) -> Vec<Family> {
        Family::COLUMN_ORDER
            .into_iter()
            .filter(|f| self.bits & f.bit() != 0)
            .collect()
    }

    /// What `self` means on `session`: `all` becomes the paper's families it has.
    pub fn resolve(self, session: &Session) -> FeatureSet {
        if !self.is_all() {
            return self;
        }
        if session.encoders.is_empty() {
            FeatureSet::MOMENTS
        } else {
            FeatureSet::of(&[Family::Encoders, Family::Moments])
        }
    }

    /// The number of columns on `session`, or None where it lacks a family.
    pub fn dim(self, session: &Session) -> Option<usize> {
        let sensors = session.sensors.len();
        self.resolve(session)
            .families()
            .into_iter()
            .map(|f| match f {
                Family::Encoders => session.encoders.len(),
                Family::Moments => FingerStats::NAMES.len() * sensors,
                Family::Raw | Family::Change | Family::Codes => session.taxel_count(),
            })
            .try_fold(0, |sum, d| (d > 0).then_some(sum + d))
            .filter(|&d| d > 0)
    }

    /// `all`, `auto` or the families joined by `+` (tactile first: `raw+encoders`).
    pub fn name(self) -> String {
        if self.is_all() {
            return "all".into();
        }
        if self.is_auto() {
            return "auto".into();
        }
        Family::NAME_ORDER
            .into_iter()
            .filter(|f| self.bits & f.bit() != 0)
            .map(Family::name)
            .collect::<Vec<_>>()
            .join("+")
    }
}

impl Default for FeatureSet {
    fn default() -> Self {
        FeatureSet::ALL
    }
}

impl fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl FromStr for FeatureSet {
    type Err = SequenceError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |reason: String| SequenceError::Parameter {
            name: "features",
            reason,
        };
        match s.trim() {
            "all" => return Ok(FeatureSet::ALL),
            "auto" => return Ok(FeatureSet::AUTO),
            _ => {}
        }
        let mut set = FeatureSet { bits: 0 };
        for part in s.split('+').map(str::trim) {
            let f = Family::parse(part).ok_or_else(|| {
                bad(format!(
                    "`{part}` is not all, auto or a family: moments (or tactile), encoders (or \
                     encoder), raw, change, codes; combine families with +, e.g. raw+encoders"
                ))
            })?;
            set.bits |= f.bit();
        }
        Ok(set)
    }
}

impl Serialize for FeatureSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl<'de> Deserialize<'de> for FeatureSet {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SequenceError {
    #[error("invalid parameter `{name}`: {reason}")]
    Parameter { name: &'static str, reason: String },
    #[error("session cannot give {set} features: {reason}")]
    Session { set: String, reason: String },
    /// The codes' dictionaries that could not be learned (the sparse coder's error kept).
    #[error("session cannot give {set} features: learning the codes' dictionaries: {source}")]
    LearnCodes {
        set: String,
        #[source]
        source: crate::sparse::SparseError,
    },
    /// A grasp's frames that do not take the shape of its sensors' taxels.
    #[error("session cannot give {set} features: grasp {grasp}: {source}")]
    Shape {
        set: String,
        grasp: usize,
        #[source]
        source: ndarray::ShapeError,
    },
    /// A grasp's frames the codes' dictionaries cannot code (the sparse coder's error kept).
    #[error("session cannot give {set} features: grasp {grasp}: {source}")]
    Codes {
        set: String,
        grasp: usize,
        #[source]
        source: crate::sparse::SparseError,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceParams {
    pub features: FeatureSet,
    /// Variance of Gaussian noise added to each raw taxel reading (0: none).
    pub taxel_noise_variance: f64,
    /// Seed of that noise (grasp g uses stream g).
    pub seed: u64,
}

impl Default for SequenceParams {
    fn default() -> Self {
        SequenceParams {
            features: FeatureSet::ALL,
            taxel_noise_variance: 0.0,
            seed: 0,
        }
    }
}

impl SequenceParams {
    pub fn validate(&self) -> Result<(), SequenceError> {
        if !(self.taxel_noise_variance.is_finite() && self.taxel_noise_variance >= 0.0) {
            return Err(SequenceError::Parameter {
                name: "taxel_noise_variance",
                reason: "must be finite and non-negative".into(),
            });
        }
        if self.features.is_auto() {
            return Err(SequenceError::Parameter {
                name: "features",
                reason: "auto is replaced by the family cross validation chooses before \
                         sequences are built"
                    .into(),
            });
        }
        if self.features.families().is_empty() && !self.features.is_all() {
            return Err(SequenceError::Parameter {
                name: "features",
                reason: "names no family".into(),
            });
        }
        Ok(())
    }
}

/// One normalised T × D matrix per grasp (rows are time steps), in session order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeatureSequences {
    pub names: Vec<String>,
    /// The families the columns hold (`all` resolved on the session).
    pub families: FeatureSet,
    pub sequences: Vec<Array2<f64>>,
    /// Raw range of each feature before normalisation.
    pub min: Vec<f64>,
    pub max: Vec<f64>,
    /// The dictionaries of the `codes` family (None without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub codes: Option<FrameCodes>,
}

impl FeatureSequences {
    pub fn dim(&self) -> usize {
        self.names.len()
    }
}

/// Where the min-max range of each feature comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SequenceRange<'a> {
    /// Every frame of every grasp of the session (the paper's normalisation).
    Session,
    /// Every frame of these grasps of the session (a model reading a new session by the
    /// statistics of its first grasps).
    Grasps(std::ops::Range<usize>),
    /// A range known already (a model's training range).
    Given { min: &'a [f64], max: &'a [f64] },
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::simulate;

    /// A small recognition session: 3 objects × 20 grasps of 8–18 frames, 5 fingertips of
    /// 12 taxels, 9 encoders.
    fn session() -> Session {
        let mut s = simulate::object_recognition(3);
        s.grasps.truncate(60);
        s
    }

    fn of(s: &Session, features: FeatureSet, noise: f64) -> FeatureSequences {
        feature_sequences(
            s,
            &SequenceParams {
                features,
                taxel_noise_variance: noise,
                seed: 5,
            },
        )
        .unwrap()
    }

    /// Column `j` of every frame, back in the units before min-max.
    fn unnormalised(f: &FeatureSequences, g: usize, t: usize, j: usize) -> f64 {
        f.min[j] + f.sequences[g][[t, j]] * (f.max[j] - f.min[j])
    }

    fn pressures(s: &Session, g: usize, t: usize) -> Vec<Vec<f64>> {
        (0..s.sensors.len())
            .map(|k| s.frame_pressures(&s.grasps[g].frames[t], k))
            .collect()
    }

    #[test]
    fn names_parse_with_the_old_aliases_and_combine_with_plus() {
        let p = |t: &str| t.parse::<FeatureSet>().unwrap();
        assert_eq!(p("tactile"), FeatureSet::MOMENTS);
        assert_eq!(p("encoder"), FeatureSet::ENCODERS);
        assert_eq!(p("raw+encoders"), p("encoder + raw"));
        assert_eq!(p("raw+encoders").name(), "raw+encoders");
        assert_eq!(p("change+moments").name(), "moments+change");
        assert_eq!(p("all"), FeatureSet::ALL);
        assert_eq!(p("auto"), FeatureSet::AUTO);
        assert_eq!(p("auto").name(), "auto");
        for bad in ["", "all+raw", "auto+raw", "pressure", "raw+"] {
            let e = bad.parse::<FeatureSet>().unwrap_err().to_string();
            assert!(
                e.contains("features") && e.contains("raw+encoders"),
                "{bad}: {e}"
            );
        }
        // Saved results and projects hold the old names; they load and mean the same.
        let old: Vec<FeatureSet> =
            serde_json::from_str(r#"["all", "tactile", "encoder", "raw+encoders"]"#).unwrap();
        assert_eq!(
            old,
            [
                FeatureSet::ALL,
                FeatureSet::MOMENTS,
                FeatureSet::ENCODERS,
                p("raw+encoders")
            ]
        );
        assert_eq!(
            serde_json::to_string(&p("encoders+change")).unwrap(),
            r#""change+encoders""#
        );
        assert!(serde_json::from_str::<FeatureSet>(r#""touch""#).is_err());
    }

    #[test]
    fn all_is_encoders_then_moments_and_moments_are_the_papers() {
        let s = session();
        let all = of(&s, FeatureSet::ALL, 0.0);
        let enc = of(&s, FeatureSet::ENCODERS, 0.0);
        let mom = of(&s, "tactile".parse().unwrap(), 0.0);
        assert_eq!((all.dim(), enc.dim(), mom.dim()), (34, 9, 25));
        assert_eq!(all.families.name(), "moments+encoders");
        assert_eq!(&all.names[..9], &enc.names[..]);
        assert_eq!(&all.names[9..], &mom.names[..]);
        for g in 0..s.grasps.len() {
            // Each column is normalised on its own: the split sets are the same numbers.
            assert_eq!(
                all.sequences[g].slice(ndarray::s![.., ..9]),
                enc.sequences[g]
            );
            assert_eq!(
                all.sequences[g].slice(ndarray::s![.., 9..]),
                mom.sequences[g]
            );
            for (t, frame) in s.grasps[g].frames.iter().enumerate() {
                assert!((unnormalised(&enc, g, t, 4) - frame.encoders[4]).abs() < 1e-9);
                // Finger k's mean (column 5k) and max (5k + 3), from the pressures.
                for (k, p) in pressures(&s, g, t).iter().enumerate() {
                    let mean = p.iter().sum::<f64>() / p.len() as f64;
                    let max = p.iter().cloned().fold(f64::MIN, f64::max);
                    assert!((unnormalised(&mom, g, t, 5 * k) - mean).abs() < 1e-9);
                    assert!((unnormalised(&mom, g, t, 5 * k + 3) - max).abs() < 1e-9);
                }
            }
        }
    }

    #[test]
    fn raw_is_every_taxel_and_its_z_score_normalises_alike() {
        let s = session();
        let raw = of(&s, FeatureSet::RAW, 0.0);
        assert_eq!(raw.dim(), 5 * 12);
        assert_eq!(raw.names[13], format!("{}/raw/1", s.sensors[1].name));
        // Each taxel z-scored over every frame of the session, then min-max as every
        // column: the same numbers (min-max forgets a per-column affine change).
        let frames: Vec<(usize, usize)> = (0..s.grasps.len())
            .flat_map(|g| (0..s.grasps[g].frames.len()).map(move |t| (g, t)))
            .collect();
        for j in [0, 13, 59] {
            let (k, i) = (j / 12, j % 12);
            let p: Vec<f64> = frames
                .iter()
                .map(|&(g, t)| pressures(&s, g, t)[k][i])
                .collect();
            let n = p.len() as f64;
            let mean = p.iter().sum::<f64>() / n;
            let sd = (p.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
            let z: Vec<f64> = p.iter().map(|v| (v - mean) / sd).collect();
            assert!(z.iter().sum::<f64>().abs() < 1e-9 * n);
            let (lo, hi) = z
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            for (&(g, t), zv) in frames.iter().zip(&z) {
                let want = (zv - lo) / (hi - lo);
                assert!((raw.sequences[g][[t, j]] - want).abs() < 1e-12, "taxel {j}");
                assert!((unnormalised(&raw, g, t, j) - pressures(&s, g, t)[k][i]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn change_is_zero_at_every_grasps_first_frame() {
        let s = session();
        for noise in [0.0, 100.0] {
            let ch = of(&s, FeatureSet::CHANGE, noise);
            assert_eq!(ch.dim(), 60);
            for (g, grasp) in s.grasps.iter().enumerate() {
                for j in 0..60 {
                    assert!(
                        unnormalised(&ch, g, 0, j).abs() < 1e-9,
                        "grasp {g} taxel {j}"
                    );
                }
                if noise == 0.0 {
                    let (t, (k, i)) = (grasp.frames.len() - 1, (2, 7));
                    let want = pressures(&s, g, t)[k][i] - pressures(&s, g, 0)[k][i];
                    assert!((unnormalised(&ch, g, t, 12 * k + i) - want).abs() < 1e-9);
                }
            }
        }
    }

    #[test]
    fn codes_are_each_frames_optimal_sparse_code_on_the_sessions_dictionaries() {
        let s = session();
        let codes = of(&s, FeatureSet::CODES, 0.0);
        assert_eq!(codes.dim(), 5 * 12, "a complete dictionary per fingertip");
        assert_eq!(codes.names[14], format!("{}/codes/2", s.sensors[1].name));
        let book = codes.codes.clone().expect("the dictionaries used");
        let (mut zeros, mut total) = (0, 0);
        for (g, t) in [(0, 0), (7, 5), (59, 3)] {
            for (k, p) in pressures(&s, g, t).iter().enumerate() {
                let c = &book.sensors[k];
                let x: Vec<f64> = p
                    .iter()
                    .zip(c.mean.iter().zip(&c.sd))
                    .map(|(v, (m, sd))| (v - m) / sd)
                    .collect();
                let d = &c.dictionary.atoms;
                // (Undoing the min-max leaves rounding where a code is 0.)
                let a: Vec<f64> = (0..12)
                    .map(|j| unnormalised(&codes, g, t, 12 * k + j))
                    .map(|v| if v.abs() < 1e-12 { 0.0 } else { v })
                    .collect();
                // The L1 optimality conditions of eq. 3 (γ = 1) at the column's values.
                let gram: Vec<f64> = d.dot(&d.t()).iter().copied().collect();
                let dx: Vec<f64> = d.dot(&ndarray::Array1::from(x.clone())).to_vec();
                let violation = crate::sparse::l1_optimality_violation(&gram, &dx, 1.0, &a);

                assert!(
                    violation < 1e-6,
                    "grasp {g} frame {t} sensor {k}: {violation}"
                );
                zeros += a.iter().filter(|v| v.abs() < 1e-9).count();
                total += a.len();
            }
        }
        assert!(zeros > total / 4, "sparse: {zeros} of {total} zero");
        // A model's dictionaries code another session; taxels it does not know are refused.
        let other = simulate::object_recognition(4);
        let params = SequenceParams {
            features: FeatureSet::CODES,
            ..SequenceParams::default()
        };
        let on_book =
            feature_sequences_in(&other, &params, SequenceRange::Session, Some(&book)).unwrap();
        assert_eq!(on_book.codes.as_ref(), Some(&book));
        let own = feature_sequences(&other, &params).unwrap();
        assert_ne!(
            own.codes.as_ref(),
            Some(&book),
            "learned on the other session"
        );
        let mut narrow = book.clone();
        narrow.sensors[2].mean.pop();
        let e = feature_sequences_in(&other, &params, SequenceRange::Session, Some(&narrow))
            .unwrap_err()
            .to_string();
        assert!(e.contains("codes' dictionaries"), "{e}");
    }

    #[test]
    fn combinations_join_the_families_columns_and_noise_reaches_taxels_only() {
        let s = session();
        let both = of(&s, "raw+encoders".parse().unwrap(), 0.0);
        let raw = of(&s, FeatureSet::RAW, 0.0);
        let enc = of(&s, FeatureSet::ENCODERS, 0.0);
        assert_eq!(both.dim(), 69);
        assert_eq!(both.names[..9], enc.names[..]);
        assert_eq!(
            both.sequences[7].slice(ndarray::s![.., 9..]),
            raw.sequences[7]
        );
        let noisy = of(&s, "raw+encoders".parse().unwrap(), 100.0);
        assert_eq!(
            noisy.sequences[7].slice(ndarray::s![.., ..9]),
            enc.sequences[7]
        );
        assert!((noisy.sequences[7][[3, 20]] - both.sequences[7][[3, 20]]).abs() > 1e-6);
    }

    #[test]
    fn all_without_encoders_uses_the_moments_and_an_explicit_family_must_exist() {
        let mut s = session();
        s.encoders.clear();
        s.grasps
            .iter_mut()
            .flat_map(|g| &mut g.frames)
            .for_each(|f| f.encoders.clear());
        let all = of(&s, FeatureSet::ALL, 0.0);
        assert_eq!(all.families, FeatureSet::MOMENTS);
        assert_eq!(all.dim(), 25);
        assert_eq!(FeatureSet::ALL.dim(&s), Some(25));
        assert_eq!(FeatureSet::ENCODERS.dim(&s), None);
        assert_eq!(FeatureSet::of(&[]).dim(&s), None);
        assert_eq!(
            FeatureSet::of(&[Family::Raw, Family::Moments]).dim(&s),
            Some(85)
        );
        let e = feature_sequences(
            &s,
            &SequenceParams {
                features: "raw+encoders".parse().unwrap(),
                ..SequenceParams::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("raw+encoders") && e.contains("no joint encoders"),
            "{e}"
        );
    }
}
