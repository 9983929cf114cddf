//! The signals a researcher can plot: any taxel, any joint, a sensor's per-frame statistic
//! or total pressure, the whole hand's total pressure, and a model's per-step output; and
//! the searchable tree they are picked from.

use serde::{Deserialize, Serialize};

use crate::session::{Frame, Session};

/// A statistic of one sensor's pressures at one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SensorStat {
    Mean,
    /// Population standard deviation (as the per-finger moments of `features`).
    Sd,
    Max,
    /// The sum of the sensor's pressures.
    Total,
}

impl SensorStat {
    pub const ALL: [SensorStat; 4] = [
        SensorStat::Mean,
        SensorStat::Sd,
        SensorStat::Max,
        SensorStat::Total,
    ];

    pub fn text(self) -> &'static str {
        match self {
            SensorStat::Mean => "mean pressure",
            SensorStat::Sd => "sd of pressure",
            SensorStat::Max => "max pressure",
            SensorStat::Total => "total pressure",
        }
    }

    fn of(self, p: &[f64]) -> f64 {
        if p.is_empty() {
            return f64::NAN;
        }
        let n = p.len() as f64;
        let total: f64 = p.iter().sum();
        match self {
            SensorStat::Total => total,
            SensorStat::Mean => total / n,
            SensorStat::Max => p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            SensorStat::Sd => {
                let mean = total / n;
                (p.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt()
            }
        }
    }
}

/// One plottable signal of a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Signal {
    /// One taxel's pressure.
    Taxel { sensor: usize, taxel: usize },
    /// One joint encoder.
    Joint(usize),
    /// A statistic of one sensor's pressures.
    Sensor { sensor: usize, stat: SensorStat },
    /// The sum of every sensor's pressures.
    HandTotal,
    /// A model's per-step output: index into the [`StepOutputs`] the caller holds.
    Output(usize),
}

/// A model's output after every step of every grasp (a class probability, a decision
/// value, a novelty score), computed from a model the session has.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepOutputs {
    /// What it is, e.g. "DS · true class probability".
    pub name: String,
    pub unit: String,
    /// `[grasp][frame]`; a grasp the model has no output for is empty.
    pub per_grasp: Vec<Vec<f64>>,
}

impl Signal {
    /// The signal in words, with its unit.
    pub fn name(self, session: &Session, outputs: &[StepOutputs]) -> (String, String) {
        let sensor_name = |k: usize| {
            (session.sensors.get(k)).map_or_else(|| format!("sensor {k}"), |s| s.name.clone())
        };
        let unit = |k: usize| session.sensors.get(k).map_or("", |s| s.unit.as_str());
        match self {
            Signal::Taxel { sensor, taxel } => (
                format!("{} taxel {}", sensor_name(sensor), taxel + 1),
                unit(sensor).into(),
            ),
            Signal::Joint(j) => (
                (session.encoders.get(j)).map_or_else(|| format!("joint {j}"), |n| n.clone()),
                String::new(),
            ),
            Signal::Sensor { sensor, stat } => (
                format!("{} {}", sensor_name(sensor), stat.text()),
                unit(sensor).into(),
            ),
            Signal::HandTotal => ("total pressure".into(), unit(0).into()),
            Signal::Output(i) => outputs.get(i).map_or_else(
                || ("a model output no longer held".into(), String::new()),
                |o| (o.name.clone(), o.unit.clone()),
            ),
        }
    }

    /// The signal's value at every frame of grasp `g` (NaN where it has none: a taxel or a
    /// joint the frame lacks, an output shorter than the grasp).
    pub fn values(self, session: &Session, g: usize, outputs: &[StepOutputs]) -> Vec<f64> {
        let Some(grasp) = session.grasps.get(g) else {
            return Vec::new();
        };
        let n = grasp.frames.len();
        match self {
            Signal::Taxel { sensor, taxel } => (grasp.frames.iter())
                .map(|f| {
                    (f.taxels.get(sensor).and_then(|t| t.get(taxel)))
                        .map_or(f64::NAN, |&raw| transformed(session, sensor, taxel, raw))
                })
                .collect(),
            Signal::Joint(j) => (grasp.frames.iter())
                .map(|f| f.encoders.get(j).copied().unwrap_or(f64::NAN))
                .collect(),
            Signal::Sensor { sensor, stat } => (grasp.frames.iter())
                .map(|f| stat.of(&pressures(session, f, sensor)))
                .collect(),
            Signal::HandTotal => (grasp.frames.iter())
                .map(|f| {
                    (0..session.sensors.len())
                        .map(|k| pressures(session, f, k).iter().sum::<f64>())
                        .sum()
                })
                .collect(),
            Signal::Output(i) => {
                let v = outputs.get(i).and_then(|o| o.per_grasp.get(g));
                (0..n)
                    .map(|t| v.and_then(|v| v.get(t)).copied().unwrap_or(f64::NAN))
                    .collect()
            }
        }
    }
}

fn transformed(session: &Session, sensor: usize, taxel: usize, raw: f64) -> f64 {
    match session.sensors.get(sensor) {
        Some(s) => s.transform.apply(taxel, raw),
        None => f64::NAN,
    }
}

/// One sensor's pressures at one frame (empty when the frame lacks the sensor).
fn pressures(session: &Session, f: &Frame, k: usize) -> Vec<f64> {
    match (f.taxels.get(k), session.sensors.get(k)) {
        (Some(raw), Some(s)) => (raw.iter().enumerate())
            .map(|(i, &v)| s.transform.apply(i, v))
            .collect(),
        _ => Vec::new(),
    }
}

/// A branch of the signal tree: a sensor (its taxels and statistics), the joints, the
/// hand, or the models.
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    pub name: String,
    pub leaves: Vec<(String, Signal)>,
}

/// Every signal of `session` (and of the `outputs` its models give), as branches of
/// named leaves: sensor → its statistics then its taxels; joints; hand; models.
pub fn tree(session: &Session, outputs: &[StepOutputs]) -> Vec<Branch> {
    let mut out = vec![Branch {
        name: "hand".into(),
        leaves: vec![("total pressure".into(), Signal::HandTotal)],
    }];
    for (k, s) in session.sensors.iter().enumerate() {
        let stats = SensorStat::ALL
            .iter()
            .map(|&stat| (stat.text().to_string(), Signal::Sensor { sensor: k, stat }));
        let taxels = (0..s.layout.taxel_count()).map(|t| {
            (
                format!("taxel {}", t + 1),
                Signal::Taxel {
                    sensor: k,
                    taxel: t,
                },
            )
        });
        out.push(Branch {
            name: s.name.clone(),
            leaves: stats.chain(taxels).collect(),
        });
    }
    if !session.encoders.is_empty() {
        out.push(Branch {
            name: "joints".into(),
            leaves: (session.encoders.iter().enumerate())
                .map(|(j, n)| (n.clone(), Signal::Joint(j)))
                .collect(),
        });
    }
    if !outputs.is_empty() {
        out.push(Branch {
            name: "models".into(),
            leaves: (outputs.iter().enumerate())
                .map(|(i, o)| (o.name.clone(), Signal::Output(i)))
                .collect(),
        });
    }
    out
}

/// The tree with only the leaves whose branch or leaf name contains every word of
/// `query` (case-insensitive); branches left empty go.
pub fn search(tree: &[Branch], query: &str) -> Vec<Branch> {
    let words: Vec<String> = query.split_whitespace().map(str::to_lowercase).collect();
    (tree.iter())
        .filter_map(|b| {
            let leaves: Vec<(String, Signal)> = (b.leaves.iter())
                .filter(|(name, _)| {
                    let text = format!("{} {}", b.name, name).to_lowercase();
                    words.iter().all(|w| text.contains(w.as_str()))
                })
                .cloned()
                .collect();
            (!leaves.is_empty()).then(|| Branch {
                name: b.name.clone(),
                leaves,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::two_sensor_session;

    #[test]
    fn values_follow_the_sensors_transform_and_statistics() {
        // Sensor 0 reads pressure as 255 − raw; frame 1 of grasp 0 has raw [255, 235, 215].
        let s = two_sensor_session();
        let taxel = Signal::Taxel {
            sensor: 0,
            taxel: 2,
        };
        assert_eq!(taxel.values(&s, 0, &[]), vec![0.0, 40.0, 20.0]);
        let stat = |stat| Signal::Sensor { sensor: 0, stat }.values(&s, 0, &[]);
        // Pressures [0, 20, 40] at frame 1: total 60, mean 20, max 40, sd √(800/3).
        assert_eq!(stat(SensorStat::Total)[1], 60.0);
        assert_eq!(stat(SensorStat::Mean)[1], 20.0);
        assert_eq!(stat(SensorStat::Max)[1], 40.0);
        assert!((stat(SensorStat::Sd)[1] - (800.0f64 / 3.0).sqrt()).abs() < 1e-12);
        // Sensor 1 is raw (identity): frame 1 holds [5]; the hand adds both sensors.
        assert_eq!(Signal::HandTotal.values(&s, 0, &[])[1], 65.0);
        assert_eq!(Signal::Joint(0).values(&s, 0, &[]), vec![0.0, 0.5, 1.0]);
        // A joint the session lacks and a grasp it lacks: missing, not a panic.
        assert!(
            Signal::Joint(7)
                .values(&s, 0, &[])
                .iter()
                .all(|v| v.is_nan())
        );
        assert!(Signal::HandTotal.values(&s, 9, &[]).is_empty());
    }

    #[test]
    fn an_output_shorter_than_its_grasp_is_missing_after_its_end() {
        let s = two_sensor_session();
        let out = StepOutputs {
            name: "DS · true class probability".into(),
            unit: String::new(),
            per_grasp: vec![vec![0.2, 0.9], vec![]],
        };
        let v = Signal::Output(0).values(&s, 0, std::slice::from_ref(&out));
        assert_eq!(&v[..2], &[0.2, 0.9]);
        assert!(v[2].is_nan());
        assert!(
            Signal::Output(0)
                .values(&s, 1, &[out])
                .iter()
                .all(|v| v.is_nan())
        );
    }

    #[test]
    fn the_tree_holds_every_taxel_and_the_search_keeps_matching_leaves() {
        let s = two_sensor_session();
        let t = tree(&s, &[]);
        let names: Vec<&str> = t.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(names, ["hand", "thumb", "index", "joints"]);
        // Four statistics and three taxels under the thumb.
        assert_eq!(t[1].leaves.len(), 4 + 3);
        let found = search(&t, "THUMB taxel");
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].leaves.len(), 3);
        assert!(search(&t, "no such signal").is_empty());
        // Every word must match, in the branch or the leaf name.
        let total = search(&t, "total");
        let leaves: usize = total.iter().map(|b| b.leaves.len()).sum();
        assert_eq!(leaves, 3, "hand, thumb and index totals");
    }
}
