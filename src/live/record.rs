//! A live recording: each completed grasp is appended to the recording's journal as it
//! ends (`session::journal`: one line and one fsync per grasp, so writing is linear in the
//! grasps), and the recording is written from it once, atomically, when recording ends. A
//! kill -9 loses at most the grasp in progress: loading the recording afterwards finds the
//! journal of a writer that is gone and finishes it, so it opens as a normal session.

use std::path::{Path, PathBuf};

use crate::session::journal::{self, Journal};
use crate::session::spec::{ImportSpec, OBJECT, RawGrasp, assemble};
use crate::session::{LabelSet, Session, SessionError};

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
    /// The recording's label sets (objects in order of first appearance, as the importers
    /// list them); None before the first grasp.
    label_sets: Option<Vec<LabelSet>>,
    journal: Option<Journal>,
    /// Per object, the trials recorded so far.
    trials: Vec<(String, u32)>,
    grasps: usize,
}

impl Recorder {
    /// A recording to `path` (a file; the journal appears beside it with the first grasp).
    /// A folder, a device or a pipe is refused, and so is a path whose earlier recording
    /// was never finished (its journal is still there).
    pub fn new(path: &Path) -> Result<Recorder, SessionError> {
        if let Ok(meta) = std::fs::metadata(path)
            && !meta.is_file()
        {
            return Err(SessionError::file(
                path,
                "is not a file: a recording is a session file (with its journal beside it \
                 while it is written); choose a file",
            ));
        }
        journal::check_free(path)?;
        Ok(Recorder {
            path: path.to_path_buf(),
            label_sets: None,
            journal: None,
            trials: Vec::new(),
            grasps: 0,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn grasps(&self) -> usize {
        self.grasps
    }

    /// Bytes written to the journal so far: one line per grasp, nothing rewritten.
    pub fn written(&self) -> u64 {
        self.journal.as_ref().map_or(0, |j| j.written)
    }

    /// Append the grasp of a one-grasp session (from [`grasp_session`]) to the journal.
    pub fn append(&mut self, one: &Session) -> Result<(), SessionError> {
        let Some(mut grasp) = one.grasps.first().cloned() else {
            return Ok(());
        };
        if self.journal.is_none() {
            self.journal = Some(Journal::create(&self.path, one)?);
        }
        let sets = self
            .label_sets
            .get_or_insert_with(|| one.label_sets.clone());
        // The object's class in the recording: its own list grows as objects appear.
        let mine = sets.iter().position(|l| l.name == OBJECT);
        if let (Some(mine), Some(theirs)) = (mine, one.label_set(OBJECT)) {
            let set = &mut sets[mine];
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
        if let Some(j) = &mut self.journal {
            j.append(&grasp)?;
        }
        self.grasps += 1;
        Ok(())
    }

    /// Write the recording from its journal (atomically) and remove the journal; nothing
    /// to do before the first grasp.
    pub fn finish(&mut self) -> Result<(), SessionError> {
        if self.journal.take().is_none() {
            return Ok(());
        }
        journal::finalise(&self.path).map(|_| ())
    }
}

impl Drop for Recorder {
    /// A recording dropped without `finish` (an engine that panicked) is finished here;
    /// else the next load of the recording finishes it.
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::{Frame, native};

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

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("tw-record-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn spec(dir: &Path) -> ImportSpec {
        ImportSpec::from_str(
            r#"{"sensors": [{"name": "a", "topic": "/a", "layout": "grid 1x2", "unit": "kPa"}],
               "label_sets": [{"name": "outcome", "classes": ["ok", "slip"]}]}"#,
            &dir.join("spec.json"),
        )
        .unwrap()
    }

    #[test]
    fn the_recording_is_a_valid_session_after_every_grasp() {
        let dir = folder("valid");
        let spec = spec(&dir);
        let path = dir.join("rec.json");
        let mut rec = Recorder::new(&path).unwrap();
        let source = Path::new("ws://127.0.0.1:1");
        let grasps = [raw("mug", 1, 3), raw("cup", 0, 2), raw("mug", 0, 4)];
        for (i, g) in grasps.iter().enumerate() {
            rec.append(&grasp_session(&spec, source, g.clone()).unwrap())
                .unwrap();
            let back = crate::session::load(&path).unwrap();
            assert_eq!(back.grasps.len(), i + 1);
        }
        let back = crate::session::load(&path).unwrap();
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
        // Finished: the recording is a plain session file, the journal gone.
        rec.finish().unwrap();
        assert!(!journal::journal_path(&path).exists());
        assert_eq!(crate::session::load(&path).unwrap(), back);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Many grasps: each is one line appended (the bytes written are the lines', nothing
    /// is rewritten), and the finished recording holds them all.
    #[test]
    fn many_grasps_are_appended_once_each() {
        let dir = folder("many");
        let spec = spec(&dir);
        let path = dir.join("rec.json");
        let mut rec = Recorder::new(&path).unwrap();
        let source = Path::new("ws://127.0.0.1:1");
        let objects = ["mug", "cup", "ball", "box"];
        let mut lines = 0;
        for i in 0..400 {
            let one = grasp_session(&spec, source, raw(objects[i % 4], i % 2, 2 + i % 5)).unwrap();
            let before = rec.written();
            rec.append(&one).unwrap();
            if i == 0 {
                // The header and the first grasp.
                lines = rec.written();
                continue;
            }
            let mut g = one.grasps[0].clone();
            g.labels[one.label_set(OBJECT).unwrap()] = i % 4;
            g.trial = Some((i / 4 + 1) as u32);
            let line = native::grasp_line(&g).len() as u64 + 1;
            assert_eq!(rec.written() - before, line, "grasp {i}");
            lines += line;
        }
        assert_eq!(rec.written(), lines);
        assert_eq!(crate::session::load(&path).unwrap().grasps.len(), 400);
        rec.finish().unwrap();
        let back = crate::session::load(&path).unwrap();
        assert_eq!(back.grasps.len(), 400);
        assert_eq!(back.grasps[399].trial, Some(100));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A writer killed mid-grasp: the journal's cut last line is left out, the journal is
    /// finished when the recording is loaded, and a new recording there is refused until
    /// then.
    #[test]
    fn a_killed_writers_journal_is_finished_at_load() {
        let dir = folder("killed");
        let spec = spec(&dir);
        let path = dir.join("rec.json");
        let mut rec = Recorder::new(&path).unwrap();
        let source = Path::new("ws://127.0.0.1:1");
        for g in [raw("mug", 1, 3), raw("cup", 0, 2)] {
            rec.append(&grasp_session(&spec, source, g).unwrap())
                .unwrap();
        }
        // What a kill -9 leaves: no finish, a line half written, a writer that is gone.
        std::mem::forget(rec);
        let jpath = journal::journal_path(&path);
        let text = std::fs::read_to_string(&jpath).unwrap();
        let pid = std::process::id().to_string();
        let gone = text.replacen(&format!("\"pid\":{pid}"), "\"pid\":4294967295", 1);
        assert_ne!(gone, text);
        std::fs::write(&jpath, format!("{gone}{{\"object\":\"mu")).unwrap();
        assert!(!path.exists());
        let err = Recorder::new(&path).err().unwrap().to_string();
        assert!(err.contains("unfinished recording"), "{err}");
        let back = crate::session::open(&path).unwrap();
        assert_eq!(back.grasps.len(), 2);
        assert!(!jpath.exists() && path.is_file());
        assert_eq!(crate::session::load(&path).unwrap(), back);
        assert!(Recorder::new(&path).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
