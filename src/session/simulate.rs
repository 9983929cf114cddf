//! The seeded simulator behind `sample-sessions/`: small sessions shaped like the two
//! papers' data, so that a fresh clone shows something real at first start and tests have
//! data with known structure. Same seed, same bytes (values are rounded before storing).
//!
//! **Grasp stability** (like the first paper): a two-finger gripper with a 4 × 7 pressure
//! sensor (kPa, up to 400) on each finger; 54 objects × 10 picks. Each object has a mass,
//! a friction coefficient, a width and a compliance; each pick a grip force and a
//! placement error along and across the pad. The contact on each pad is an elliptical
//! pressure blob whose size grows with compliance and grip force and which is cut off where
//! it runs past the pad's edge. A pick holds when the friction the contact can give beats
//! the load during the shake test: the stability margin is
//! `ln(μ · F · a_eff / (m g (1 + shake) · (1 + lever)))` plus noise, with `a_eff` the share of
//! the blob that lies on the pad and `lever` the placement error along the pad. The 25%
//! least stable picks of the session fail (the threshold is the margin's 25th percentile),
//! so failed grasps differ the way the paper reports: smaller contact areas, contacts at
//! the fingertip's edge, fewer active taxels. Frames at 12.5 Hz: approach (no contact),
//! closing, full contact (the key frame), lift, and the shake test, during which failed
//! grasps slip (the blob slides towards the tip and fades).
//!
//! **Object recognition** (like the second paper): an iCub-like hand with 5 fingertips ×
//! 12 taxels (raw 0–255, about 245 at rest, falling under pressure) and 9 joint encoders,
//! at 10 Hz; 10 objects × 20 grasps. Each object has a size (the finger angles at first
//! contact), a stiffness (how quickly pressure rises once touching and how far the fingers
//! sink in), a shape (where on each fingertip it presses, and which fingers touch it) and a
//! per-grasp pose jitter. One of the objects is "none": the hand closes on air.

use super::{Frame, Grasp, LabelSet, Layout, Sensor, Session, SessionMeta, ValueTransform, icub};
use crate::rng::Rng;

pub const STABILITY_OBJECTS: usize = 54;
pub const STABILITY_PICKS: usize = 10;
pub const STABILITY_FAILURE_SHARE: f64 = 0.25;
const PAD_ROWS: usize = 7;
const PAD_COLS: usize = 4;
const STABILITY_FRAMES: usize = 16;
const STABILITY_KEY_FRAME: usize = 8;
const MAX_KPA: f64 = 400.0;

pub const RECOGNITION_OBJECTS: [&str; 10] = [
    "sponge",
    "plush_toy",
    "soft_bottle",
    "full_bottle",
    "soda_can",
    "tennis_ball",
    "wooden_block",
    "book",
    "mug",
    "none",
];
pub const RECOGNITION_GRASPS: usize = 20;

fn round_to(v: f64, step: f64) -> f64 {
    let r = (v / step).round() * step;
    // Normalise −0.0 so the file never shows "-0.0".
    if r == 0.0 {
        0.0
    } else {
        (r * 1e6).round() / 1e6
    }
}

struct StabilityObject {
    name: String,
    mass: f64,
    friction: f64,
    width: f64,
    compliance: f64,
}

struct Pick {
    object: usize,
    force: f64,
    offset_along: f64,
    offset_across: f64,
    margin: f64,
    /// Blob semi-axes (taxels) along and across the pad, and its on-pad share.
    axes: (f64, f64),
}

fn blob(center: (f64, f64), axes: (f64, f64), peak: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(PAD_ROWS * PAD_COLS);
    for r in 0..PAD_ROWS {
        for c in 0..PAD_COLS {
            let dr = (r as f64 - center.0) / axes.0;
            let dc = (c as f64 - center.1) / axes.1;
            let d2 = dr * dr + dc * dc;
            // A flat-topped contact: pressure falls off smoothly to zero at the rim.
            let v = if d2 < 1.0 {
                peak * (1.0 - d2).powf(0.7)
            } else {
                0.0
            };
            out.push(round_to(v.min(MAX_KPA), 0.1));
        }
    }
    out
}

/// Share of a blob's area that lies on the pad (sampled on a fine grid).
fn on_pad_share(center: (f64, f64), axes: (f64, f64)) -> f64 {
    let (mut inside, mut total) = (0usize, 0usize);
    let n = 24;
    for i in 0..n {
        for j in 0..n {
            let u = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            let v = -1.0 + 2.0 * (j as f64 + 0.5) / n as f64;
            if u * u + v * v > 1.0 {
                continue;
            }
            total += 1;
            let r = center.0 + u * axes.0;
            let c = center.1 + v * axes.1;
            if (-0.5..PAD_ROWS as f64 - 0.5).contains(&r)
                && (-0.5..PAD_COLS as f64 - 0.5).contains(&c)
            {
                inside += 1;
            }
        }
    }
    inside as f64 / total.max(1) as f64
}

/// The grasp-stability sample session.
pub fn grasp_stability(seed: u64) -> Session {
    let mut rng = Rng::stream(seed, 1);
    let objects: Vec<StabilityObject> = (0..STABILITY_OBJECTS)
        .map(|i| StabilityObject {
            name: format!("object_{:02}", i + 1),
            mass: rng.range(0.05, 1.2),
            friction: rng.range(0.3, 1.0),
            width: rng.range(0.3, 1.0),
            compliance: rng.range(0.2, 1.0),
        })
        .collect();
    let g = 9.81;
    let mut picks = Vec::with_capacity(STABILITY_OBJECTS * STABILITY_PICKS);
    for (o, obj) in objects.iter().enumerate() {
        for _ in 0..STABILITY_PICKS {
            let force = rng.range(4.0, 20.0);
            let offset_along = rng.normal() * 1.4;
            let offset_across = rng.normal() * 0.5;
            let center = (3.0 + offset_along, 1.5 + offset_across);
            let along =
                0.8 + 2.2 * obj.width * (0.6 + 0.4 * obj.compliance) * (force / 12.0).sqrt();
            let across = 0.6 + 1.2 * obj.compliance * (force / 12.0).sqrt();
            let share = on_pad_share(center, (along, across));
            let area = std::f64::consts::PI * along * across * share;
            let capacity = obj.friction * force * area.sqrt();
            let load = obj.mass * g * 1.5 * (1.0 + 0.35 * offset_along.abs());
            let margin = (capacity / load).ln() + 0.15 * rng.normal();
            picks.push(Pick {
                object: o,
                force,
                offset_along,
                offset_across,
                margin,
                axes: (along, across),
            });
        }
    }
    let mut margins: Vec<f64> = picks.iter().map(|p| p.margin).collect();
    margins.sort_by(f64::total_cmp);
    let threshold = margins[(margins.len() as f64 * STABILITY_FAILURE_SHARE) as usize];

    let grasps = picks
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let failed = p.margin < threshold;
            let obj = &objects[p.object];
            let mut prng = Rng::stream(seed, 1000 + i as u64);
            // The two fingers see mirrored placements with a little independent error.
            let centers = [
                (3.0 + p.offset_along, 1.5 + p.offset_across),
                (
                    3.0 + p.offset_along + 0.2 * prng.normal(),
                    1.5 - p.offset_across + 0.2 * prng.normal(),
                ),
            ];
            let peak = (p.force * 9.0 / (p.axes.0 * p.axes.1)).min(MAX_KPA);
            let frames = (0..STABILITY_FRAMES)
                .map(|f| {
                    let (scale, slide) = match f {
                        0..=2 => (0.0, 0.0),
                        3..=7 => ((f - 2) as f64 / 6.0, 0.0),
                        8 => (1.0, 0.0),
                        9..=11 => (
                            if failed {
                                1.0 - 0.08 * (f - 8) as f64
                            } else {
                                1.0
                            },
                            if failed { 0.25 * (f - 8) as f64 } else { 0.0 },
                        ),
                        _ => {
                            let shake = 1.0 + 0.12 * ((f - 12) as f64 * 2.1).sin();
                            if failed {
                                (
                                    shake * (0.75 - 0.17 * (f - 11) as f64).max(0.0),
                                    0.75 + 0.5 * (f - 11) as f64,
                                )
                            } else {
                                (shake, 0.0)
                            }
                        }
                    };
                    let taxels = centers
                        .iter()
                        .map(|&(r, c)| {
                            let axes = (
                                p.axes.0 * scale.sqrt().max(0.3),
                                p.axes.1 * scale.sqrt().max(0.3),
                            );
                            let mut v = if scale > 0.0 {
                                blob((r + slide, c), axes, peak * scale)
                            } else {
                                vec![0.0; PAD_ROWS * PAD_COLS]
                            };
                            for x in v.iter_mut().filter(|x| **x > 0.0) {
                                *x = round_to((*x + prng.normal() * 1.5).clamp(0.0, MAX_KPA), 0.1);
                            }
                            v
                        })
                        .collect();
                    Frame {
                        t: round_to(f as f64 * 0.08, 0.01),
                        taxels,
                        encoders: Vec::new(),
                    }
                })
                .collect();
            Grasp {
                object: obj.name.clone(),
                trial: Some((i % STABILITY_PICKS) as u32 + 1),
                labels: vec![usize::from(failed)],
                frames,
                key_frame: STABILITY_KEY_FRAME,
            }
        })
        .collect();
    let pad = |name: &str| Sensor {
        name: name.into(),
        layout: Layout::Grid {
            rows: PAD_ROWS,
            cols: PAD_COLS,
        },
        unit: "kPa".into(),
        transform: ValueTransform::Identity,
        range: None,
    };
    Session {
        meta: SessionMeta {
            name: "Simulated grasp stability".into(),
            source: format!("tactile-workbench simulator, seed {seed}"),
            frame_rate_hz: Some(12.5),
            notes: "Two 4 × 7 pads on a parallel gripper, 54 objects × 10 picks; the 25% least \
                    stable picks fail. See docs/simulator.md."
                .into(),
            ..Default::default()
        },
        sensors: vec![pad("left"), pad("right")],
        encoders: Vec::new(),
        label_sets: vec![LabelSet {
            name: "outcome".into(),
            classes: vec!["success".into(), "failure".into()],
        }],
        grasps,
    }
}

struct RecognitionObject {
    /// Joint angle at first contact, as a share of the full closing range.
    contact_at: f64,
    /// Pressure gained per step once in contact (raw units).
    stiffness: f64,
    /// How far the fingers sink in after contact (share of the range).
    sink: f64,
    /// Which fingers touch, and where on each fingertip (taxel index of the centre).
    touches: [bool; 5],
    spot: [usize; 5],
}

/// The object-recognition sample session.
pub fn object_recognition(seed: u64) -> Session {
    let mut rng = Rng::stream(seed, 2);
    let objects: Vec<RecognitionObject> = RECOGNITION_OBJECTS
        .iter()
        .map(|name| {
            let none = *name == "none";
            let mut touches = [true; 5];
            if !none {
                // Small objects miss the little (and sometimes the ring) finger.
                if rng.bernoulli(0.4) {
                    touches[4] = false;
                }
                if rng.bernoulli(0.2) {
                    touches[3] = false;
                }
            } else {
                touches = [false; 5];
            }
            let mut spot = [0usize; 5];
            for s in spot.iter_mut() {
                *s = rng.below(icub::TAXELS);
            }
            RecognitionObject {
                contact_at: if none { 2.0 } else { rng.range(0.25, 0.75) },
                stiffness: rng.range(6.0, 40.0),
                sink: rng.range(0.02, 0.25),
                touches,
                spot,
            }
        })
        .collect();
    let layout = icub::fingertip_layout();
    let positions = match &layout {
        Layout::Points { positions, .. } => positions.clone(),
        _ => Vec::new(),
    };
    // Joint ranges (degrees) of the nine hand joints.
    let joint_open = [20.0, 70.0, 10.0, 0.0, 10.0, 5.0, 5.0, 5.0, 10.0];
    let joint_range = [40.0, 30.0, 50.0, 60.0, 70.0, 80.0, 70.0, 80.0, 200.0];
    let mut grasps = Vec::new();
    for (c, obj) in objects.iter().enumerate() {
        for trial in 0..RECOGNITION_GRASPS {
            let mut g = Rng::stream(seed, 10_000 + (c * RECOGNITION_GRASPS + trial) as u64);
            let steps = 8 + g.below(11);
            let speed = 1.0 / (steps as f64 - 3.0);
            let contact_at = obj.contact_at + 0.04 * g.normal();
            let jitter: Vec<f64> = (0..9).map(|_| 2.0 * g.normal()).collect();
            let mut frames = Vec::with_capacity(steps);
            for step in 0..steps {
                let command = (step as f64 * speed).min(1.0);
                // Fingers stop at contact, then sink in as the object yields.
                let closure = if command <= contact_at {
                    command
                } else {
                    contact_at + obj.sink * (1.0 - (-(command - contact_at) * 6.0).exp())
                };
                let encoders = (0..9)
                    .map(|j| {
                        round_to(
                            joint_open[j] + joint_range[j] * closure + jitter[j] + 0.3 * g.normal(),
                            0.01,
                        )
                    })
                    .collect();
                let press_time = ((command - contact_at) / speed).max(0.0);
                let taxels = (0..5)
                    .map(|f| {
                        let level = if obj.touches[f] && command > contact_at {
                            (obj.stiffness * press_time * (1.0 + 0.1 * g.normal())).min(200.0)
                        } else {
                            0.0
                        };
                        let centre = positions[obj.spot[f]];
                        (0..icub::TAXELS)
                            .map(|t| {
                                let p = positions[t];
                                let d2 = ((p.x - centre.x).powi(2) + (p.y - centre.y).powi(2))
                                    / (30.0f64).powi(2);
                                let pressure = level * (-d2).exp();
                                (245.0 - pressure + 1.2 * g.normal())
                                    .round()
                                    .clamp(0.0, 255.0)
                            })
                            .collect()
                    })
                    .collect();
                frames.push(Frame {
                    t: round_to(step as f64 * 0.1, 0.01),
                    taxels,
                    encoders,
                });
            }
            let key_frame = (0..frames.len())
                .max_by(|&a, &b| {
                    let tot =
                        |f: &Frame| -> f64 { f.taxels.iter().flatten().map(|v| 255.0 - v).sum() };
                    tot(&frames[a]).total_cmp(&tot(&frames[b]))
                })
                .unwrap_or(0);
            grasps.push(Grasp {
                object: RECOGNITION_OBJECTS[c].to_string(),
                trial: Some(trial as u32 + 1),
                labels: vec![c],
                frames,
                key_frame,
            });
        }
    }
    Session {
        meta: SessionMeta {
            name: "Simulated object recognition".into(),
            source: format!("tactile-workbench simulator, seed {seed}"),
            frame_rate_hz: Some(10.0),
            notes: "An iCub-like hand, 5 fingertips × 12 taxels + 9 encoders, 10 objects × 20 \
                    grasps. See docs/simulator.md."
                .into(),
            ..Default::default()
        },
        sensors: icub::FINGERS
            .iter()
            .map(|name| Sensor {
                name: name.to_string(),
                layout: layout.clone(),
                unit: "raw capacitance (0–255, falls under pressure)".into(),
                transform: ValueTransform::Reversed { offset: 255.0 },
                range: None,
            })
            .collect(),
        encoders: (7..16).map(|j| format!("joint {j:02}")).collect(),
        label_sets: vec![LabelSet {
            name: "object".into(),
            classes: RECOGNITION_OBJECTS.iter().map(|s| s.to_string()).collect(),
        }],
        grasps,
    }
}
