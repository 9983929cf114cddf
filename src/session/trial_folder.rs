//! Importer of a folder of trial files, the layout many public tactile data sets ship in:
//! one CSV per grasp (rows are frames, columns named as in the long CSV and read by its
//! row parser), the grasp's object, classes and trial number taken from the file's path
//! below the folder by the spec's trial pattern (see `trial_pattern`; by default one folder
//! per label, `<object>/<class>/….csv`).
//!
//! Trial files are the `.csv` files in the folder and its subfolders; hidden entries (names
//! starting with `.`) and links to folders are passed over, other files (a README, the spec)
//! ignored. Every trial file must match the pattern. Files are read one at a time, in
//! natural order of their paths (`trial-2` before `trial-10`).

use std::cmp::Ordering;
use std::path::{Path, PathBuf};

use super::error::{read_text, shorten};
use super::long_csv::{FrameColumns, GraspRows, Table, row_fields, table};
use super::spec::{ImportSpec, LabelError, OBJECT, RawGrasp, assemble};
use super::trial_pattern::TRIAL;
use super::{Frame, Session, SessionError};

/// One trial file's frames.
pub struct Trial {
    pub frames: Vec<Frame>,
    /// The frame whose `key` is 1, if one is.
    pub key_frame: Option<usize>,
}

/// A trial file and its path below the folder, `/`-separated.
pub struct TrialFile {
    pub path: PathBuf,
    pub relative: String,
}

/// How deep [`holds_trial_files`] looks: the folder and two levels of subfolders.
const PEEK_DEPTH: usize = 3;

/// Parse one trial file's text (`path` names it in errors): a header naming the spec's
/// taxel and joint columns (and optionally `time` and `key`), then one row per frame. A
/// frame's `t` is its `time` from the first row's; without a `time` column, the row's
/// index over the spec's `frame_rate_hz`.
pub fn parse_trial(text: &str, path: &Path, spec: &ImportSpec) -> Result<Trial, SessionError> {
    let Table {
        header_line: header_no,
        names,
        rows,
    } = table(text, path)?;
    let cols = FrameColumns::find(&names, spec)
        .map_err(|e| SessionError::line_caused(path, header_no, e))?;
    let period = match (cols.time, spec.frame_rate_hz) {
        (Some(_), _) => 0.0,
        (None, Some(hz)) => 1.0 / hz,
        (None, None) => {
            return Err(SessionError::line(
                path,
                header_no,
                "no `time` column, and the spec has no `frame_rate_hz` to time the rows by",
            ));
        }
    };
    let mut grasp = GraspRows::default();
    for (i, (no, line)) in rows.enumerate() {
        let fields = row_fields(path, no, line, names.len())?;
        let row = cols.read(path, no, &names, &fields, spec)?;
        let time = row.time.unwrap_or(i as f64 * period);
        grasp.push(path, no, "the file", time, row)?;
    }
    if grasp.frames.is_empty() {
        return Err(SessionError::file(
            path,
            "the file has a header but no rows",
        ));
    }
    Ok(Trial {
        frames: grasp.frames,
        key_frame: grasp.key_frame,
    })
}

/// Compare paths as people number files: runs of digits by their value, so `trial-2`
/// comes before `trial-10`.
fn natural_order(a: &str, b: &str) -> Ordering {
    let run = |s: &str| {
        let digits = s.starts_with(|c: char| c.is_ascii_digit());
        let end = s
            .find(|c: char| c.is_ascii_digit() != digits)
            .unwrap_or(s.len());
        (digits, end)
    };
    let (mut a, mut b) = (a, b);
    while !a.is_empty() && !b.is_empty() {
        let ((da, ea), (db, eb)) = (run(a), run(b));
        let (ra, rb) = (&a[..ea], &b[..eb]);
        let order = if da && db {
            let (na, nb) = (ra.trim_start_matches('0'), rb.trim_start_matches('0'));
            na.len()
                .cmp(&nb.len())
                .then_with(|| na.cmp(nb))
                .then_with(|| ra.len().cmp(&rb.len()))
        } else {
            ra.cmp(rb)
        };
        if order != Ordering::Equal {
            return order;
        }
        a = &a[ea..];
        b = &b[eb..];
    }
    a.len().cmp(&b.len())
}

/// Walk `dir` to `depth` levels (1: its own files), adding its `.csv` files below `prefix`;
/// stops once `limit` files are found.
fn walk(
    dir: &Path,
    prefix: &str,
    depth: usize,
    limit: usize,
    out: &mut Vec<TrialFile>,
) -> Result<(), SessionError> {
    let entries = std::fs::read_dir(dir).map_err(|e| SessionError::io(dir, e))?;
    for entry in entries {
        if out.len() >= limit {
            return Ok(());
        }
        let entry = entry.map_err(|e| SessionError::io(dir, e))?;
        let path = entry.path();
        let name = entry.file_name();
        let Some(name) = name.to_str() else {
            return Err(SessionError::file(
                &path,
                "the name is not UTF-8 text, so no trial pattern can match it",
            ));
        };
        if name.starts_with('.') {
            continue;
        }
        let kind = entry.file_type().map_err(|e| SessionError::io(&path, e))?;
        let relative = format!("{prefix}{name}");
        if kind.is_dir() {
            if depth > 1 {
                walk(&path, &format!("{relative}/"), depth - 1, limit, out)?;
            }
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
            // A link to a file counts; a link to a folder is not followed.
            && std::fs::metadata(&path).is_ok_and(|m| m.is_file())
        {
            out.push(TrialFile { path, relative });
        }
    }
    Ok(())
}

/// The trial files of a folder, in natural order of their paths.
pub fn trial_files(dir: &Path) -> Result<Vec<TrialFile>, SessionError> {
    if !dir.is_dir() {
        return Err(SessionError::file(dir, "not a folder of trial files"));
    }
    let mut files = Vec::new();
    walk(dir, "", usize::MAX, usize::MAX, &mut files)?;
    files.sort_by(|a, b| natural_order(&a.relative, &b.relative));
    Ok(files)
}

/// Whether `dir` looks like a folder of trial files: a `.csv` in it or in its subfolders
/// (two levels down; the bundled datasets' folders hold none).
pub fn holds_trial_files(dir: &Path) -> bool {
    let mut found = Vec::new();
    walk(dir, "", PEEK_DEPTH, 1, &mut found).is_ok() && !found.is_empty()
}

/// Import a folder of trial files as the spec describes.
pub fn import_trial_folder(dir: &Path, spec: &ImportSpec) -> Result<Session, SessionError> {
    let pattern = spec.trial_pattern()?;
    let files = trial_files(dir)?;
    if files.is_empty() {
        return Err(SessionError::file(
            dir,
            "the folder holds no trial files (`.csv` files, in it or its subfolders; a ROS 2 \
             bag folder has a metadata.yaml)",
        ));
    }
    let sets = spec.recorded_label_sets();
    let mut grasps = Vec::with_capacity(files.len());
    // Each numbered trial's object, number and file, to refuse a number given twice.
    let mut numbered: Vec<(String, u32, &Path)> = Vec::new();
    for f in &files {
        let from_path =
            |m: String| SessionError::file(&f.path, format!("from its path `{}`: {m}", f.relative));
        let refused = |e: LabelError| from_path(e.to_string()).with_source(e);
        let captures = pattern.captures(&f.relative).ok_or_else(|| {
            from_path(format!(
                "does not match the spec's trial pattern `{}`",
                pattern.as_str()
            ))
        })?;
        // The spec made sure that the pattern captures the object and every label set.
        let value = |name: &str| {
            captures
                .iter()
                .find(|(n, _)| *n == name)
                .map_or("", |(_, v)| *v)
        };
        let object = value(OBJECT);
        spec.check_object(object).map_err(refused)?;
        let classes = sets
            .iter()
            .map(|set| spec.class_index(set, value(&set.name)).map_err(refused))
            .collect::<Result<Vec<_>, _>>()?;
        let trial = match captures.iter().find(|(n, _)| *n == TRIAL) {
            None => None,
            Some((_, digits)) => {
                let n: u32 = digits.parse().map_err(|_| {
                    from_path(format!(
                        "trial number {} is too large (at most {})",
                        shorten(digits),
                        u32::MAX
                    ))
                })?;
                if let Some((_, _, other)) =
                    numbered.iter().find(|(o, t, _)| o == object && *t == n)
                {
                    return Err(from_path(format!(
                        "trial {n} of `{}` again: {} is that trial too",
                        shorten(object),
                        other.display()
                    )));
                }
                numbered.push((object.to_string(), n, &f.path));
                Some(n)
            }
        };
        let t = parse_trial(&read_text(&f.path)?, &f.path, spec)?;
        grasps.push(RawGrasp {
            object: object.to_string(),
            classes,
            frames: t.frames,
            key_frame: t.key_frame,
            trial,
        });
    }
    let how = format!(
        "One CSV file per grasp, its labels from its path (`{}`); a frame's time is from the \
         file's first row.",
        pattern.as_str()
    );
    assemble(spec, dir, "folder of trial files", &how, grasps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_compares_numbers_by_value() {
        let mut names = vec![
            "cup/trial-10.csv",
            "cup/trial-2.csv",
            "cup/trial-02.csv",
            "box/trial-1.csv",
            "cup/trial-1.csv",
            "cup/trial.csv",
        ];
        names.sort_by(|a, b| natural_order(a, b));
        assert_eq!(
            names,
            [
                "box/trial-1.csv",
                "cup/trial-1.csv",
                "cup/trial-2.csv",
                "cup/trial-02.csv",
                "cup/trial-10.csv",
                "cup/trial.csv",
            ]
        );
    }
}
