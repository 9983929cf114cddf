//! Seeded perturbations of a session, for the robustness experiment ("where the methods
//! fail"): one physical fault at a time, applied to the RAW readings so that it means the
//! same thing for every sensor whatever its value transform.
//!
//! Every sensor's transform is affine with slope ±1 in the raw reading (identity,
//! `offset − reading`, `baseline − reading`), so a change of pressure by Δ is a change of
//! the raw reading by ±Δ, and "no contact" / "full scale" are raw readings we can solve
//! for. Strengths:
//!
//! - [`PerturbationKind::Noise`]: additive Gaussian noise on every raw reading of every
//!   frame, strength = variance on the iCub's 0–255 scale (the paper's Fig. 8 uses 100 and
//!   1000). A sensor whose raw range is W wide gets variance `strength · (W / 255)²`, i.e.
//!   the same noise relative to its full scale (BioTac 12-bit: 1000 → sd ≈ 507 counts).
//! - [`PerturbationKind::DeadTaxels`]: a share (0–1) of all taxels stuck at zero pressure
//!   (the resting reading) or at full-scale pressure, chosen at random but nested: with
//!   the same seed a larger share kills a superset of the taxels.
//! - [`PerturbationKind::DeadSensor`]: a number of whole sensors (fingers) stuck, chosen
//!   at random, nested like the taxels.
//! - [`PerturbationKind::Drift`]: an offset that raises the pressure by `strength · W`
//!   (a share of full scale) at the last grasp of the session, growing linearly with the
//!   grasp's place in the session order from 0 at the first grasp; constant within a grasp
//!   (a slow baseline creep).
//! - [`PerturbationKind::Gain`]: every pressure multiplied by `strength` (a new sensor
//!   with a different sensitivity, the first paper's second experiment).
//! - [`PerturbationKind::Truncation`]: each grasp keeps its first ⌈strength · T⌉ frames
//!   (at least one), strength = share kept.
//! - [`PerturbationKind::MissingFrames`]: round(strength · T) frames of each grasp dropped
//!   at random (at least one frame is kept), time stamps unchanged so the gaps show.
//!
//! Saturation: with `saturate` (the default) every perturbed reading is clamped to the
//! sensor's raw range, as a real sensor's reading would saturate. The existing Fig. 8
//! reproduction (`features::sequence`) does not clip, as the paper does not say it did;
//! `saturate: false` reproduces that.
//!
//! Raw range of a sensor: the range its unit states ("0–255" on the iCub); otherwise the
//! span of the raw readings of every sensor with the same unit over the session (BTS3:
//! 87–3975, 95 % of the BioTac's 12-bit scale; the simulated kPa pads: 0–125.5).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::rng::Rng;
use crate::session::{Session, ValueTransform};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PerturbError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("invalid data: {0}")]
    Data(String),
}

fn param(name: &'static str, reason: impl Into<String>) -> PerturbError {
    PerturbError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// Where a stuck taxel or sensor stays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stuck {
    /// The resting reading: zero pressure (a broken taxel).
    Zero,
    /// The full-scale reading: the largest pressure the sensor can report (a short).
    Max,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PerturbationKind {
    Noise,
    DeadTaxels { stuck: Stuck },
    DeadSensor { stuck: Stuck },
    Drift,
    Gain,
    Truncation,
    MissingFrames,
}

impl PerturbationKind {
    /// The strength that leaves the session unchanged.
    pub fn neutral(self) -> f64 {
        match self {
            PerturbationKind::Gain | PerturbationKind::Truncation => 1.0,
            _ => 0.0,
        }
    }

    /// What the strength measures, for axis titles.
    pub fn strength_title(self) -> (&'static str, &'static str) {
        match self {
            PerturbationKind::Noise => ("noise variance (iCub 0–255 scale)", "reading²"),
            PerturbationKind::DeadTaxels { .. } => ("share of taxels stuck", "fraction"),
            PerturbationKind::DeadSensor { .. } => ("sensors stuck", "count"),
            PerturbationKind::Drift => ("drift at the last grasp", "share of full scale"),
            PerturbationKind::Gain => ("gain", "factor"),
            PerturbationKind::Truncation => ("share of each grasp kept", "fraction"),
            PerturbationKind::MissingFrames => ("share of frames dropped", "fraction"),
        }
    }
}

/// One perturbation at one strength.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PerturbParams {
    pub kind: PerturbationKind,
    pub strength: f64,
    pub seed: u64,
    /// Clamp perturbed readings to the sensor's raw range.
    pub saturate: bool,
}

impl PerturbParams {
    pub fn new(kind: PerturbationKind, strength: f64, seed: u64) -> Self {
        PerturbParams {
            kind,
            strength,
            seed,
            saturate: true,
        }
    }

    /// Check the strength against its kind (and, for a dead sensor, the session).
    pub fn validate(&self) -> Result<(), PerturbError> {
        let s = self.strength;
        if !s.is_finite() {
            return Err(param("strength", format!("must be finite, got {s}")));
        }
        let unit = |what: &str| {
            if (0.0..=1.0).contains(&s) {
                Ok(())
            } else {
                Err(param(
                    "strength",
                    format!("{what} must lie in [0, 1], got {s}"),
                ))
            }
        };
        match self.kind {
            PerturbationKind::Noise => {
                if s < 0.0 {
                    return Err(param(
                        "strength",
                        format!("a noise variance must be ≥ 0, got {s}"),
                    ));
                }
            }
            PerturbationKind::DeadTaxels { .. } => unit("a share of taxels")?,
            PerturbationKind::DeadSensor { .. } => {
                if s < 0.0 || s.fract() != 0.0 {
                    return Err(param(
                        "strength",
                        format!("a count of dead sensors must be a whole number ≥ 0, got {s}"),
                    ));
                }
            }
            PerturbationKind::Drift => {
                if !(-1.0..=1.0).contains(&s) {
                    return Err(param(
                        "strength",
                        format!("a drift (share of full scale) must lie in [-1, 1], got {s}"),
                    ));
                }
            }
            PerturbationKind::Gain => {
                if s < 0.0 {
                    return Err(param("strength", format!("a gain must be ≥ 0, got {s}")));
                }
            }
            PerturbationKind::Truncation => {
                if !(s > 0.0 && s <= 1.0) {
                    return Err(param(
                        "strength",
                        format!("the share of a grasp kept must lie in (0, 1], got {s}"),
                    ));
                }
            }
            PerturbationKind::MissingFrames => {
                if !(0.0..1.0).contains(&s) {
                    return Err(param(
                        "strength",
                        format!("the share of frames dropped must lie in [0, 1), got {s}"),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The raw range of a sensor, and which end means the most pressure.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RawRange {
    pub lo: f64,
    pub hi: f64,
}

impl RawRange {
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    fn clamp(&self, v: f64) -> f64 {
        v.clamp(self.lo, self.hi)
    }
}

/// A range "A–B" (or "A-B") stated in a unit text, e.g. "raw capacitance (0–255, …)".
fn stated_range(unit: &str) -> Option<RawRange> {
    let chars: Vec<char> = unit.chars().collect();
    let number_at = |mut i: usize| -> Option<(f64, usize)> {
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
            i += 1;
        }
        let text: String = chars[start..i].iter().collect();
        text.parse().ok().map(|v| (v, i))
    };
    let mut i = 0;
    while i < chars.len() {
        let boundary = i == 0 || !(chars[i - 1].is_ascii_digit() || chars[i - 1] == '.');
        if chars[i].is_ascii_digit()
            && boundary
            && let Some((lo, j)) = number_at(i)
        {
            if j < chars.len()
                && (chars[j] == '–' || chars[j] == '-')
                && let Some((hi, _)) = number_at(j + 1)
                && hi > lo
            {
                return Some(RawRange { lo, hi });
            }
            i = j.max(i + 1);
            continue;
        }
        i += 1;
    }
    None
}

/// The raw range of every sensor of `session` (see the module notes).
pub fn raw_ranges(session: &Session) -> Result<Vec<RawRange>, PerturbError> {
    // One pass over the readings: the span of each unit that states no range.
    let mut spans: BTreeMap<&str, (f64, f64)> = BTreeMap::new();
    for (s, sensor) in session.sensors.iter().enumerate() {
        if stated_range(&sensor.unit).is_some() {
            continue;
        }
        let (lo, hi) = spans
            .entry(sensor.unit.as_str())
            .or_insert((f64::INFINITY, f64::NEG_INFINITY));
        for v in session
            .grasps
            .iter()
            .flat_map(|g| &g.frames)
            .filter_map(|f| f.taxels.get(s))
            .flatten()
        {
            *lo = lo.min(*v);
            *hi = hi.max(*v);
        }
    }
    let mut out = Vec::with_capacity(session.sensors.len());
    for sensor in &session.sensors {
        if let Some(r) = stated_range(&sensor.unit) {
            out.push(r);
            continue;
        }
        let (lo, hi) = spans[sensor.unit.as_str()];
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(PerturbError::Data(format!(
                "sensor `{}` has no spread of readings to take a raw range from",
                sensor.name
            )));
        }
        out.push(RawRange { lo, hi });
    }
    Ok(out)
}

/// +1 when the pressure grows with the raw reading, −1 when it falls.
fn slope(t: &ValueTransform) -> f64 {
    match t {
        ValueTransform::Identity => 1.0,
        ValueTransform::Reversed { .. } | ValueTransform::BaselineMinus { .. } => -1.0,
    }
}

/// The raw reading that gives pressure `p` at `taxel`.
fn raw_of(t: &ValueTransform, taxel: usize, p: f64) -> f64 {
    // p = apply(0) + slope · raw.
    (p - t.apply(taxel, 0.0)) / slope(t)
}

/// `session` with one perturbation applied. The result keeps every count consistent
/// (frames dropped or cut keep a valid key frame), so every analysis can read it.
pub fn perturb(session: &Session, p: &PerturbParams) -> Result<Session, PerturbError> {
    p.validate()?;
    let ranges = raw_ranges(session)?;
    let mut out = session.clone();
    let s = p.strength;
    let sat = |r: &RawRange, v: f64| if p.saturate { r.clamp(v) } else { v };
    match p.kind {
        PerturbationKind::Noise => {
            for (g, grasp) in out.grasps.iter_mut().enumerate() {
                let mut rng = Rng::stream(p.seed, g as u64);
                for frame in &mut grasp.frames {
                    for (sn, values) in frame.taxels.iter_mut().enumerate() {
                        let Some(r) = ranges.get(sn) else { continue };
                        let sd = s.sqrt() * r.width() / 255.0;
                        for v in values.iter_mut() {
                            *v = sat(r, *v + sd * rng.normal());
                        }
                    }
                }
            }
        }
        PerturbationKind::DeadTaxels { stuck } => {
            let all: Vec<(usize, usize)> = session
                .sensors
                .iter()
                .enumerate()
                .flat_map(|(sn, sensor)| (0..sensor.layout.taxel_count()).map(move |t| (sn, t)))
                .collect();
            let n = (s * all.len() as f64).round() as usize;
            let order = Rng::stream(p.seed, 0xDEAD).permutation(all.len());
            let dead: Vec<(usize, usize)> =
                order[..n.min(all.len())].iter().map(|&i| all[i]).collect();
            stick(&mut out, &ranges, &dead, stuck);
        }
        PerturbationKind::DeadSensor { stuck } => {
            let n = s as usize;
            let count = session.sensors.len();
            if n > count {
                return Err(param(
                    "strength",
                    format!("{n} dead sensors, but the session has {count}"),
                ));
            }
            let order = Rng::stream(p.seed, 0x5E45).permutation(count);
            let dead: Vec<(usize, usize)> = order[..n]
                .iter()
                .flat_map(|&sn| (0..session.sensors[sn].layout.taxel_count()).map(move |t| (sn, t)))
                .collect();
            stick(&mut out, &ranges, &dead, stuck);
        }
        PerturbationKind::Drift => {
            let last = out.grasps.len().saturating_sub(1).max(1) as f64;
            let sensors = &session.sensors;
            for (g, grasp) in out.grasps.iter_mut().enumerate() {
                let share = s * g as f64 / last;
                for frame in &mut grasp.frames {
                    for (sn, values) in frame.taxels.iter_mut().enumerate() {
                        let (Some(r), Some(sensor)) = (ranges.get(sn), sensors.get(sn)) else {
                            continue;
                        };
                        // Raising the pressure by Δ moves the reading by slope · Δ.
                        let shift = slope(&sensor.transform) * share * r.width();
                        for v in values.iter_mut() {
                            *v = sat(r, *v + shift);
                        }
                    }
                }
            }
        }
        PerturbationKind::Gain => {
            let sensors = &session.sensors;
            for grasp in &mut out.grasps {
                for frame in &mut grasp.frames {
                    for (sn, values) in frame.taxels.iter_mut().enumerate() {
                        let (Some(r), Some(sensor)) = (ranges.get(sn), sensors.get(sn)) else {
                            continue;
                        };
                        let t = &sensor.transform;
                        // raw_of(gain · p) = raw + (gain − 1) · p / slope, written so that a
                        // gain of 1 returns every reading exactly.
                        for (i, v) in values.iter_mut().enumerate() {
                            *v = sat(r, *v + (s - 1.0) * t.apply(i, *v) / slope(t));
                        }
                    }
                }
            }
        }
        PerturbationKind::Truncation => {
            for grasp in &mut out.grasps {
                let keep = ((s * grasp.frames.len() as f64).ceil() as usize)
                    .clamp(1, grasp.frames.len().max(1));
                grasp.frames.truncate(keep);
                grasp.key_frame = grasp.key_frame.min(grasp.frames.len().saturating_sub(1));
            }
        }
        PerturbationKind::MissingFrames => {
            for (g, grasp) in out.grasps.iter_mut().enumerate() {
                let t = grasp.frames.len();
                let drop = ((s * t as f64).round() as usize).min(t.saturating_sub(1));
                if drop == 0 {
                    continue;
                }
                let mut rng = Rng::stream(p.seed, g as u64);
                let mut gone = vec![false; t];
                for &i in &rng.permutation(t)[..drop] {
                    gone[i] = true;
                }
                // The key frame moves to the nearest kept frame (earlier first).
                let key = grasp.key_frame;
                let new_key_old_index = (0..t)
                    .filter(|&i| !gone[i])
                    .min_by_key(|&i| (i.abs_diff(key), i))
                    .unwrap_or(0);
                grasp.key_frame = (0..new_key_old_index).filter(|&i| !gone[i]).count();
                let mut i = 0;
                grasp.frames.retain(|_| {
                    let keep = !gone[i];
                    i += 1;
                    keep
                });
            }
        }
    }
    Ok(out)
}

/// Set `taxels` (sensor, taxel) of every frame to the stuck reading.
fn stick(out: &mut Session, ranges: &[RawRange], taxels: &[(usize, usize)], stuck: Stuck) {
    let values: Vec<(usize, usize, f64)> = taxels
        .iter()
        .map(|&(sn, t)| {
            let tr = &out.sensors[sn].transform;
            let r = ranges[sn];
            let v = match stuck {
                Stuck::Zero => r.clamp(raw_of(tr, t, 0.0)),
                Stuck::Max => {
                    if slope(tr) > 0.0 {
                        r.hi
                    } else {
                        r.lo
                    }
                }
            };
            (sn, t, v)
        })
        .collect();
    for grasp in &mut out.grasps {
        for frame in &mut grasp.frames {
            for &(sn, t, v) in &values {
                if let Some(x) = frame.taxels.get_mut(sn).and_then(|s| s.get_mut(t)) {
                    *x = v;
                }
            }
        }
    }
}

/// One axis of the robustness sweep (its meaning for the experiment:
/// `experiments::robustness::perturbations`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Perturbation {
    /// Gaussian noise on the raw readings (variance, iCub 0–255 scale).
    Noise,
    /// A share of taxels stuck at zero pressure.
    DeadTaxels,
    /// A share of taxels stuck at full-scale pressure.
    SaturatedTaxels,
    /// Whole sensors (fingers) stuck at zero pressure (a count).
    DeadSensor,
    /// A linear offset over the session (share of full scale at the last grasp).
    Drift,
    /// Pressures multiplied by a factor (a new sensor).
    Gain,
    /// Share of each test grasp kept (its beginning).
    Truncation,
    /// Share of each test grasp's frames dropped at random.
    MissingFrames,
    /// Stability: failures' share of the training set; recognition: share of their
    /// training grasps kept by half the classes (the minority).
    Imbalance,
    /// Training grasps per class.
    FewExamples,
    /// Share of the objects held out (never seen in training).
    NewObjects,
}

impl Perturbation {
    pub const ALL: [Perturbation; 11] = [
        Perturbation::Noise,
        Perturbation::DeadTaxels,
        Perturbation::SaturatedTaxels,
        Perturbation::DeadSensor,
        Perturbation::Drift,
        Perturbation::Gain,
        Perturbation::Truncation,
        Perturbation::MissingFrames,
        Perturbation::Imbalance,
        Perturbation::FewExamples,
        Perturbation::NewObjects,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Perturbation::Noise => "noise",
            Perturbation::DeadTaxels => "dead-taxels",
            Perturbation::SaturatedTaxels => "saturated-taxels",
            Perturbation::DeadSensor => "dead-sensor",
            Perturbation::Drift => "drift",
            Perturbation::Gain => "gain",
            Perturbation::Truncation => "truncation",
            Perturbation::MissingFrames => "missing-frames",
            Perturbation::Imbalance => "imbalance",
            Perturbation::FewExamples => "few-examples",
            Perturbation::NewObjects => "new-objects",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stated_ranges_are_read_from_units() {
        let r = stated_range("raw capacitance (0–255, falls under pressure)").unwrap();
        assert_eq!((r.lo, r.hi), (0.0, 255.0));
        let r = stated_range("counts 100-4095").unwrap();
        assert_eq!((r.lo, r.hi), (100.0, 4095.0));
        assert!(stated_range("kPa").is_none());
        assert!(stated_range("raw electrode reading").is_none());
    }

    #[test]
    fn raw_of_inverts_every_transform() {
        for t in [
            ValueTransform::Identity,
            ValueTransform::Reversed { offset: 255.0 },
            ValueTransform::BaselineMinus {
                baseline: vec![3000.0, 2500.0],
            },
        ] {
            for taxel in 0..2 {
                for p in [-3.0, 0.0, 17.5] {
                    assert!((t.apply(taxel, raw_of(&t, taxel, p)) - p).abs() < 1e-9);
                }
            }
        }
    }
}
