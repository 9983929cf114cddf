//! Sessions: the data model, the native JSON format, importers of the real datasets and of
//! researchers' own recordings (ROS 2 bags, long-format CSVs, described by an import spec),
//! the simulator of the sample sessions, and validation.

pub mod align;
pub mod bag;
pub mod bts3;
pub mod cdr;
mod error;
pub mod icub;
pub mod journal;
pub mod long_csv;
mod model;
pub mod native;
pub mod ros2;
pub mod simulate;
pub mod spec;
pub mod subset;
pub mod trial_folder;
pub mod trial_pattern;
mod validate;

pub use bts3::import_bts3;
pub use error::{Location, SessionError};
pub(crate) use error::{bag_time, shorten};
pub use icub::{import_icub, import_icub_with};
pub use model::*;
pub use native::save;

/// The label set every imported session has: the grasped object.
pub const OBJECT: &str = "object";

/// Read a native session file. A live recording still journalled (being written, or its
/// writer killed) is read from its journal ([`journal`]).
pub fn load(path: &std::path::Path) -> Result<Session, SessionError> {
    if let Some(recording) = journal::open_unfinished(path) {
        return recording;
    }
    native::load(path)
}
pub use spec::ImportSpec;
pub use subset::{SubsetError, SubsetSpec, Trials, subset, subset_grasps};
pub use validate::validate;

/// Import a researcher's own recording as its import spec describes: a `.mcap` file or a
/// ROS 2 bag folder (one with `metadata.yaml`), a long-format `.csv`, or any other folder
/// as a folder of trial files.
pub fn import_with_spec(
    path: &std::path::Path,
    spec_path: &std::path::Path,
) -> Result<Session, SessionError> {
    let spec = ImportSpec::load(spec_path)?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if path.is_dir() && !path.join("metadata.yaml").is_file() {
        trial_folder::import_trial_folder(path, &spec)
    } else if path.is_dir() || ext.eq_ignore_ascii_case("mcap") {
        ros2::import_bag(path, &spec)
    } else if ext.eq_ignore_ascii_case("csv") {
        long_csv::import_long_csv(path, &spec)
    } else {
        Err(SessionError::file(
            path,
            "expected a .mcap file, a ROS 2 bag folder, a long-format .csv or a folder of trial \
             files",
        ))
    }
}

/// The last component of `path` as text, for a session's metadata: where a session came
/// from without a machine's absolute path.
pub fn file_name(path: &std::path::Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    name.or_else(|| {
        let abs = std::fs::canonicalize(path).ok()?;
        abs.file_name().map(|n| n.to_string_lossy().into_owned())
    })
    .unwrap_or_else(|| "an unnamed file".into())
}

/// The file name without its extension (a folder's name as is).
pub fn file_stem(path: &std::path::Path) -> String {
    match path.file_stem() {
        Some(stem) => stem.to_string_lossy().into_owned(),
        None => file_name(path),
    }
}

/// Whether `path` is a recording that only an import spec can describe — a `.mcap` file,
/// a ROS 2 bag folder, a folder of trial files, or a `.csv` that is not a BTS3 file — so
/// that opening it needs
/// [`import_with_spec`] (the workbench then asks for the spec).
pub fn needs_spec(path: &std::path::Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if path.is_dir() {
        return path.join("metadata.yaml").is_file() || trial_folder::holds_trial_files(path);
    }
    if ext.eq_ignore_ascii_case("mcap") {
        return true;
    }
    if ext.eq_ignore_ascii_case("csv") {
        use std::io::BufRead;
        let mut first = String::new();
        let read = std::fs::File::open(path)
            .map(std::io::BufReader::new)
            .and_then(|mut r| r.read_line(&mut first));
        let first = first.trim_start_matches('\u{feff}');
        return read.is_ok() && !first.trim().is_empty() && !first.starts_with("object,slipped,");
    }
    false
}

/// Open a session from any supported path: an iCub dataset folder, a BTS3 `.csv`, or a
/// native session file. A recording that needs an import spec ([`needs_spec`]) is an
/// error saying so.
pub fn open(path: &std::path::Path) -> Result<Session, SessionError> {
    if needs_spec(path) {
        return Err(SessionError::file(
            path,
            "a recording of your own (ROS 2 bag, long-format CSV or folder of trial files): \
             import it with an import spec (`import mcap|csv … --spec SPEC.json`, docs/import.md)",
        ));
    }
    if path.is_dir() {
        import_icub(path)
    } else if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        import_bts3(path)
    } else {
        load(path)
    }
}
