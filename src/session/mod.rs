//! Sessions: the data model, the native JSON format, importers of the real datasets,
//! the simulator of the sample sessions, and validation.

pub mod bts3;
mod error;
pub mod icub;
mod model;
pub mod native;
pub mod simulate;
mod validate;

pub use bts3::import_bts3;
pub use error::{Location, SessionError};
pub use icub::{import_icub, import_icub_with};
pub use model::*;
pub use native::{load, save};
pub use validate::validate;

/// Open a session from any supported path: an iCub dataset folder, a BTS3 `.csv`, or a
/// native session file.
pub fn open(path: &std::path::Path) -> Result<Session, SessionError> {
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
