//! Sessions: the data model, the native JSON format, importers of the real datasets,
//! the simulator of the sample sessions, and validation.

mod model;

pub use model::*;
