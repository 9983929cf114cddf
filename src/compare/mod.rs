//! Comparing grasps on one timeline: any signal of a session (a taxel, a joint, a sensor's
//! statistic, a model's per-step output) for many grasps, aligned at an event, overlaid and
//! summed up per group (bands against time, or distributions for single frames), as
//! figures of the figure model. Headless: the window's Compare view draws what this builds.

pub mod align;
pub mod figures;
pub mod groups;
pub mod outputs;
pub mod signal;
pub mod stats;

pub use align::Event;
pub use figures::{ComparePlot, GraspsByTime, PointGrasps, grasp_name, time_window};
pub use groups::Groups;
pub use outputs::{ModelReading, read_model, read_sequences};
pub use signal::{Branch, SensorStat, Signal, StepOutputs};
pub use stats::Spread;

use crate::figures::Figure;
use crate::session::Session;

/// What to compare.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    pub signal: Signal,
    pub event: Event,
    pub spread: Spread,
    /// The grasps overlaid (the selection's).
    pub overlaid: Vec<usize>,
    /// The groups every grasp of the session is summed up by.
    pub groups: Groups,
    /// Seed of a strip chart's sideways jitter.
    pub seed: u64,
}

/// The comparison's figures, and which grasp each drawn part stands for.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub overlay: Figure,
    /// For a strip overlay (single frames): the grasp of each point, `[series][point]`;
    /// for lines: each series' grasp as its only entry.
    pub overlay_grasps: PointGrasps,
    pub groups: Figure,
    pub group_grasps: PointGrasps,
    pub heatmap: Figure,
    pub heatmap_rows: Vec<usize>,
    /// Each heatmap column's aligned time (s).
    pub heatmap_times: Vec<f64>,
    /// The session has one frame per grasp: groups are distributions, not bands.
    pub single_frame: bool,
}

impl Comparison {
    pub fn figure(&self, plot: ComparePlot) -> &Figure {
        match plot {
            ComparePlot::Overlay => &self.overlay,
            ComparePlot::Groups => &self.groups,
            ComparePlot::Heatmap => &self.heatmap,
        }
    }
}

/// Whether every grasp of `session` is a single frame (nothing to draw against time).
pub fn single_frame(session: &Session) -> bool {
    session.grasps.iter().all(|g| g.frames.len() <= 1)
}

/// The groups' bands (or distributions, for single frames) of `request` over every grasp
/// of the session: the part of a comparison that grows with the session, for a worker.
pub fn group_figure(
    session: &Session,
    outputs: &[StepOutputs],
    request: &Request,
) -> (Figure, PointGrasps) {
    let all: Vec<usize> = (0..session.grasps.len()).collect();
    let traces = stats::traces(session, outputs, request.signal, request.event, &all);
    let labels = labels(session, outputs, request);
    if single_frame(session) {
        let d = stats::distributions(&traces, &request.groups);
        figures::distributions(&request.groups, &d, &labels, request.seed)
    } else {
        let b = stats::bands(
            &traces,
            &request.groups,
            request.spread,
            stats::grid_step(session),
        );
        let n = b.len();
        (
            figures::bands(&request.groups, &b, request.spread, &labels),
            vec![Vec::new(); n],
        )
    }
}

fn labels(session: &Session, outputs: &[StepOutputs], request: &Request) -> figures::Labels {
    let (signal, unit) = request.signal.name(session, outputs);
    figures::Labels {
        signal,
        unit,
        time: request.event.axis_title(),
    }
}

/// Every figure of `request` on `session`.
pub fn compare(session: &Session, outputs: &[StepOutputs], request: &Request) -> Comparison {
    let labels = labels(session, outputs, request);
    let single = single_frame(session);
    let overlaid = stats::traces(
        session,
        outputs,
        request.signal,
        request.event,
        &request.overlaid,
    );
    let (overlay, overlay_grasps) = if single {
        // Single frames overlaid are points: a strip per group of the overlaid grasps.
        let d = stats::distributions(&overlaid, &request.groups);
        figures::distributions(&request.groups, &d, &labels, request.seed)
    } else {
        let grasps = overlaid.iter().map(|t| vec![t.grasp]).collect();
        (
            figures::overlay(session, &overlaid, &request.groups, &labels),
            grasps,
        )
    };
    let (groups, group_grasps) = group_figure(session, outputs, request);
    let h = figures::heatmap(
        session,
        &overlaid,
        &request.groups,
        stats::grid_step(session),
        &labels,
    );
    Comparison {
        overlay,
        overlay_grasps,
        groups,
        group_grasps,
        heatmap: h.figure,
        heatmap_rows: h.rows,
        heatmap_times: h.times,
        single_frame: single,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::figures::FigureKind;
    use crate::session::{Frame, Grasp, LabelSet, Layout, Sensor, SessionMeta, ValueTransform};

    /// Two sensors (a thumb of three taxels read as 255 − raw, an index of one raw taxel),
    /// one joint, three grasps of 3, 2 and 1 frames at 10 Hz, label set "outcome".
    pub(crate) fn two_sensor_session() -> Session {
        let sensor = |name: &str, n: usize, transform| Sensor {
            name: name.into(),
            layout: Layout::Grid { rows: 1, cols: n },
            unit: "a.u.".into(),
            transform,
            range: None,
        };
        let frame = |t: f64, thumb: [f64; 3], index: f64, joint: f64| Frame {
            t,
            taxels: vec![thumb.to_vec(), vec![index]],
            encoders: vec![joint],
        };
        let grasp = |object: &str, label: usize, frames: Vec<Frame>, key| Grasp {
            object: object.into(),
            trial: None,
            labels: vec![label],
            frames,
            key_frame: key,
        };
        Session {
            meta: SessionMeta::default(),
            sensors: vec![
                sensor("thumb", 3, ValueTransform::Reversed { offset: 255.0 }),
                sensor("index", 1, ValueTransform::Identity),
            ],
            encoders: vec!["j0".into()],
            label_sets: vec![LabelSet {
                name: "outcome".into(),
                classes: vec!["success".into(), "failure".into()],
            }],
            grasps: vec![
                grasp(
                    "mug",
                    0,
                    vec![
                        frame(0.0, [255.0, 255.0, 255.0], 0.0, 0.0),
                        frame(0.1, [255.0, 235.0, 215.0], 5.0, 0.5),
                        frame(0.2, [250.0, 255.0, 235.0], 5.0, 1.0),
                    ],
                    2,
                ),
                grasp(
                    "ball",
                    1,
                    vec![
                        frame(0.0, [255.0, 255.0, 255.0], 0.0, 0.0),
                        frame(0.1, [155.0, 255.0, 255.0], 0.0, 0.2),
                    ],
                    1,
                ),
                grasp(
                    "mug",
                    1,
                    vec![frame(0.0, [255.0, 255.0, 205.0], 0.0, 0.0)],
                    0,
                ),
            ],
        }
    }

    #[test]
    fn a_comparison_overlays_the_selection_and_bands_every_grasp() {
        let s = two_sensor_session();
        let request = Request {
            signal: Signal::HandTotal,
            event: Event::FirstFrame,
            spread: Spread::MeanSd,
            overlaid: vec![1, 0],
            groups: Groups::by_object(&s),
            seed: 1,
        };
        let c = compare(&s, &[], &request);
        assert!(!c.single_frame);
        let FigureKind::Chart(o) = &c.overlay.kind else {
            panic!("the overlay is a chart")
        };
        // The selection's two grasps, in its order, named after their grasps.
        assert_eq!(o.series.len(), 2);
        assert_eq!(c.overlay_grasps, [vec![1], vec![0]]);
        assert_eq!(o.series[0].name, "ball · grasp 2");
        assert_eq!(o.series[0].y, [0.0, 100.0]);
        // Bands over all three grasps: mug (grasps 0 and 2) and ball.
        let FigureKind::Chart(b) = &c.groups.kind else {
            panic!("bands are a chart")
        };
        let names: Vec<&str> = b.series.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["mug (n=2)", "ball (n=1)"]);
        // Mug at t = 0: hand totals 0 (grasp 0) and 50 (grasp 2): mean 25 ± 25.
        assert_eq!(b.series[0].y[0], 25.0);
        let e = b.series[0].error.as_ref().expect("a band");
        assert_eq!((e.lower[0], e.upper[0]), (0.0, 50.0));
        // The heatmap's rows are the overlaid grasps sorted by group: mug, then ball; its
        // columns the frames at 0, 0.1 and 0.2 s.
        assert_eq!(c.heatmap_rows, [0, 1]);
        assert_eq!(c.heatmap_times.len(), 3);
        for (t, want) in c.heatmap_times.iter().zip([0.0, 0.1, 0.2]) {
            assert!((t - want).abs() < 1e-12, "{:?}", c.heatmap_times);
        }
        for f in [&c.overlay, &c.groups, &c.heatmap] {
            f.validate().expect("a drawable figure");
        }
    }

    #[test]
    fn single_frames_give_distributions_not_time_axes() {
        let mut s = two_sensor_session();
        for g in &mut s.grasps {
            g.frames.truncate(1);
            g.key_frame = 0;
        }
        let request = Request {
            signal: Signal::Taxel {
                sensor: 0,
                taxel: 2,
            },
            event: Event::ContactOnset,
            spread: Spread::MeanSd,
            overlaid: vec![0, 1, 2],
            groups: Groups::by_label_set(&s, 0),
            seed: 7,
        };
        let c = compare(&s, &[], &request);
        assert!(c.single_frame);
        let FigureKind::Chart(d) = &c.groups.kind else {
            panic!("distributions are a chart")
        };
        // A strip per class and the medians: success holds grasp 0 (0), failure grasps 1
        // and 2 (0 and 50).
        assert_eq!(d.series.len(), 3);
        assert_eq!(c.group_grasps[..2], [vec![0], vec![1, 2]]);
        assert_eq!(d.series[1].y, [0.0, 50.0]);
        assert!(d.series[1].x.iter().all(|x| (x - 2.0).abs() <= 0.25));
        assert_eq!(d.series[2].y, [0.0, 25.0]);
        assert!(!d.x.title.contains("time"), "{}", d.x.title);
        // Each strip's group named on its axis, at the strip's position.
        assert_eq!(d.x.categories, ["success", "failure"]);
        assert_eq!(d.x.category_at(d.series[1].x[0]), Some("failure"));
        // The same seed jitters the same way.
        assert_eq!(compare(&s, &[], &request), c);
        c.groups.validate().expect("drawable");
    }
}
