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
