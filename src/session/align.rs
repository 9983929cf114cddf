//! Time alignment of a bag's topics, as robotics tools synchronise them (ROS
//! `message_filters`' approximate-time policy, bag players' nearest lookups): the reference
//! topic's messages are the frames, and every other topic contributes to a frame its
//! message nearest in time, if it lies within a tolerance.
//!
//! Two publishers never stamp together: a joint state 1 ms after a tactile frame belongs to
//! that frame, not to the next one. Holding the latest earlier message instead gives the
//! first frame of a grasp a value from before the grasp; the nearest message within the
//! tolerance cannot come from farther than the tolerance outside the grasp's window, since
//! every frame lies inside it.

/// The default tolerance: half the reference topic's median period (ns), so that a topic at
/// the reference's rate, however offset, contributes each of its messages to one frame.
/// Zero when the reference has fewer than two messages (only equal stamps then match).
pub fn default_tolerance(reference: &[u64]) -> u64 {
    let mut periods: Vec<u64> = reference
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .collect();
    if periods.is_empty() {
        return 0;
    }
    let mid = periods.len() / 2;
    let (_, median, _) = periods.select_nth_unstable(mid);
    *median / 2
}

/// The index of the stamp nearest to `t` within `tolerance` (the earlier on a tie), in
/// `stamps` sorted ascending.
pub fn nearest(stamps: &[u64], t: u64, tolerance: u64) -> Option<usize> {
    let after = stamps.partition_point(|&s| s < t);
    let before = after.checked_sub(1).map(|i| (i, t - stamps[i]));
    let at_or_after = stamps.get(after).map(|&s| (after, s - t));
    let best = match (before, at_or_after) {
        (Some(b), Some(a)) => Some(if b.1 <= a.1 { b } else { a }),
        (b, a) => b.or(a),
    };
    best.filter(|&(_, d)| d <= tolerance).map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn tolerance_is_half_the_median_period() {
        // 10 ms frames with one 50 ms gap: the gap does not move the median.
        let r = [0, 10, 20, 30, 80, 90, 100].map(|k| k * MS);
        assert_eq!(default_tolerance(&r), 5 * MS);
        assert_eq!(default_tolerance(&[7]), 0);
        assert_eq!(default_tolerance(&[]), 0);
    }

    /// Frames every 10 ms; a topic stamped 1 ms after (or before) each frame gives each frame
    /// its own message, never its neighbour's.
    #[test]
    fn offsets_of_one_ms_either_way_pick_the_frames_own_message() {
        let frames: Vec<u64> = (0..20).map(|k| 1000 * MS + k * 10 * MS).collect();
        let tol = default_tolerance(&frames);
        for offset in [MS as i64, -(MS as i64)] {
            let other: Vec<u64> = frames.iter().map(|&t| (t as i64 + offset) as u64).collect();
            for (k, &t) in frames.iter().enumerate() {
                assert_eq!(
                    nearest(&other, t, tol),
                    Some(k),
                    "offset {offset}, frame {k}"
                );
            }
        }
    }

    /// A topic at half the rate, stamped 2 ms after every other frame: the frames with a
    /// message 2 ms away get it; those 8 ms from both neighbours (beyond 5 ms) get none.
    #[test]
    fn a_topic_at_half_the_rate_fills_only_the_frames_it_reaches() {
        let frames: Vec<u64> = (0..10).map(|k| k * 10 * MS).collect();
        let half: Vec<u64> = (0..5).map(|k| k * 20 * MS + 2 * MS).collect();
        let tol = default_tolerance(&frames);
        for (k, &t) in frames.iter().enumerate() {
            let want = (k % 2 == 0).then_some(k / 2);
            assert_eq!(nearest(&half, t, tol), want, "frame {k}");
        }
        // With a tolerance of a whole reference period, every frame has a message: the odd
        // ones take the earlier (8 ms before), not the later (12 ms after).
        for (k, &t) in frames.iter().enumerate() {
            assert_eq!(nearest(&half, t, 10 * MS), Some(k / 2), "frame {k}");
        }
    }

    /// A topic that stops after 50 ms: later frames find no message within the tolerance,
    /// rather than holding the last one.
    #[test]
    fn a_topic_that_stops_leaves_later_frames_without_a_message() {
        let frames: Vec<u64> = (0..10).map(|k| k * 10 * MS).collect();
        let stops: Vec<u64> = (0..6).map(|k| k * 10 * MS + MS).collect();
        let tol = default_tolerance(&frames);
        let got: Vec<Option<usize>> = frames.iter().map(|&t| nearest(&stops, t, tol)).collect();
        let want: Vec<Option<usize>> = (0..10).map(|k| (k < 6).then_some(k)).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn ties_take_the_earlier_message() {
        assert_eq!(nearest(&[8, 12], 10, 5), Some(0));
        assert_eq!(nearest(&[8, 12], 10, 1), None);
        assert_eq!(nearest(&[], 10, 5), None);
        assert_eq!(nearest(&[10], 10, 0), Some(0));
    }
}
