//! Aligning grasps in time: each grasp's time is taken relative to an event of its own
//! (its first frame, its contact onset or its key frame), so that many grasps share one
//! time axis.

use serde::{Deserialize, Serialize};

use super::signal::Signal;
use crate::session::Session;

/// The moment of a grasp that aligned time counts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Event {
    FirstFrame,
    /// The first frame whose total pressure has risen by [`ONSET_SHARE`] of the grasp's
    /// whole rise above its first frame.
    #[default]
    ContactOnset,
    /// The session's key frame (full contact).
    KeyFrame,
}

/// The share of a grasp's pressure rise that marks its contact onset: small enough to
/// catch the first touch, large enough that sensor noise before it does not.
pub const ONSET_SHARE: f64 = 0.1;

impl Event {
    pub const ALL: [Event; 3] = [Event::ContactOnset, Event::KeyFrame, Event::FirstFrame];

    pub fn text(self) -> &'static str {
        match self {
            Event::FirstFrame => "first frame",
            Event::ContactOnset => "contact onset",
            Event::KeyFrame => "key frame",
        }
    }

    /// The axis title of time counted from this event.
    pub fn axis_title(self) -> String {
        format!("time from {}", self.text())
    }

    /// The frame of grasp `g` this event falls on (0 for a grasp the session lacks).
    pub fn frame(self, session: &Session, g: usize) -> usize {
        let Some(grasp) = session.grasps.get(g) else {
            return 0;
        };
        match self {
            Event::FirstFrame => 0,
            Event::KeyFrame => grasp.key_frame.min(grasp.frames.len().saturating_sub(1)),
            Event::ContactOnset => onset(&Signal::HandTotal.values(session, g, &[])),
        }
    }

    /// The time of every frame of grasp `g` relative to this event's frame.
    pub fn times(self, session: &Session, g: usize) -> Vec<f64> {
        let Some(grasp) = session.grasps.get(g) else {
            return Vec::new();
        };
        let at = grasp
            .frames
            .get(self.frame(session, g))
            .map_or(0.0, |f| f.t);
        grasp.frames.iter().map(|f| f.t - at).collect()
    }
}

/// The first index where `total` has risen by [`ONSET_SHARE`] of its greatest rise above
/// its first value; 0 when it never rises (or is empty).
pub fn onset(total: &[f64]) -> usize {
    let Some(&first) = total.first() else {
        return 0;
    };
    let peak = total
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(first, f64::max);
    let rise = peak - first;
    // A NaN or non-positive rise: the grasp never rises.
    if rise.is_nan() || rise <= 0.0 {
        return 0;
    }
    let level = first + ONSET_SHARE * rise;
    total.iter().position(|&v| v >= level).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::two_sensor_session;

    #[test]
    fn onset_is_the_first_frame_past_a_tenth_of_the_rise() {
        // Rise 0 → 100: the level is 10; 9 is below it, 10 reaches it.
        assert_eq!(onset(&[0.0, 5.0, 9.0, 10.0, 100.0, 50.0]), 3);
        // From a resting 200, a rise of 50: the level is 205.
        assert_eq!(onset(&[200.0, 204.0, 206.0, 250.0]), 2);
        assert_eq!(onset(&[3.0, 3.0, 3.0]), 0, "no rise");
        assert_eq!(onset(&[5.0, 1.0]), 0, "only a fall");
        assert_eq!(onset(&[]), 0);
        assert_eq!(
            onset(&[0.0, f64::NAN, 8.0]),
            2,
            "missing values are skipped"
        );
    }

    #[test]
    fn times_count_from_the_event() {
        // Grasp 0: frames at 0, 0.1, 0.2 s; hand totals 0, 65, 30 (onset at frame 1);
        // key frame 2.
        let s = two_sensor_session();
        let close = |a: Vec<f64>, b: [f64; 3]| {
            assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12), "{a:?}")
        };
        close(Event::FirstFrame.times(&s, 0), [0.0, 0.1, 0.2]);
        close(Event::ContactOnset.times(&s, 0), [-0.1, 0.0, 0.1]);
        close(Event::KeyFrame.times(&s, 0), [-0.2, -0.1, 0.0]);
        assert!(Event::KeyFrame.times(&s, 5).is_empty());
    }
}
