//! Importer of a researcher's ROS 2 bag (MCAP) with an import spec: the bag's streams are
//! cut into grasps by a CSV of windows or by an event topic, and aligned on the reference
//! topic's stamps (see [`super::align`]).
//!
//! - A window is clipped to the bag's span (a note says so) and refused only when it holds
//!   no frame.
//! - The reference topic is the first sensor's. A grasp's frames are its messages whose
//!   bag time lies in the (clipped) window, both ends included; a frame's `t` is its time
//!   from the window's start.
//! - Every other topic (a sensor's or the joints') gives each frame its message nearest in
//!   time within the tolerance (the spec's `sync_tolerance_s`, default half the reference's
//!   median period): values are never interpolated, and never come from farther than the
//!   tolerance outside the window. A frame lacking a message of some topic within the
//!   tolerance is left out, and the session's notes count it.
//! - The key frame is the frame nearest to the `key` time where the windows CSV or a `key`
//!   event gives one (the earlier on a tie), else the frame of greatest total pressure.

use std::path::Path;

use super::LabelSet;
use super::align;
use super::bag::{self, Bag};
use super::error::{bag_time, read_text, shorten};
use super::long_csv::split_line;
use super::spec::{GraspCut, ImportSpec, LabelError, RawGrasp, assemble};
use super::{Frame, Session, SessionError};

/// A grasp's window in bag time (ns), where it came from, its labels and key time.
struct Window {
    start: u64,
    end: u64,
    object: String,
    classes: Vec<usize>,
    key: Option<u64>,
    /// Where an error about the window points.
    origin: Origin,
}

#[derive(Clone, Copy)]
enum Origin {
    /// A line of the windows CSV.
    Line(usize),
    /// The `start` event of the events topic, at this bag time.
    Event(u64),
}

/// Import a `.mcap` file or a ROS 2 bag folder as the spec describes.
pub fn import_bag(path: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    let Some(cut) = &spec.cut else {
        return Err(SessionError::field(
            &spec.path,
            "grasps",
            "a bag needs `grasps`: a `windows` CSV or an `events` topic",
        ));
    };
    // The windows CSV is read before the bag, so that its own errors come first and fast.
    let windows = match cut {
        GraspCut::Windows(csv) => Some((csv.as_path(), read_windows(csv, spec)?)),
        GraspCut::Events(_) => None,
    };
    let events_topic = match cut {
        GraspCut::Events(t) => Some(t.as_str()),
        GraspCut::Windows(_) => None,
    };
    let bag = bag::read(path, spec, events_topic)?;
    let Some(span) = bag.span else {
        return Err(SessionError::file(path, "the bag holds no messages"));
    };
    let (windows, windows_file) = match (windows, events_topic) {
        (Some((csv, w)), _) => {
            check_windows(&w, csv)?;
            (w, csv)
        }
        (None, Some(topic)) => (events_to_windows(&bag, path, topic, spec)?, path),
        (None, None) => unreachable!("a cut is either windows or events"),
    };
    let tolerance = spec
        .sync_tolerance_ns
        .unwrap_or_else(|| align::default_tolerance(&bag.tactile[0].stamps));
    let cut = cut_grasps(
        &bag,
        spec,
        &windows,
        windows_file,
        events_topic,
        span,
        tolerance,
    )?;
    let how = format!(
        "Frames: the messages of `{}` inside each grasp's {}; every other topic gives each \
         frame its message nearest in time within {} ms.{}",
        bag.tactile[0].topic,
        match spec.cut.as_ref() {
            Some(GraspCut::Windows(csv)) => format!("window of {}", super::file_name(csv)),
            Some(GraspCut::Events(t)) => format!("start and end events on `{t}`"),
            None => String::new(),
        },
        tolerance as f64 / 1e6,
        cut.notes(&bag),
    );
    assemble(spec, path, "ROS 2 bag", &how, cut.grasps)
}

/// Seconds of bag time, as a windows CSV writes them (`1700000000.153` or with all nine
/// decimals), as integer nanoseconds: parsed as decimal text, so no digit is lost.
fn parse_bag_time(text: &str) -> Option<u64> {
    let t = text.trim();
    let (int, frac) = t.split_once('.').unwrap_or((t, ""));
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if digits(int) && (frac.is_empty() || digits(frac)) {
        let secs: u64 = int.parse().ok()?;
        let mut ns: u64 = 0;
        for (i, b) in frac.bytes().take(9).enumerate() {
            ns += u64::from(b - b'0') * 10u64.pow(8 - i as u32);
        }
        // Round half up on the tenth decimal.
        if frac.len() > 9 && frac.as_bytes()[9] >= b'5' {
            ns += 1;
        }
        return secs.checked_mul(1_000_000_000)?.checked_add(ns);
    }
    // Scientific notation and the like: through f64 (microsecond precision at epoch times).
    let v: f64 = t.parse().ok()?;
    (0.0..1.8e10).contains(&v).then(|| (v * 1e9).round() as u64)
}

fn read_windows(csv: &Path, spec: &ImportSpec) -> Result<Vec<Window>, SessionError> {
    let text = read_text(csv)?;
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.find(|(_, l)| !l.trim().is_empty()) else {
        return Err(SessionError::file(csv, "the windows file is empty"));
    };
    let header_line = text.lines().position(|l| !l.trim().is_empty()).unwrap_or(0) + 1;
    let names = split_line(header.trim_start_matches('\u{feff}'))
        .map_err(|e| SessionError::line_caused(csv, header_line, e))?;
    let index = super::long_csv::column_index(&names)
        .map_err(|e| SessionError::line_caused(csv, header_line, e))?;
    let col = |name: &str| index.find(name);
    let need = |name: &str| {
        col(name).ok_or_else(|| {
            SessionError::line(
                csv,
                header_line,
                format!(
                    "no `{name}` column (a windows CSV has start, end, object{}, and \
                     optionally key)",
                    spec.recorded_label_sets()
                        .iter()
                        .map(|l| format!(", {}", l.name))
                        .collect::<String>()
                ),
            )
        })
    };
    let (c_start, c_end, c_object) = (need("start")?, need("end")?, need("object")?);
    let c_labels: Vec<usize> = spec
        .recorded_label_sets()
        .iter()
        .map(|l| need(&l.name))
        .collect::<Result<_, _>>()?;
    let c_key = col("key");
    let mut windows = Vec::new();
    for (i, line) in lines {
        let no = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let fields = split_line(line).map_err(|e| SessionError::line_caused(csv, no, e))?;
        if fields.len() != names.len() {
            return Err(SessionError::line(
                csv,
                no,
                format!("{} values, expected {}", fields.len(), names.len()),
            ));
        }
        let time = |c: usize| {
            parse_bag_time(&fields[c]).ok_or_else(|| {
                SessionError::line_field(
                    csv,
                    no,
                    names[c].trim(),
                    format!(
                        "`{}` is not a bag time in seconds",
                        shorten(fields[c].trim())
                    ),
                )
            })
        };
        let (start, end) = (time(c_start)?, time(c_end)?);
        if end <= start {
            return Err(SessionError::line(
                csv,
                no,
                format!(
                    "the window ends ({} s) before it starts ({} s)",
                    bag_time(end),
                    bag_time(start)
                ),
            ));
        }
        let object = fields[c_object].trim().to_string();
        spec.check_object(&object)
            .map_err(|e| SessionError::line_field_caused(csv, no, "object", e))?;
        let classes = spec
            .recorded_label_sets()
            .iter()
            .zip(&c_labels)
            .map(|(set, &c)| {
                spec.class_index(set, fields[c].trim())
                    .map_err(|e| SessionError::line_field_caused(csv, no, &set.name, e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let key = match c_key {
            Some(c) if !fields[c].trim().is_empty() => {
                let k = time(c)?;
                if !(start..=end).contains(&k) {
                    return Err(SessionError::line_field(
                        csv,
                        no,
                        "key",
                        format!("{} s is outside the window", bag_time(k)),
                    ));
                }
                Some(k)
            }
            _ => None,
        };
        windows.push(Window {
            start,
            end,
            object,
            classes,
            key,
            origin: Origin::Line(no),
        });
    }
    if windows.is_empty() {
        return Err(SessionError::file(csv, "the windows file lists no windows"));
    }
    Ok(windows)
}

/// Windows must not overlap (whether they reach into the bag is checked when cutting).
fn check_windows(windows: &[Window], csv: &Path) -> Result<(), SessionError> {
    let line = |w: &Window| match w.origin {
        Origin::Line(l) => l,
        Origin::Event(_) => 0,
    };
    let mut order: Vec<&Window> = windows.iter().collect();
    order.sort_by_key(|w| (w.start, line(w)));
    for pair in order.windows(2) {
        if pair[1].start <= pair[0].end {
            return Err(SessionError::line(
                csv,
                line(pair[1]),
                format!(
                    "the window overlaps the one of line {} (which ends at {} s)",
                    line(pair[0]),
                    bag_time(pair[0].end)
                ),
            ));
        }
    }
    Ok(())
}

/// Windows from `start:OBJECT`, `key` and `end:CLASS[,CLASS…]` events.
fn events_to_windows(
    bag: &Bag,
    path: &Path,
    topic: &str,
    spec: &ImportSpec,
) -> Result<Vec<Window>, SessionError> {
    let sets = spec.recorded_label_sets();
    let mut windows = Vec::new();
    let mut open: Option<(u64, String, Option<u64>)> = None;
    for (t, text) in &bag.events {
        let at = |m: String| SessionError::topic(path, topic, Some(*t), m);
        let refused = |e: LabelError| SessionError::topic_caused(path, topic, Some(*t), e);
        let text = text.trim();
        let (word, arg) = text.split_once(':').unwrap_or((text, ""));
        match (word.trim(), &mut open) {
            ("start", Some((s, _, _))) => {
                return Err(at(format!(
                    "a grasp starts while the one started at {} s has not ended",
                    bag_time(*s)
                )));
            }
            ("start", None) => {
                let object = arg.trim().to_string();
                spec.check_object(&object).map_err(refused)?;
                open = Some((*t, object, None));
            }
            ("key", Some((_, _, key))) => {
                if key.is_some() {
                    return Err(at("a second `key` event in one grasp".into()));
                }
                *key = Some(*t);
            }
            ("end", Some(_)) => {
                let classes = event_classes(spec, &sets, arg, text).map_err(refused)?;
                if let Some((start, object, key)) = open.take() {
                    windows.push(Window {
                        start,
                        end: *t,
                        object,
                        classes,
                        key,
                        origin: Origin::Event(start),
                    });
                }
            }
            ("key" | "end", None) => {
                return Err(at(format!("`{}` comes before any `start`", shorten(text))));
            }
            _ => {
                return Err(at(format!(
                    "`{}` is not an event: expected start:OBJECT, key or end:LABELS",
                    shorten(text)
                )));
            }
        }
    }
    if let Some((s, _, _)) = open {
        return Err(SessionError::topic(
            path,
            topic,
            Some(s),
            "the grasp started here never ends (no `end` event follows)",
        ));
    }
    if windows.is_empty() {
        return Err(SessionError::topic(
            path,
            topic,
            None,
            "the events topic marks no grasps",
        ));
    }
    Ok(windows)
}

/// The grasps cut from a bag, with what the alignment left out.
struct Cut {
    grasps: Vec<RawGrasp>,
    /// Frames left out, per topic of `Bag::tactile` then the joints (last), that lacked a
    /// message within the tolerance (a frame may lack several).
    lacking: Vec<usize>,
    left_out: usize,
    clipped: usize,
}

impl Cut {
    /// The alignment's notes for the session, empty when nothing was left out or clipped.
    fn notes(&self, bag: &Bag) -> String {
        let mut out = String::new();
        if self.left_out > 0 {
            let topics: Vec<&str> = bag
                .tactile
                .iter()
                .map(|t| t.topic.as_str())
                .chain(bag.joints.as_ref().map(|j| j.topic.as_str()))
                .collect();
            let which: Vec<String> = self
                .lacking
                .iter()
                .zip(&topics)
                .filter(|(n, _)| **n > 0)
                .map(|(n, t)| format!("`{t}` in {n}"))
                .collect();
            out += &format!(
                " {} frame{} left out for lacking a message within the tolerance ({}).",
                self.left_out,
                if self.left_out == 1 { " was" } else { "s were" },
                which.join(", ")
            );
        }
        if self.clipped > 0 {
            out += &format!(
                " {} window{} clipped to the bag's span.",
                self.clipped,
                if self.clipped == 1 { " was" } else { "s were" }
            );
        }
        out
    }
}

fn cut_grasps(
    bag: &Bag,
    spec: &ImportSpec,
    windows: &[Window],
    windows_file: &Path,
    events_topic: Option<&str>,
    span: (u64, u64),
    tolerance: u64,
) -> Result<Cut, SessionError> {
    let reference = &bag.tactile[0];
    // Which topic, and where in its rows, each sensor's values are.
    let places: Vec<(usize, std::ops::Range<usize>)> = spec
        .sensors
        .iter()
        .map(|s| {
            let topic = bag
                .tactile
                .iter()
                .position(|t| Some(&t.topic) == s.topic.as_ref())
                .unwrap_or(0);
            (topic, s.range_in_message())
        })
        .collect();
    let n_joints = spec.encoder_names().len();
    let n_topics = bag.tactile.len();
    let mut cut = Cut {
        grasps: Vec::with_capacity(windows.len()),
        lacking: vec![0; n_topics + 1],
        left_out: 0,
        clipped: 0,
    };
    let mut rows = vec![0usize; n_topics];
    for w in windows {
        let where_ = |m: String| match (w.origin, events_topic) {
            (Origin::Line(l), _) => SessionError::line(windows_file, l, m),
            (Origin::Event(t), Some(topic)) => SessionError::topic(windows_file, topic, Some(t), m),
            (Origin::Event(_), None) => SessionError::file(windows_file, m),
        };
        let (start, end) = (w.start.max(span.0), w.end.min(span.1));
        if start > end {
            return Err(where_(format!(
                "the window {}–{} s falls outside the bag, which spans {}–{} s, and holds no \
                 frame",
                bag_time(w.start),
                bag_time(w.end),
                bag_time(span.0),
                bag_time(span.1)
            )));
        }
        if (start, end) != (w.start, w.end) {
            cut.clipped += 1;
        }
        let first = reference.stamps.partition_point(|&s| s < start);
        let last = reference.stamps.partition_point(|&s| s <= end);
        let mut frames = Vec::with_capacity(last - first);
        let mut stamps = Vec::with_capacity(last - first);
        for i in first..last {
            let t = reference.stamps[i];
            // Each topic's nearest message within the tolerance; the reference's is its own.
            let mut complete = true;
            for (k, tt) in bag.tactile.iter().enumerate() {
                match if k == 0 {
                    Some(i)
                } else {
                    align::nearest(&tt.stamps, t, tolerance)
                } {
                    Some(row) => rows[k] = row,
                    None => {
                        cut.lacking[k] += 1;
                        complete = false;
                    }
                }
            }
            let joint_row = match &bag.joints {
                Some(j) => {
                    let row = align::nearest(&j.stamps, t, tolerance);
                    if row.is_none() {
                        cut.lacking[n_topics] += 1;
                        complete = false;
                    }
                    row
                }
                None => None,
            };
            if !complete {
                cut.left_out += 1;
                continue;
            }
            let taxels = places
                .iter()
                .map(|(topic, range)| bag.tactile[*topic].row(rows[*topic])[range.clone()].to_vec())
                .collect();
            let encoders = match (&bag.joints, joint_row) {
                (Some(j), Some(row)) => j.values[row * n_joints..(row + 1) * n_joints].to_vec(),
                _ => Vec::new(),
            };
            frames.push(Frame {
                t: (t - start) as f64 / 1e9,
                taxels,
                encoders,
            });
            stamps.push(t);
        }
        if frames.is_empty() {
            return Err(where_(format!(
                "the grasp {}–{} s holds no frame: no message of `{}` inside it has a message \
                 of every other topic within {} ms",
                bag_time(w.start),
                bag_time(w.end),
                reference.topic,
                tolerance as f64 / 1e6
            )));
        }
        let key_frame = w.key.map(|k| {
            // The nearest stamp; the earlier one on a tie.
            let after = stamps.partition_point(|&s| s < k).min(stamps.len() - 1);
            if after > 0 && k - stamps[after - 1] <= stamps[after].abs_diff(k) {
                after - 1
            } else {
                after
            }
        });
        cut.grasps.push(RawGrasp {
            object: w.object.clone(),
            classes: w.classes.clone(),
            frames,
            key_frame,
            trial: None,
        });
    }
    Ok(cut)
}

/// The classes of an `end` event's labels (comma-separated, one per recorded label set of
/// `sets`); an error quotes `shown`. Bags and live streams read their events alike.
pub(crate) fn event_classes(
    spec: &ImportSpec,
    sets: &[&LabelSet],
    labels: &str,
    shown: &str,
) -> Result<Vec<usize>, LabelError> {
    let values: Vec<&str> = if labels.trim().is_empty() {
        Vec::new()
    } else {
        labels.split(',').map(str::trim).collect()
    };
    if values.len() != sets.len() {
        return Err(LabelError::LabelCount {
            shown: shown.to_string(),
            given: values.len(),
            sets: sets.iter().map(|l| l.name.clone()).collect(),
        });
    }
    sets.iter()
        .zip(&values)
        .map(|(set, v)| spec.class_index(set, v))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bag_times_keep_every_nanosecond() {
        assert_eq!(
            parse_bag_time("1700000000.153000001"),
            Some(1_700_000_000_153_000_001)
        );
        assert_eq!(parse_bag_time("12.5"), Some(12_500_000_000));
        assert_eq!(parse_bag_time(" 3 "), Some(3_000_000_000));
        assert_eq!(parse_bag_time("1.0000000005"), Some(1_000_000_001));
        assert_eq!(parse_bag_time("1.5e0"), Some(1_500_000_000));
        assert_eq!(parse_bag_time("-1"), None);
        assert_eq!(parse_bag_time("soon"), None);
        assert_eq!(parse_bag_time("99999999999999999999"), None);
    }
}
