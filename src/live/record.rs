//! A live recording: each completed grasp is added to a native session file as it ends.
//!
//! Each grasp is written by an atomic rewrite (temporary file, fsync, rename): the file on
//! disk is at every moment a complete, valid session, so a kill -9 loses at most the grasp
//! in progress and leaves nothing to repair. Each grasp is serialised once, when it ends;
//! a rewrite copies the lines already made (a few hundred kB for a session of a hundred
//! grasps), which costs milliseconds next to a grasp's seconds. An append-only journal
//! would save that copy but leave a file that is not a session until a finaliser ran,
//! which is exactly what a kill -9 prevents.

use std::path::{Path, PathBuf};

use crate::fsutil;
use crate::session::spec::{ImportSpec, OBJECT, RawGrasp, assemble};
use crate::session::{LabelSet, Session, SessionError, native};

/// A completed grasp as a session of its own: built and validated by the bag importer's
/// `assemble`, so a grasp from a stream is the grasp a recording of it would give.
pub fn grasp_session(
    spec: &ImportSpec,
    source: &Path,
    grasp: RawGrasp,
) -> Result<Session, SessionError> {
    assemble(
        spec,
        source,
        "live stream",
        "Grasps cut from a live stream.",
        vec![grasp],
    )
}

pub struct Recorder {
    path: PathBuf,
    /// The session's header: meta, sensors, encoders and label sets (objects in order of
    /// first appearance, as the importers list them); its grasps are in `lines`.
    header: Option<Session>,
    lines: Vec<String>,
    /// Per object, the trials recorded so far.
    trials: Vec<(String, u32)>,
}

impl Recorder {
    /// A recording to `path`; the file appears with the first grasp.
    pub fn new(path: &Path) -> Recorder {
        Recorder {
            path: path.to_path_buf(),
            header: None,
            lines: Vec::new(),
            trials: Vec::new(),
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn grasps(&self) -> usize {
        self.lines.len()
    }

    /// Add the grasp of a one-grasp session (from [`grasp_session`]) and rewrite the file.
    pub fn append(&mut self, one: &Session) -> Result<(), SessionError> {
        let Some(mut grasp) = one.grasps.first().cloned() else {
            return Ok(());
        };
        let header = self.header.get_or_insert_with(|| Session {
            grasps: Vec::new(),
            ..one.clone()
        });
        // The object's class in the recording: its own list grows as objects appear.
        if let (Some(mine), Some(theirs)) = (header.label_set(OBJECT), one.label_set(OBJECT)) {
            let set: &mut LabelSet = &mut header.label_sets[mine];
            let class = match set.classes.iter().position(|c| *c == grasp.object) {
                Some(c) => c,
                None => {
                    set.classes.push(grasp.object.clone());
                    set.classes.len() - 1
                }
            };
            if let Some(l) = grasp.labels.get_mut(theirs) {
                *l = class;
            }
        }
        let trial = match self.trials.iter_mut().find(|(o, _)| *o == grasp.object) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                self.trials.push((grasp.object.clone(), 1));
                1
            }
        };
        grasp.trial = Some(trial);
        self.lines.push(native::grasp_line(&grasp));
        let lines = &self.lines;
        fsutil::write_atomic_with(&self.path, |w| native::with_grasp_lines(header, lines, w))
            .map_err(|e| SessionError::io(&self.path, &e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::Frame;

    fn raw(object: &str, class: usize, n: usize) -> RawGrasp {
        RawGrasp {
            object: object.into(),
            classes: vec![class],
            frames: (0..n)
                .map(|i| Frame {
                    t: i as f64 * 0.01,
                    taxels: vec![vec![i as f64, 1.0]],
                    encoders: Vec::new(),
                })
                .collect(),
            key_frame: Some(n - 1),
            trial: None,
        }
    }

    #[test]
    fn the_recording_is_a_valid_session_after_every_grasp() {
        let dir = std::env::temp_dir().join(format!("tw-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let spec = ImportSpec::from_str(
            r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "kPa"}],
               "label_sets": [{"name": "outcome", "classes": ["ok", "slip"]}]}"#,
            &dir.join("spec.json"),
        )
        .unwrap();
        let path = dir.join("rec.json");
        let mut rec = Recorder::new(&path);
        let source = Path::new("ws://127.0.0.1:1");
        let grasps = [raw("mug", 1, 3), raw("cup", 0, 2), raw("mug", 0, 4)];
        for (i, g) in grasps.iter().enumerate() {
            rec.append(&grasp_session(&spec, source, g.clone()).unwrap())
                .unwrap();
            let back = native::load(&path).unwrap();
            assert_eq!(back.grasps.len(), i + 1);
        }
        let back = native::load(&path).unwrap();
        let objects = &back.label_sets[back.label_set(OBJECT).unwrap()].classes;
        assert_eq!(objects, &["mug", "cup"]);
        // Object, trial, labels, frames, key frame.
        type Row = (String, Option<u32>, Vec<usize>, usize, usize);
        let rows: Vec<Row> = back
            .grasps
            .iter()
            .map(|g| {
                (
                    g.object.clone(),
                    g.trial,
                    g.labels.clone(),
                    g.frames.len(),
                    g.key_frame,
                )
            })
            .collect();
        assert_eq!(
            rows,
            [
                ("mug".into(), Some(1), vec![0, 1], 3, 2),
                ("cup".into(), Some(1), vec![1, 0], 2, 1),
                ("mug".into(), Some(2), vec![0, 0], 4, 3),
            ]
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
