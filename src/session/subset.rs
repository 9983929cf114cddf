//! A session of some of another session's grasps: for train/test splits across objects,
//! trials or labels, and for researchers building their own test sets. Sensors, encoders,
//! label sets and every kept grasp are copied unchanged; the notes say what was kept.

use std::ops::RangeInclusive;

use super::Session;

/// Trial numbers as sorted, disjoint ranges: `1..100000000` is one range, never a list of
/// its numbers, and a trial is looked up by bisection.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trials(Vec<RangeInclusive<u32>>);

impl Trials {
    /// The union of `ranges` (in any order, overlapping or not).
    pub fn new(ranges: impl IntoIterator<Item = RangeInclusive<u32>>) -> Trials {
        let mut ranges: Vec<_> = ranges.into_iter().filter(|r| !r.is_empty()).collect();
        ranges.sort_by_key(|r| *r.start());
        let mut merged: Vec<RangeInclusive<u32>> = Vec::with_capacity(ranges.len());
        for r in ranges {
            match merged.last_mut() {
                Some(last) if *r.start() <= last.end().saturating_add(1) => {
                    *last = *last.start()..=(*last.end()).max(*r.end());
                }
                _ => merged.push(r),
            }
        }
        Trials(merged)
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn contains(&self, trial: u32) -> bool {
        let i = self.0.partition_point(|r| *r.end() < trial);
        self.0.get(i).is_some_and(|r| r.contains(&trial))
    }

    /// `1..10, 12` as the command line writes them.
    fn describe(&self) -> String {
        let parts: Vec<String> = self
            .0
            .iter()
            .map(|r| match r.start() == r.end() {
                true => r.start().to_string(),
                false => format!("{}..{}", r.start(), r.end()),
            })
            .collect();
        parts.join(", ")
    }
}

impl From<RangeInclusive<u32>> for Trials {
    fn from(r: RangeInclusive<u32>) -> Trials {
        Trials::new([r])
    }
}

/// Which grasps to keep: all conditions must hold (an empty list does not filter).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SubsetSpec {
    pub objects: Vec<String>,
    pub trials: Trials,
    /// (label set, class): within one label set a grasp may have any of the classes
    /// listed for it.
    pub labels: Vec<(String, String)>,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct SubsetError(String);

impl SubsetSpec {
    /// In words, for the new session's notes.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if !self.objects.is_empty() {
            parts.push(format!("objects {}", self.objects.join(", ")));
        }
        if !self.trials.is_empty() {
            parts.push(format!("trials {}", self.trials.describe()));
        }
        for (set, class) in &self.labels {
            parts.push(format!("{set} = {class}"));
        }
        if parts.is_empty() {
            "every grasp".into()
        } else {
            parts.join("; ")
        }
    }
}

/// The grasps of `session` that `spec` keeps, as a session of their own named `name`.
pub fn subset(session: &Session, spec: &SubsetSpec, name: &str) -> Result<Session, SubsetError> {
    let objects = session.objects();
    if let Some(o) = spec.objects.iter().find(|o| !objects.contains(o)) {
        return Err(SubsetError(format!(
            "no object {o:?} in {}; it has {}",
            session.meta.name,
            objects.join(", ")
        )));
    }
    if !spec.trials.is_empty() && session.grasps.iter().all(|g| g.trial.is_none()) {
        return Err(SubsetError(format!(
            "the grasps of {} carry no trial numbers",
            session.meta.name
        )));
    }
    // Per label set named, the classes allowed.
    let mut allowed: Vec<(usize, Vec<usize>)> = Vec::new();
    for (set_name, class) in &spec.labels {
        let set = session.label_set(set_name).ok_or_else(|| {
            SubsetError(format!(
                "no label set {set_name:?}; the session has {}",
                session
                    .label_sets
                    .iter()
                    .map(|l| l.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let classes = &session.label_sets[set].classes;
        let c = classes.iter().position(|c| c == class).ok_or_else(|| {
            SubsetError(format!(
                "label set {set_name:?} has no class {class:?} (classes {})",
                classes.join(", ")
            ))
        })?;
        match allowed.iter_mut().find(|(s, _)| *s == set) {
            Some((_, cs)) => cs.push(c),
            None => allowed.push((set, vec![c])),
        }
    }
    let grasps: Vec<_> = session
        .grasps
        .iter()
        .filter(|g| spec.objects.is_empty() || spec.objects.contains(&g.object))
        .filter(|g| spec.trials.is_empty() || g.trial.is_some_and(|t| spec.trials.contains(t)))
        .filter(|g| {
            allowed
                .iter()
                .all(|(set, cs)| g.labels.get(*set).is_some_and(|l| cs.contains(l)))
        })
        .cloned()
        .collect();
    if grasps.is_empty() {
        return Err(SubsetError(format!(
            "no grasp of {} has {}",
            session.meta.name,
            spec.describe()
        )));
    }
    Ok(with_grasps(session, grasps, &spec.describe(), name))
}

/// The grasps of `session` at `indices` (any order, repeats kept once), as a session of
/// their own named `name`: a selection made in the window saved as a test set.
pub fn subset_grasps(
    session: &Session,
    indices: &[usize],
    name: &str,
) -> Result<Session, SubsetError> {
    let n = session.grasps.len();
    if let Some(&g) = indices.iter().find(|&&g| g >= n) {
        return Err(SubsetError(format!(
            "no grasp {} in {}: it has {n}",
            g + 1,
            session.meta.name
        )));
    }
    let mut keep = indices.to_vec();
    keep.sort_unstable();
    keep.dedup();
    if keep.is_empty() {
        return Err(SubsetError("no grasps chosen".into()));
    }
    // One-based, as the browser numbers grasps.
    let mut listed: Vec<String> = keep.iter().take(10).map(|g| (g + 1).to_string()).collect();
    if keep.len() > 10 {
        listed.push("…".into());
    }
    let what = format!("grasps {}", listed.join(", "));
    let grasps = keep.iter().map(|&g| session.grasps[g].clone()).collect();
    Ok(with_grasps(session, grasps, &what, name))
}

/// `session` with only `grasps`, named `name`, its notes saying which (`what`).
fn with_grasps(session: &Session, grasps: Vec<super::Grasp>, what: &str, name: &str) -> Session {
    let mut meta = session.meta.clone();
    let note = format!(
        "{} of the {} grasps of {} ({what})",
        grasps.len(),
        session.grasps.len(),
        session.meta.name,
    );
    meta.notes = if meta.notes.is_empty() {
        note
    } else {
        format!("{}\n{note}", meta.notes)
    };
    meta.name = name.to_string();
    Session {
        meta,
        grasps,
        ..session.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::simulate;

    fn session() -> Session {
        simulate::object_recognition(1)
    }

    #[test]
    fn keeps_exactly_the_grasps_every_condition_allows() -> Result<(), SubsetError> {
        let s = session();
        let objects = s.objects();
        let spec = SubsetSpec {
            objects: vec![objects[0].clone(), objects[2].clone()],
            trials: Trials::new([1..=2]),
            labels: Vec::new(),
        };
        let sub = subset(&s, &spec, "part")?;
        assert_eq!(sub.meta.name, "part");
        let wanted: Vec<_> = s
            .grasps
            .iter()
            .filter(|g| g.object == objects[0] || g.object == objects[2])
            .filter(|g| matches!(g.trial, Some(1 | 2)))
            .collect();
        assert!(!wanted.is_empty() && wanted.len() < s.grasps.len());
        assert_eq!(sub.grasps.iter().collect::<Vec<_>>(), wanted);
        assert!(sub.meta.notes.contains(&format!(
            "{} of the {} grasps",
            wanted.len(),
            s.grasps.len()
        )));
        assert_eq!(sub.sensors, s.sensors);
        assert_eq!(sub.label_sets, s.label_sets);
        Ok(())
    }

    #[test]
    fn trial_ranges_stay_ranges() {
        let t = Trials::new([5..=9, 1..=1, 2..=3, 8..=u32::MAX]);
        assert_eq!(t, Trials::new([1..=3, 5..=u32::MAX]));
        assert!(t.contains(1) && t.contains(3) && !t.contains(4) && t.contains(u32::MAX));
        assert_eq!(t.describe(), format!("1..3, 5..{}", u32::MAX));
        assert!(!Trials::new([1..=100_000_000]).contains(0));
    }

    #[test]
    fn chosen_grasps_keep_their_session_order_once_each() -> Result<(), SubsetError> {
        let s = session();
        let sub = subset_grasps(&s, &[7, 2, 7], "chosen")?;
        assert_eq!(sub.meta.name, "chosen");
        assert_eq!(sub.grasps, vec![s.grasps[2].clone(), s.grasps[7].clone()]);
        assert!(sub.meta.notes.contains("grasps 3, 8"), "{}", sub.meta.notes);
        assert_eq!(sub.sensors, s.sensors);
        let past = s.grasps.len();
        let past_the_end = subset_grasps(&s, &[past], "x")
            .map(|_| ())
            .map_err(|e| e.to_string());
        assert!(matches!(past_the_end, Err(e) if e.contains(&format!("no grasp {}", past + 1))));
        assert!(subset_grasps(&s, &[], "x").is_err());
        Ok(())
    }

    #[test]
    fn unknown_names_and_empty_results_are_errors_that_name_them() {
        let s = session();
        let err = |spec: SubsetSpec| subset(&s, &spec, "x").unwrap_err().to_string();
        assert!(
            err(SubsetSpec {
                objects: vec!["teapot".into()],
                ..Default::default()
            })
            .contains("teapot")
        );
        assert!(
            err(SubsetSpec {
                labels: vec![("colour".into(), "red".into())],
                ..Default::default()
            })
            .contains("colour")
        );
        assert!(
            err(SubsetSpec {
                trials: Trials::from(99..=99),
                ..Default::default()
            })
            .contains("no grasp")
        );
    }
}
